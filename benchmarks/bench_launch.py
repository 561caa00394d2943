"""Speed of closed-loop launches and of a 1,000-launch verification.

1. One launch (default rig, 85 C, 100 N m step, 1 kHz controller with the sensor
   chain, run through synchronisation): the compiled loop
   (``launch._closed_loop``) against the same loop run as Python
   (``_closed_loop.py_func``: the same compiled engine and controller, but the
   per-sample work - sensor filters, controller call, integrator call - in
   Python), measured in the same run.
2. ``verify.run`` of the design on its plant over the shipped ranges (1,000 random
   samples + the corners) on all cores, wall time including the worker start and the
   nominal launches: as verification runs (each launch to ``verify.HORIZON`` after the
   request, which decides every requirement) and with every launch run to lock-up
   (``through_lockup``), in the same run; the pass rates must be equal.
   Target: 1,000 verification launches in under 30 s on this 2-core machine.
3. Where a launch's time goes: one launch as verification runs it (to ``verify.HORIZON``
   after the request), the design as shipped against the same design with its input
   dither switched off, timed in turns, with the integrator's steps, rejected steps and
   events. Each dither edge is a step of the valve input that the coil current follows
   with its 0.5 ms time constant, and the stem's stick/slip and the magnet's play follow it.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import interleaved_times, median_time  # noqa: E402

from wetclutch.launch import loop as launch  # noqa: E402
from wetclutch.launch import design, metrics, verify  # noqa: E402
from wetclutch.params import Params  # noqa: E402


def one_launch() -> launch.LaunchResult:
    return launch.simulate(Params(), "launch", launch.Conditions(t_ref=100.0, oil_temp_C=85.0),
                           nominal=metrics.Response.empty())


def main() -> None:
    t_c, res = median_time(one_launch, 20)
    compiled = launch._closed_loop
    launch._closed_loop = compiled.py_func  # the same loop, per-sample work in Python
    try:
        t_py, res_py = median_time(one_launch, 2)
    finally:
        launch._closed_loop = compiled
    same = abs(res_py.summary["t95_s"] - res.summary["t95_s"]) < 1e-12
    print(f"machine: {os.cpu_count()} cores")
    print(f"one launch, compiled loop       {t_c * 1e3:8.1f} ms  ({len(res.signals)} samples, t_sync {res.summary['t_sync_s']:.2f} s)")
    print(f"one launch, loop in Python      {t_py * 1e3:8.1f} ms  (same result: {same})")
    print(f"speed ratio                     {t_py / t_c:8.1f} x")
    runs = {}
    for whole in (True, False):
        t0 = time.perf_counter()
        out = verify.run(design.cached(Params()), n=1000, seed=0, progress=False, through_lockup=whole)
        runs[whole] = (time.perf_counter() - t0, out)
    (w_whole, o_whole), (w, out) = runs[True], runs[False]
    print(f"verify, launches to lock-up: {o_whole['cases']} launches on {os.cpu_count()} workers  {w_whole:6.1f} s  "
          f"pass rate {100 * o_whole['pass_rate']:.1f} %")
    print(f"verify: {out['cases']} launches on {os.cpu_count()} workers  {w:6.1f} s  (target < 30 s for 1000)  "
          f"pass rate {100 * out['pass_rate']:.1f} %  ({w_whole / w:.2f}x faster than to lock-up, same verdicts: "
          f"{[r['requirements'] for r in out['results']] == [r['requirements'] for r in o_whole['results']]})")

    plant, d = Params(), design.cached(Params())
    cond = launch.Conditions(t_ref=100.0, oil_temp_C=85.0, t_max=launch.Conditions().t_request + verify.HORIZON)
    plain = design.with_settings(d, dither_amp=0.0, dither_amp_torque=0.0)
    cases = {name: (lambda c=c: launch.simulate(plant, c, cond, nominal=metrics.Response.empty()), 5)
             for name, c in (("as designed", d), ("without dither", plain))}
    times, last = interleaved_times(cases, 5)
    for name in cases:
        st = last[name].stats
        print(f"one launch to {cond.t_max:.2f} s, {name:15s} {times[name] * 1e3:7.1f} ms  steps {st['steps']}, rejected "
              f"{st['rejected']}, events {st['events']}")
    print(f"the dither's share of a launch's time: {1 - times['without dither'] / times['as designed']:.0%}")


if __name__ == "__main__":
    main()
