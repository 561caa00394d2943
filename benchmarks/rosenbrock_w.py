"""Would a stiff method take a launch with fewer evaluations? A Rosenbrock-W step against the engine's, per sample.

Not a timing. One verification launch of the default design on the built-in rig (100 N m, 85 C, to 1.45 s after
the request) runs with its per-sample loop in Python. At every 1 ms controller sample in which the engine located
no event, the sample is integrated a second time from the same state and modes (after the same restart for the
new valve input) by ROS34PW2 (Rang and Angermann 2005, BIT 45: a 4-stage Rosenbrock-W method of order 3 with an
embedded order-2 solution), with the modes held, at the engine's tolerances and error norm:

* ``W diagonal``: the stiff part taken implicitly is the diagonal of the two fastest modes, the valve stem's speed
  (``-d/m`` while the stem slides) and the coil current (``-(R + k_amp)/L`` regulating, ``-R/L`` saturated,
  ``-(R + R_fw)/L`` freewheeling); W-methods keep their order for any such approximation of the Jacobian, and the
  linear solve is a division;
* ``W = I``: the same stages with nothing implicit, an explicit method of order 3.

Printed per phase: the steps, rejected steps and right-hand-side evaluations per sample of each method (the
engine's counted as seven a step attempt, its stages and a restart's), the states that bound the Rosenbrock
steps, and how far the end states lie from the engine's in units of the error weight (``atol + rtol |x|``: the
largest over the states, its median over the samples).

Usage: ``python benchmarks/rosenbrock_w.py`` (a few seconds)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from stiffness import TEMP, run_watched, state_names

from wetclutch.params import Params
from wetclutch.physics import actuator
from wetclutch.plant import clutch
from wetclutch.sim import integrator
from wetclutch.sim.rhs import rhs_call
from wetclutch.sim.workspace import FS_AMP, FS_T, IS_EVENTS, IS_REJECTED, IS_SETTLE, IS_STEPS, SETTLE_INPUT, Workspace

#: ROS34PW2 in Hairer's form: (I - gamma h W) k_i = h f(y + sum a_ij k_j) + h W sum g_ij k_j; y1 = y + sum b_i k_i
GAMMA = 4.3586652150845900e-01
A = np.array([[0.0, 0.0, 0.0, 0.0],
              [8.7173304301691801e-01, 0.0, 0.0, 0.0],
              [8.4457060015369423e-01, -1.1299064236397981e-01, 0.0, 0.0],
              [0.0, 0.0, 1.0, 0.0]])
G = np.array([[0.0, 0.0, 0.0, 0.0],
              [-8.7173304301691801e-01, 0.0, 0.0, 0.0],
              [-9.0338057013044082e-01, 5.4180672388095326e-02, 0.0, 0.0],
              [2.4212380706095346e-01, -1.2232505839045147e+00, 5.4526025533510214e-01, 0.0]])
B = np.array([2.4212380706095346e-01, -1.2232505839045147e+00, 1.5452602553351023e+00, 4.3586652150845900e-01])
B_HAT = np.array([3.7810903145819369e-01, -9.6042292212423178e-02, 0.5, 2.1793326075422950e-01])
C = A.sum(axis=1)
#: the engine's right-hand-side evaluations per step attempt: six stages, and the restarts' first stages
ENGINE_EVALS = 7


def stiff_diagonal(params: Params, ws: Workspace, net, stem: int, brake: int, implicit: bool) -> np.ndarray:
    """The diagonal Jacobian that the W-method takes implicitly (zero where ``implicit`` is False)."""
    d = np.zeros(ws.x.size)
    if not implicit:
        return d
    v = params.valve
    if abs(ws.clm[brake]) == 1:  # the stem slides: its speed has the damper's rate
        d[stem] = -v.d_stem / v.m_stem
    mode = ws.fstate[FS_AMP]
    r = v.R_coil + (v.amp_gain if mode == actuator.REGULATE else 0.0 if mode == actuator.SATURATED else v.R_freewheel)
    d[int(net.act[actuator.STATE]) + actuator.CURRENT] = -r / v.L_coil
    return d


def w_sample(ws: Workspace, net, ext, t0: float, t1: float, rtol: float, atol: np.ndarray, h: float,
             diag: np.ndarray, worst: np.ndarray) -> tuple[int, int, float]:
    """ROS34PW2 from ``t0`` to ``t1`` on the workspace's state, its modes held: (steps, rejected, next step)."""
    n = ws.x.size
    dx, aux = np.zeros(n), ws.aux.copy()
    steps = rejected = 0
    t = t0
    while t < t1 - 1e-15:
        hh = min(h, t1 - t)
        y0 = ws.x.copy()
        winv = 1.0 / (1.0 - GAMMA * hh * diag)
        k = np.zeros((4, n))
        for i in range(4):
            rhs_call(t + C[i] * hh, y0 + A[i, :i] @ k[:i], net, ext, ws, dx, aux, False, True)
            k[i] = (hh * dx + hh * diag * (G[i, :i] @ k[:i])) * winv
        y1 = y0 + B @ k
        e = ((B - B_HAT) @ k) / (atol + rtol * np.maximum(np.abs(y0), np.abs(y1)))
        err = float(np.sqrt(np.mean(e * e)))
        worst[int(np.argmax(np.abs(e)))] += 1
        fac = min(5.0, max(0.2, 0.9 * max(err, 1e-10) ** (-1.0 / 3.0)))
        if err > 1.0:
            rejected += 1
            h = hh * fac
            continue
        steps += 1
        ws.x[:] = y1
        integrator._play_on(ws, net)  # the magnet's magnetisation moved on to the step's end, as the engine does
        t += hh
        h = hh * fac if hh == h else max(h, hh * fac)
    return steps, rejected, h


