"""Compile time of the numerical core on a cold cache (a fresh machine's first run).

Runs, in a fresh interpreter with ``NUMBA_CACHE_DIR`` pointing at an empty temporary
directory, what a first ``wetclutch launch`` does: one closed-loop launch (engine, actuator,
controller, sensor chain), then a 5 s clutch step through ``integrate``; and prints the wall
time of each, which is almost all numba compilation. A second fresh interpreter on the now
warm cache shows what loading the cached machine code costs.
Target: the cold first run under 60 s.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time

_FIRST_RUN = """
import time
t0 = time.perf_counter()
import wetclutch as wc
from wetclutch.launch import loop, metrics
from wetclutch.plant import clutch
from wetclutch.sim.network import integrate
from wetclutch.sim.signals import Step
t1 = time.perf_counter()
loop.simulate(wc.Params(), "launch", loop.Conditions(t_ref=100.0, oil_temp_C=85.0), nominal=metrics.Response.empty())
t2 = time.perf_counter()
integrate(clutch.build(wc.Params(), Step(1.0, 0.2, 1.0), temp_C=85.0).network, 5.0)
t3 = time.perf_counter()
print(f"{t1 - t0:.3f} {t2 - t1:.3f} {t3 - t2:.3f}")
"""


def _run(cache: str) -> tuple[float, float, float, float]:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", _FIRST_RUN], env=env, check=True, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    imp, launch, step = (float(v) for v in out.stdout.split())
    return wall, imp, launch, step


def main() -> None:
    with tempfile.TemporaryDirectory() as cache:
        cold = _run(cache)
        warm = _run(cache)
    print(f"machine: {os.cpu_count()} cores")
    for name, (wall, imp, launch, step) in (("cold cache", cold), ("warm cache", warm)):
        print(f"{name}: first run {wall:6.1f} s  (import {imp:5.1f} s, first launch {launch:6.1f} s, "
              f"first clutch step {step:5.1f} s)")
    print(f"target: cold first run < 60 s: {'met' if cold[0] < 60.0 else 'not met'}")


if __name__ == "__main__":
    main()
