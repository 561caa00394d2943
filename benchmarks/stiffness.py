"""What sets the step of a closed-loop launch: the plant's fastest modes and the steps the engine takes.

Not a timing. One launch of the default design on the built-in rig (100 N m, 85 C, to 1.45 s after the
request, as verification runs it) is run with its per-sample loop in Python, so that the state can be
read at chosen times; at each, the Jacobian of the engine's right-hand side (the modes as decided there)
is formed by finite differences and its fastest eigenvalues are printed with the states that carry them,
beside the real-axis stability bound of the engine's explicit Dormand-Prince step (``h |lambda| <= 3.3``).
Then the steps, rejected steps and located events per 1 ms controller sample, in the standby and in the
slip phase, and after a jump of the valve input (the torque dither's edges) against the other samples.

Usage: ``python benchmarks/stiffness.py``
"""

from __future__ import annotations

import numpy as np

from wetclutch.launch import design, metrics, verify
from wetclutch.launch import loop as launch
from wetclutch.params import Params
from wetclutch.physics import actuator
from wetclutch.plant import clutch
from wetclutch.sim.rhs import rhs_call
from wetclutch.sim.signals import External
from wetclutch.sim.workspace import IS_EVENTS, IS_REJECTED, IS_STEPS

#: DOPRI5's stability region reaches -3.3 on the negative real axis
DOPRI5_REAL_BOUND = 3.3
SNAPSHOTS = (0.5, 1.1, 1.3, 1.6, 2.0, 2.4)  # s: standby, early slip, slip
T_REF, TEMP = 100.0, 85.0


def state_names(params: Params) -> tuple[list[str], np.ndarray]:
    """The launch network's state vector, named (speeds, deflections, energy accumulators, actuator states), and
    its absolute tolerances in a launch."""
    rn = clutch.build(params, External(0), config="clutch", temp_C=TEMP)
    net = rn.network
    names = [f"speed {b.name}" for b in net.bodies] + [f"deflection {s.name}" for s in net.springs]
    names += [f"energy {c.name}" for c in net.clutches] + [f"energy {e}" for e in ("drag", "damper", "gear", "source")]
    assert len(names) == net.actuator_state, "the state layout has changed: name its energy accumulators anew"
    act = {actuator.CURRENT: "coil current I", actuator.PRESSURE: "clutch pressure p", actuator.VOLUME_IN: "oil in",
           actuator.VOLUME_OUT: "oil out", actuator.MAGNETISATION: "magnetisation I_m"}
    names += [act[i] for i in range(actuator.N_STATES)]
    return names + [f"state {i}" for i in range(len(names), net.n_state)], rn.atol(launch.ATOL)


def jacobian(t: float, x: np.ndarray, net, ext, ws) -> np.ndarray:
    """Finite-difference Jacobian of the right-hand side at ``(t, x)`` for the workspace's modes."""
    n = x.size
    f0, aux = np.zeros(n), ws.aux.copy()
    rhs_call(t, x.copy(), net, ext, ws, f0, aux, True, True)
    jac = np.zeros((n, n))
    for i in range(n):
        e = 1e-6 * max(abs(x[i]), 1e-6)
        xp = x.copy()
        xp[i] += e
        f = np.zeros(n)
        rhs_call(t, xp, net, ext, ws, f, aux, True, True)
        jac[:, i] = (f - f0) / e
    return jac


def run_watched(watch) -> launch.Conditions:
    """Run the verification launch (:data:`T_REF`, :data:`TEMP`) of the default design on the built-in rig with its
    per-sample loop in Python, ``watch(advance, net, ext, ws, t_stop, *args)`` called for each sample in place of the
    engine's ``advance``; returns the launch's conditions."""
    advance, compiled = launch.advance, launch._closed_loop
    launch.advance = lambda *args: watch(advance, *args)
    launch._closed_loop = compiled.py_func  # the per-sample loop in Python, the engine compiled
    try:
        cond = launch.Conditions(t_ref=T_REF, oil_temp_C=TEMP, t_max=launch.Conditions().t_request + verify.HORIZON)
        launch.simulate(Params(), design.cached(Params()), cond, nominal=metrics.Response.empty())
    finally:
        launch.advance, launch._closed_loop = advance, compiled
    return cond


def main() -> None:
    names, atol = state_names(Params())
    per_sample: list[tuple[float, int, int, int, float]] = []

    def watched(advance, net, ext, ws, t_stop, *args):
        before = (ws.istate[IS_STEPS], ws.istate[IS_REJECTED], ws.istate[IS_EVENTS])
        status = advance(net, ext, ws, t_stop, *args)
        per_sample.append((t_stop, ws.istate[IS_STEPS] - before[0], ws.istate[IS_REJECTED] - before[1],
                           ws.istate[IS_EVENTS] - before[2], ext[0]))
        if any(abs(t_stop - s) < 1e-9 for s in SNAPSHOTS):
            jac = jacobian(t_stop, ws.x, net, ext, ws)
            lam, vec = np.linalg.eig(jac)
            order = np.argsort(-np.abs(lam))[:3]
            i_p = int(net.act[actuator.STATE]) + actuator.PRESSURE
            print(f"t = {t_stop:.2f} s  fastest modes (1/s); the clutch pressure's own rate, d(dp/dt)/dp = "
                  f"{jac[i_p, i_p]:.3g} 1/s:")
            # the states that carry a mode, each in the units of the engine's error weight (atol + rtol |x|)
            weight = atol + launch.RTOL * np.abs(ws.x)
            for k in order:
                v = np.abs(vec[:, k]) / weight
                share = v / v.max()
                carriers = ", ".join(names[i] for i in np.argsort(-share)[:2] if share[i] > 0.05)
                print(f"    {lam[k].real:10.3g} {lam[k].imag:+9.3g}j  ({carriers}); explicit step <= "
                      f"{DOPRI5_REAL_BOUND / abs(lam[k]) * 1e3:.3f} ms")
        return status

    cond = run_watched(watched)
    a = np.array(per_sample)
    t_req = cond.t_request
    print("\nper 1 ms sample: accepted steps, rejected steps, located events")
    for label, sel in (("standby", a[:, 0] <= t_req), ("slip phase", a[:, 0] > t_req + 0.05)):
        print(f"  {label:32s} {a[sel, 1].mean():5.2f} {a[sel, 2].mean():5.2f} {a[sel, 3].mean():5.2f}")
    jump = np.r_[False, np.abs(np.diff(a[:, 4])) > 0.05]
    for label, sel in (("after an input jump > 0.05 V", jump), ("other samples", ~jump)):
        print(f"  {label:32s} {a[sel, 1].mean():5.2f} {a[sel, 2].mean():5.2f} {a[sel, 3].mean():5.2f}")
    print(f"  whole launch: {int(a[:, 1].sum())} steps, {int(a[:, 2].sum())} rejected, {int(a[:, 3].sum())} events")


if __name__ == "__main__":
    main()
