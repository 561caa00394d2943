"""Where a closed-loop launch's time goes: the engine's sections timed from inside.

Not a timing of the engine as shipped. The package is copied to a temporary directory with timers (the
monotonic clock read through ctypes, some 20 ns a reading) between the sections of the integrator's step
loop and of the closed loop's sample. The verification launch of ``stiffness.py`` (100 N m, 85 C, to 1.45 s
after the request) then runs four times in a fresh process on that copy, and the last run's time is printed
per section with the number of times each ran, beside the launch's steps, event-function evaluations and
golden-section searches for a slip's dip. The timers add some 10-20 % to the launch: read the sections'
shares. The copy compiles without numba's cache (its clock is a ctypes pointer): about 1-2 minutes.

Usage: ``python benchmarks/launch_profile.py``
"""

from __future__ import annotations

import argparse
import ast
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import wetclutch

#: the sections, in the order of their slots in the copy's timer table
SECTIONS = ("advance, whole call", "sensors and controller", "restart for the sample's input",
            "six stages (right-hand sides)", "error estimate, event functions", "locating events", "output rows",
            "dense state at an event", "modes re-decided at an event", "accepted step: next step, copies",
            "time events", "step limit, loop")
#: slots of the timer table (rows of the copy's event log after its own) for the counters
DIP_SEARCHES, EVALUATIONS, FULL_EVALUATIONS = 20, 22, 23
ROWS = 40

_CLOCK = f'''

import ctypes as _ct

_clock = _ct.CDLL("libc.so.6").clock_gettime
_clock.argtypes = [_ct.c_int, _ct.c_void_p]
_clock.restype = _ct.c_int


@njit(_nrt=False, inline="always")
def tnow(ws):
    """The monotonic clock (ns), read into the two spare slots at the end of ``ws.istate``."""
    n = ws.istate.shape[0]
    buf = ws.istate[n - 2:]
    _clock(1, buf.ctypes)
    return float(buf[0]) * 1e9 + float(buf[1])


@njit(_nrt=False, inline="always")
def tick(ws, k, t0):
    """Add the time since ``t0`` to section ``k`` and count it; the time now."""
    t = tnow(ws)
    m = ws.evlog.shape[0] - {ROWS} + k
    ws.evlog[m, 0] += t - t0
    ws.evlog[m, 1] += 1.0
    return t


@njit(_nrt=False, inline="always")
def count(ws, k):
    """Count one more of counter ``k``."""
    ws.evlog[ws.evlog.shape[0] - {ROWS} + k, 1] += 1.0
'''

#: (file, text, replacement) of the instrumentation, each text found exactly once
_PATCHES = (
    ("sim/workspace.py", "evlog=np.zeros((EVENT_LOG, 3)),", f"evlog=np.zeros((EVENT_LOG + {ROWS}, 3)),"),
    ("sim/workspace.py", "istate = np.zeros(N_ISTATE, dtype=np.int64)",
     "istate = np.zeros(N_ISTATE + 2, dtype=np.int64)"),
    ("sim/integrator.py", "from .compiled import jit, jit_inline",
     "from .compiled import count, jit, jit_inline, tick, tnow"),
    ("sim/integrator.py", "            if n < ws.evlog.shape[0]:", f"            if n < ws.evlog.shape[0] - {ROWS}:"),
    ("sim/integrator.py", "    if ws.istate[IS_SETTLE] == SETTLE_INPUT:\n",
     "    tp = tnow(ws)\n    if ws.istate[IS_SETTLE] == SETTLE_INPUT:\n"),
    ("sim/integrator.py", "    while t < t_stop:\n", "    tp = tick(ws, 2, tp)\n    while t < t_stop:\n"),
    ("sim/integrator.py", "        copy(y_old, ws.x)\n", "        tp = tick(ws, 11, tp)\n        copy(y_old, ws.x)\n"),
    ("sim/integrator.py", "        err = error_norm(", "        tp = tick(ws, 3, tp)\n        err = error_norm("),
    ("sim/integrator.py", "            ws.istate[IS_REJECTED] += 1\n            continue",
     "            ws.istate[IS_REJECTED] += 1\n            tp = tick(ws, 4, tp)\n            continue"),
    ("sim/integrator.py", "        t_ev, e_ev = _locate_event(t, t_new, h, y_old, ws, net, ext)\n",
     ("        tp = tick(ws, 4, tp)\n        t_ev, e_ev = _locate_event(t, t_new, h, y_old, ws, net, ext)\n"
      "        tp = tick(ws, 5, tp)\n")),
    ("sim/integrator.py", "                   out_t, out_x, out_aux, out_mode)\n        if t_ev != np.inf:\n",
     "                   out_t, out_x, out_aux, out_mode)\n        tp = tick(ws, 6, tp)\n        if t_ev != np.inf:\n"),
    ("sim/integrator.py", "            direction = ws.fstate[FS_PLAY_DIR]\n",
     "            direction = ws.fstate[FS_PLAY_DIR]\n            tp = tick(ws, 7, tp)\n"),
    ("sim/integrator.py", "                ws.istate[IS_TURNS] += 1\n            continue",
     "                ws.istate[IS_TURNS] += 1\n            tp = tick(ws, 8, tp)\n            continue"),
    ("sim/integrator.py", "        if at_lim and (hit_bp or hit_pwm):\n            bp_i, after_edge, ok = _time_event(",
     ("        tp = tick(ws, 9, tp)\n        if at_lim and (hit_bp or hit_pwm):\n"
      "            bp_i, after_edge, ok = _time_event(")),
    ("sim/integrator.py", ("                return ERR_SINGULAR\n        else:\n            copy(ws.K[0], ws.K[6])\n"
                           "            copy(ws.g_old, ws.g_new)\n            copy(ws.aux, ws.aux_new)\n"),
     ("                return ERR_SINGULAR\n            tp = tick(ws, 10, tp)\n        else:\n"
      "            copy(ws.K[0], ws.K[6])\n            copy(ws.g_old, ws.g_new)\n            copy(ws.aux, ws.aux_new)\n"
      "            tp = tick(ws, 9, tp)\n")),
    ("sim/integrator.py", "    # the last grid point, when it falls on t_stop",
     "    tp = tick(ws, 11, tp)\n    # the last grid point, when it falls on t_stop"),
    ("sim/integrator.py", "        gm = _event_value(e, tm, t, h, y_old, ws, net, ext)\n",
     (f"        count(ws, {EVALUATIONS})\n        if _sliding(e, ws, net) < 0:\n"
      f"            count(ws, {FULL_EVALUATIONS})\n"
      "        gm = _event_value(e, tm, t, h, y_old, ws, net, ext)\n")),
    ("sim/integrator.py",
     "    # golden-section search for the least slip on the dense output (its slip is smooth within the step)\n",
     f"    count(ws, {DIP_SEARCHES})\n"),
    ("launch/loop.py", "from ..sim.integrator import",
     "from ..sim.compiled import tick, tnow\nfrom ..sim.integrator import"),
    ("launch/loop.py", "        _true_values(net, ws.x, probe, temp, truth)\n",
     "        tq = tnow(ws)\n        _true_values(net, ws.x, probe, temp, truth)\n"),
    ("launch/loop.py",
     ("        status = advance(net, ext, ws, (k + 1) * dt, dt, 0.0, rtol, atol, np.inf, out_t, out_x, out_aux, "
      "out_mode)\n"),
     ("        tq = tick(ws, 1, tq)\n        status = advance(net, ext, ws, (k + 1) * dt, dt, 0.0, rtol, atol, np.inf, "
      "out_t, out_x, out_aux, out_mode)\n        tq = tick(ws, 0, tq)\n")),
)

