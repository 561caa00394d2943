"""A first run on a cold numba cache compiles the core on two processes.

Almost all of a fresh machine's first run is numba compiling the integrator, and numba
compiles one function after another on one core. The integrator (:func:`~wetclutch.sim.
integrator.advance`, with the right-hand side inlined into its stages) and the compiled copy
of the right-hand side that its restarts, located events and output rows call
(:func:`~wetclutch.sim.rhs.rhs_call`) are the two largest pieces, and the first needs the
second only when its type inference reaches a call to it, after it has spent some ten seconds
inlining its stages. So when :func:`begin` finds no cached ``rhs_call``, it starts a second
Python process that compiles ``rhs_call`` into the cache (``python -m wetclutch.sim.coldstart``),
then the integrator's event location, PWM edge and mode log and what the layers above
:func:`register` (the closed loop's controller), and holds this process's own compilation of
``rhs_call`` until the second process reports it done; then it loads the cached one. The results
are those of a serial compile (each function compiled once).

Where no second interpreter can be started (``sys.executable`` is not Python, as inside a
simulation tool that embeds it), or the second process fails or has not reported within
:data:`WAIT` seconds, this process compiles ``rhs_call`` itself, as it would without this module.
"""

from __future__ import annotations

import importlib
import os
import pickle
import select
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numba

from .integrator import _log_modes, _pwm_edge, _root
from .rhs import rhs_call

#: seconds to wait for the second process's ``rhs_call`` (it takes some 20 s on 2 cores)
WAIT = 300.0
_started = False
_REGISTERED: list[Callable[[Any, Any, Any], list[tuple[str, str, tuple]]]] = []


def job(fn, *args) -> tuple[str, str, tuple]:
    """A compile job for the second process: the compiled function ``fn`` (by module and name) for the types of
    ``args``."""
    return fn.py_func.__module__, fn.py_func.__name__, tuple(numba.typeof(v) for v in args)


def _core_jobs(net, ext, ws) -> list[tuple[str, str, tuple]]:
    """``rhs_call`` first, then the integrator's other helpers that call it, on these records."""
    return [job(rhs_call, 0.0, ws.x, net, ext, ws, ws.dx, ws.aux, False, True),
            job(_root, 0, 1.0, 0.0, -1.0, 2.0, 0.0, 1.0, ws.y_old, ws, net, ext),
            job(_pwm_edge, 0.0, ws, net, ext),
            job(_log_modes, 0.0, ws.clm_before, ws)]


def cold() -> bool:
    """True if the numba cache holds no compiled ``rhs_call`` (a first run)."""
    try:
        index = Path(rhs_call._cache._cache_file._index_path)
    except AttributeError:  # a numba whose cache is laid out otherwise: behave as without this module
        return False
    return not index.exists()


def _python() -> bool:
    return Path(sys.executable).name.lower().startswith("python")


def register(jobs: Callable[[Any, Any, Any], list[tuple[str, str, tuple]]]) -> None:
    """Have the second process also compile what ``jobs(net, ext, ws)`` lists (:func:`job`): a layer above the
    core names its compiled functions that run beside the integrator (a closed loop's controller)."""
    _REGISTERED.append(jobs)


def begin(net, ext, ws) -> None:
    """Before the first compile of the integrator in this process (on the records ``net``, ``ext``, ``ws``): on a
    cold cache, compile ``rhs_call`` on a second process meanwhile, then the integrator's other callers of it and
    the :func:`register`-ed jobs. Nothing on a warm cache, or after the first call."""
    global _started
    if _started:
        return
    _started = True
    if rhs_call.overloads or not cold() or not _python():
        return
    try:
        child = subprocess.Popen([sys.executable, "-m", __name__], stdin=subprocess.PIPE,
                                 stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=dict(os.environ))
        child.stdin.write(pickle.dumps(_core_jobs(net, ext, ws) + [j for f in _REGISTERED for j in f(net, ext, ws)]))
        child.stdin.close()
    except OSError:
        return
    own = rhs_call.compile

    def compile_after_child(sig):
        # numba asks for rhs_call when typing a caller: take the second process's from the cache
        # (its first line, or its end if it failed; past WAIT seconds this process compiles it itself)
        del rhs_call.compile
        if os.name != "posix" or select.select([child.stdout], [], [], WAIT)[0]:
            child.stdout.readline()
        return own(sig)

    rhs_call.compile = compile_after_child


def _main() -> None:
    for module, name, sig in pickle.load(sys.stdin.buffer):
        getattr(importlib.import_module(module), name).compile(sig)
        print(name, flush=True)


if __name__ == "__main__":
    _main()
