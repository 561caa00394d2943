"""Speed of a 5 s clutch step with the full actuator and driveline against a stiff scipy baseline.

Prints the wall time per run (7 rounds in which they take turns: 10 engine runs in a row,
then one run of each scipy variant; median per turn, then over the rounds; after JIT
warm-up) of the engine on the ``clutch`` configuration (DC step 0.2 -> 1 V at 1 s, 85 C,
output every 1 ms) at the relative tolerances :data:`RTOLS`, and of
``benchmarks/scipy_actuator.py`` (solve_ivp, BDF, rtol 1e-6) on the same equations: with the
energy and oil-volume bookkeeping the engine carries (the target's baseline), without it (a
lighter model), and with LSODA (automatic Adams/BDF switching) for comparison. Then the
agreement of the two (pressure samples, torque onset, energy terms and balance), each one's
pressure error against a tight reference on which both agree, and the speed ratios: at equal
accuracy, the engine at the loosest of :data:`RTOLS` whose largest and rms errors are both at
most the baseline's, and at the engine's default rtol 1e-8. Then the same at every accuracy BDF reaches with its
tolerance tightened (:data:`SCIPY_RTOLS`, timed in the same turns): a ratio at one accuracy alone could be an
accident of where the two methods' error curves happen to cross.
Targets: engine < 20 ms and >= 200x faster than the stiff baseline at equal accuracy.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import interleaved_times
from scipy_actuator import E_CL, ENERGY_TERMS, V_IN, Rig, actuator_step_scipy, energy_residual

import wetclutch as wc
from wetclutch.plant import clutch
from wetclutch.sim.network import integrate
from wetclutch.sim.signals import Step


#: the engine's relative tolerances timed (its default first)
RTOLS = (1e-8, 3e-8, 1e-7, 3e-7, 1e-6, 1e-9, 1e-10)
#: BDF's relative tolerances timed for the comparison at several accuracies (the baseline's 1e-6 first)
SCIPY_RTOLS = (1e-6, 3e-7, 1e-7, 3e-8)


def _name(rtol: float) -> str:
    return f"engine rtol {rtol:g}"


def _bdf(rtol: float) -> str:
    return "scipy" if rtol == SCIPY_RTOLS[0] else f"BDF rtol {rtol:g}"


def _equal(errors: dict[str, tuple[float, float, float]], baseline: str) -> float | None:
    """The loosest engine tolerance whose largest and rms errors are both at most ``baseline``'s (None if none)."""
    ok = [r for r in RTOLS if errors[_name(r)][0] <= errors[baseline][0] and errors[_name(r)][1] <= errors[baseline][1]]
    return max(ok) if ok else None


def _errors(t: np.ndarray, p: np.ndarray, t_ref: np.ndarray, p_ref: np.ndarray) -> tuple[float, float, float]:
    """Largest, rms and median pressure error (Pa) of ``p`` against the reference on its grid."""
    err = np.abs(np.interp(t_ref, t, p) - p_ref)
    return float(err.max()), float(np.sqrt(np.mean(err**2))), float(np.median(err))


