"""Speed of a 5 s clutch step with the full actuator and driveline against a stiff scipy baseline.

Prints the wall time per run (7 rounds in which they take turns: 10 engine runs in a row,
then one run of each scipy variant; median per turn, then over the rounds; after JIT
warm-up; the engine at its default rtol 1e-8, which is at least as accurate as the
baseline, and at the baseline's rtol 1e-6) of the engine on the ``clutch`` configuration
(DC step 0.2 -> 1 V at 1 s, 85 C, output every 1 ms) and of ``benchmarks/scipy_actuator.py``
(solve_ivp, BDF, rtol 1e-6) on the same equations: with the energy and oil-volume
bookkeeping the engine carries (the target's baseline), without it (a lighter model), and
with LSODA (automatic Adams/BDF switching) for comparison. Then the speed ratios, the
agreement of the two (pressure samples, torque onset, energy terms and balance) and each
one's pressure error against a tight reference on which both agree.
Targets: engine < 20 ms and >= 100x faster than the stiff baseline.
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


def main() -> None:
    rn = clutch.build(wc.Params(), Step(1.0, 0.2, 1.0), temp_C=85.0)
    # the engine at its default rtol 1e-8 is about as accurate as the baseline at rtol 1e-6 (with an
    # absolute tolerance 1e-9 of each state's scale); the errors against a tight reference follow below
    times, res = interleaved_times({
        "engine": (lambda: integrate(rn.network, 5.0, dt_out=1e-3), 10),
        "loose": (lambda: integrate(rn.network, 5.0, dt_out=1e-3, rtol=1e-6), 10),
        "scipy": (lambda: actuator_step_scipy(5.0, rtol=1e-6), 1),
        "light": (lambda: actuator_step_scipy(5.0, rtol=1e-6, bookkeeping=False), 1),
        "lsoda": (lambda: actuator_step_scipy(5.0, method="LSODA", rtol=1e-6), 1),
    }, 7)
    (t_eng, tr), (t_loose, tr_loose), (t_sp, sp) = ((times[k], res[k]) for k in ("engine", "loose", "scipy"))
    p_eng = tr.x[:, rn.i_pressure]
    onset = tr.t[np.argmax(np.abs(tr.clutch_torque("clutch")) > 0.2)]
    print(f"machine: {os.cpu_count()} cores")
    print(f"engine  clutch step 5 s (actuator + driveline)  {t_eng * 1e3:8.2f} ms/run   (target < 20 ms)  {tr.stats}")
    print(f"engine  the same at rtol 1e-6 (less accurate)   {t_loose * 1e3:8.2f} ms/run   {tr_loose.stats}")
    print(f"scipy   solve_ivp BDF, same equations           {t_sp * 1e3:8.1f} ms/run")
    print(f"scipy   BDF without the energy/volume states    {times['light'] * 1e3:8.1f} ms/run")
    print(f"scipy   LSODA (Adams/BDF switching), same eqs   {times['lsoda'] * 1e3:8.1f} ms/run")
    print(f"speed ratio at equal accuracy                   {t_sp / t_eng:8.0f} x      (target >= 100 x)")
    print(f"speed ratio at equal rtol 1e-6                  {t_sp / t_loose:8.0f} x")
    print(f"speed ratio against BDF without the bookkeeping {times['light'] / t_eng:8.0f} x")
    print(f"speed ratio against LSODA                       {times['lsoda'] / t_eng:8.0f} x")
    for ts in (1.2, 1.5, 3.0, 5.0):
        pe = np.interp(ts, tr_loose.t, tr_loose.x[:, rn.i_pressure])
        ps = np.interp(ts, sp["t"], sp["p_clutch"])
        pl = np.interp(ts, tr.t, p_eng)
        print(f"p_clutch at {ts:3.1f} s: engine {pl / 1e5:8.4f} bar (rtol 1e-6: {pe / 1e5:8.4f}), scipy {ps / 1e5:8.4f} bar")
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
    for name, t, p in (("engine rtol 1e-8", tr.t, p_eng), ("engine rtol 1e-6", tr_loose.t, tr_loose.x[:, rn.i_pressure]),
                       ("scipy  rtol 1e-6", sp["t"], sp["p_clutch"])):
        err = np.abs(np.interp(ref.t, t, p) - p_ref)
        print(f"pressure error of {name} against it: largest {err.max():7.1f} Pa, rms {np.sqrt(np.mean(err**2)):7.2f} Pa, "
              f"median {np.median(err):6.2f} Pa")


if __name__ == "__main__":
    main()