def main() -> None:
    params = Params()
    names, _ = state_names(params)
    stem = names.index(f"speed {clutch.STEM}")
    rn = clutch.build(params, 0.0, config="clutch", temp_C=TEMP)
    brake = [c.name for c in rn.network.clutches].index("stem_friction")
    rows: list[tuple] = []
    worst = {True: np.zeros(64, int), False: np.zeros(64, int)}
    h_next = {True: 1e-4, False: 1e-4}

    def watched(advance, net, ext, ws, t_stop, dt, t_out0, rtol, atol, *rest):
        start, ext0 = Workspace(*[a.copy() for a in ws]), ext.copy()
        before = (ws.istate[IS_STEPS], ws.istate[IS_REJECTED], ws.istate[IS_EVENTS])
        status = advance(net, ext, ws, t_stop, dt, t_out0, rtol, atol, *rest)
        t0 = start.fstate[FS_T]
        if ws.istate[IS_EVENTS] == before[2] and t0 > 0.05 and start.istate[IS_SETTLE] == SETTLE_INPUT:
            figures = [t0, ws.istate[IS_STEPS] - before[0], ws.istate[IS_REJECTED] - before[1]]
            for implicit in (True, False):
                w = Workspace(*[a.copy() for a in start])
                integrator._restart_input(w, net, ext0)
                s, r, h_next[implicit] = w_sample(w, net, ext0, t0, t_stop, rtol, atol, h_next[implicit],
                                                  stiff_diagonal(params, w, net, stem, brake, implicit),
                                                  worst[implicit])
                dev = np.abs(w.x - ws.x) / (atol + rtol * np.abs(ws.x))
                figures += [s, r, float(dev.max())]
            rows.append(tuple(figures))
        return status

    cond = run_watched(watched)
    a = np.array(rows)
    print("per 1 ms sample without events: steps / rejected / right-hand-side evaluations (the median over the "
          "samples of the end state's largest distance from the engine's, in error weights)")
    for label, sel in (("standby", a[:, 0] < cond.t_request), ("slip phase", a[:, 0] > cond.t_request + 0.05)):
        b = a[sel]
        line = f"  {label:10s} {sel.sum():4d} samples | DOPRI5 (engine) {b[:, 1].mean():.2f} / {b[:, 2].mean():.2f} / " \
               f"{ENGINE_EVALS * (b[:, 1] + b[:, 2]).mean():.1f}"
        for col, name in ((3, "W diagonal"), (6, "W = I")):
            line += f" | {name} {b[:, col].mean():.2f} / {b[:, col + 1].mean():.2f} / " \
                    f"{4 * (b[:, col] + b[:, col + 1]).mean():.1f} ({np.median(b[:, col + 2]):.1f})"
        print(line)
    for implicit, name in ((True, "W diagonal"), (False, "W = I")):
        top = np.argsort(-worst[implicit])[:3]
        print(f"  {name}: the largest share of the step's error estimate: "
              + ", ".join(f"{names[i]} {worst[implicit][i]}" for i in top if worst[implicit][i]))


if __name__ == "__main__":
    main()