_DRIVER = f'''
from wetclutch.launch import design, metrics, verify
from wetclutch.launch import loop as launch
from wetclutch.params import Params

kept = {{}}
new_workspace = launch.new_workspace


def keep(*args, **kwargs):
    kept["ws"] = new_workspace(*args, **kwargs)
    return kept["ws"]


launch.new_workspace = keep
cond = launch.Conditions(t_ref=100.0, oil_temp_C=85.0, t_max=launch.Conditions().t_request + verify.HORIZON)
for _ in range(4):
    res = launch.simulate(Params(), design.cached(Params()), cond, nominal=metrics.Response.empty())
print(repr((kept["ws"].evlog[-{ROWS}:, :2].tolist(), res.stats)))
'''


def _instrumented(dst: Path) -> None:
    """A copy of the package in ``dst`` with the timers in it."""
    src = Path(wetclutch.__file__).resolve().parent
    pkg = dst / "wetclutch"
    shutil.copytree(src, pkg, ignore=shutil.ignore_patterns("__pycache__"))
    compiled = pkg / "sim" / "compiled.py"
    compiled.write_text(compiled.read_text() + _CLOCK)
    for name, old, new in _PATCHES:
        path = pkg / name
        text = path.read_text()
        if text.count(old) != 1:
            sys.exit(f"launch_profile: the engine has changed: '{old.strip()[:60]}' is not once in {name}")
        path.write_text(text.replace(old, new))


def main() -> None:
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()  # no options: refuse any
    with tempfile.TemporaryDirectory() as tmp:
        _instrumented(Path(tmp))
        env = {**os.environ, "PYTHONPATH": tmp, "NUMBA_CACHE_DIR": str(Path(tmp) / "cache")}
        out = subprocess.run([sys.executable, "-W", "ignore", "-c", _DRIVER], env=env, capture_output=True, text=True,
                             check=False)
    if out.returncode != 0:
        sys.exit(out.stderr.strip().splitlines()[-1])
    table, stats = ast.literal_eval(out.stdout.strip().splitlines()[-1])
    whole = table[0][0] + table[1][0]
    print(f"one verification launch: {stats['steps']} steps, {stats['rejected']} rejected, {stats['events']} events, "
           f"{stats['mode_switches']} mode changes; {whole / 1e6:.2f} ms in its samples (shares of that)")
    print(f"{'section':36s} {'ms':>7s} {'share':>6s} {'times':>7s} {'ns each':>8s}")
    for k, name in enumerate(SECTIONS):
        ns, n = table[k]
        print(f"{name:36s} {ns / 1e6:7.2f} {100 * ns / whole:5.1f}% {int(n):7d} {ns / max(n, 1):8.0f}")
    print(f"event-function evaluations while locating: {int(table[EVALUATIONS][1])}, of them a whole right-hand "
           f"side (not a sliding clutch's slip): {int(table[FULL_EVALUATIONS][1])}; golden-section searches for a "
           f"slip's dip: {int(table[DIP_SEARCHES][1])}")


if __name__ == "__main__":
    main()