def main() -> None:
    rn = clutch.build(wc.Params(), Step(1.0, 0.2, 1.0), temp_C=85.0)
    times, res = interleaved_times({
        **{_name(r): (lambda r=r: integrate(rn.network, 5.0, dt_out=1e-3, rtol=r), 10) for r in RTOLS},
        "scipy": (lambda: actuator_step_scipy(5.0, rtol=1e-6), 1),
        **{_bdf(r): (lambda r=r: actuator_step_scipy(5.0, rtol=r), 1) for r in SCIPY_RTOLS[1:]},
        "light": (lambda: actuator_step_scipy(5.0, rtol=1e-6, bookkeeping=False), 1),
        "lsoda": (lambda: actuator_step_scipy(5.0, method="LSODA", rtol=1e-6), 1),
    }, 7)
    t_sp, sp = times["scipy"], res["scipy"]
    tr = res[_name(RTOLS[0])]
    onset = tr.t[np.argmax(np.abs(tr.clutch_torque("clutch")) > 0.2)]
    print(f"machine: {os.cpu_count()} cores")
    for r in RTOLS:
        print(f"engine  clutch step 5 s, rtol {r:<5g}              {times[_name(r)] * 1e3:8.2f} ms/run   "
              f"{res[_name(r)].stats}")
    print(f"scipy   solve_ivp BDF, same equations           {t_sp * 1e3:8.1f} ms/run")
    print(f"scipy   BDF without the energy/volume states    {times['light'] * 1e3:8.1f} ms/run")
    print(f"scipy   LSODA (Adams/BDF switching), same eqs   {times['lsoda'] * 1e3:8.1f} ms/run")
    for ts in (1.2, 1.5, 3.0, 5.0):
        pl = np.interp(ts, tr.t, tr.x[:, rn.i_pressure])
        ps = np.interp(ts, sp["t"], sp["p_clutch"])
        print(f"p_clutch at {ts:3.1f} s: engine {pl / 1e5:8.4f} bar, scipy {ps / 1e5:8.4f} bar")
    print(f"torque onset: engine {onset:.4f} s (first 1 ms sample), scipy {sp['onset_time']:.4f} s (event)")
    e_eng = tr.energies()
    e_sp = dict(zip(ENERGY_TERMS, sp["y_end"][E_CL:V_IN], strict=True))
    dev = max(abs(e_sp[k] / e_eng[k][-1] - 1.0) for k in e_sp)
    print(f"energy terms at 5 s: largest relative difference {dev:.1e}; energy balance closes to "
          f"{tr.energy_residual():.1e} (engine), {energy_residual(Rig(), sp['y']):.1e} (scipy) of the stored energy")
    # accuracy against a tight reference that both methods agree on (engine rtol 1e-12, scipy rtol 1e-9)
    ref = integrate(rn.network, 5.0, dt_out=1e-3, rtol=1e-12, atol=1e-14)
    p_ref = ref.x[:, rn.i_pressure]
    sp_ref = actuator_step_scipy(5.0, rtol=1e-9)
    print(f"reference: engine rtol 1e-12 vs scipy rtol 1e-9, largest pressure difference "
          f"{np.abs(np.interp(ref.t, sp_ref['t'], sp_ref['p_clutch']) - p_ref).max():.2f} Pa")
    errors = {_name(r): _errors(res[_name(r)].t, res[_name(r)].x[:, rn.i_pressure], ref.t, p_ref) for r in RTOLS}
    for r in SCIPY_RTOLS:
        errors[_bdf(r)] = _errors(res[_bdf(r)]["t"], res[_bdf(r)]["p_clutch"], ref.t, p_ref)
    for name, (largest, rms, median) in errors.items():
        label = name if name != "scipy" else "scipy BDF rtol 1e-6"
        print(f"pressure error of {label:20s} against it: largest {largest:7.2f} Pa, rms {rms:7.3f} Pa, "
              f"median {median:6.3f} Pa")
    # equal accuracy: the loosest engine tolerance whose largest and rms errors are both within the baseline's
    eq = _equal(errors, "scipy")
    if eq is not None:
        print(f"speed ratio at equal accuracy (engine rtol {eq:g})   {t_sp / times[_name(eq)]:8.0f} x      "
              f"(target >= 200 x)")
    else:
        print("speed ratio at equal accuracy: no engine tolerance tried is as accurate as the baseline")
    print("at each accuracy BDF reaches (its tolerance tightened), the engine's loosest tolerance as accurate:")
    for r in SCIPY_RTOLS:
        eq_r = _equal(errors, _bdf(r))
        largest, rms, _ = errors[_bdf(r)]
        head = f"  BDF rtol {r:<5g} {times[_bdf(r)] * 1e3:7.1f} ms (largest {largest:5.2f} Pa, rms {rms:6.3f} Pa): "
        print(head + (f"engine rtol {eq_r:<5g} {times[_name(eq_r)] * 1e3:5.2f} ms, "
                      f"{times[_bdf(r)] / times[_name(eq_r)]:5.0f} x" if eq_r is not None
                      else "no engine tolerance tried is as accurate"))
    t_eng = times[_name(RTOLS[0])]
    print(f"speed ratio at the engine's default rtol {RTOLS[0]:g}   {t_sp / t_eng:8.0f} x")
    print(f"speed ratio against BDF without the bookkeeping {times['light'] / t_eng:8.0f} x (engine rtol {RTOLS[0]:g})")
    print(f"speed ratio against LSODA                       {times['lsoda'] / t_eng:8.0f} x (engine rtol {RTOLS[0]:g})")


if __name__ == "__main__":
    main()
