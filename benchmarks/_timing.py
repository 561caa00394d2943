"""Timing helper shared by the benchmark scripts."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from typing import Any


def median_time(fn: Callable[[], Any], repeats: int) -> tuple[float, Any]:
    """Median wall time (s) of ``fn()`` over ``repeats`` calls after one warm-up call, and the last result."""
    out = fn()  # warm-up: JIT compilation, caches
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def interleaved_times(fns: dict[str, tuple[Callable[[], Any], int]], rounds: int) -> tuple[dict[str, float], dict[str, Any]]:
    """Median wall time (s) per call of each function, timed in turns: ``{name: (fn, calls per turn)}``.

    A speed ratio is only meaningful when both sides see the same machine; on a shared
    host a burst of load lasting a few hundred milliseconds would otherwise fall on
    whichever side happened to be running. Each turn runs one function several times in a
    row (warm caches, as in a batch of simulations) and keeps the median of that turn; the
    result is the median over the rounds. Returns those times and each function's last result.
    """
    out = {name: fn() for name, (fn, _) in fns.items()}  # warm-up: JIT compilation, caches
    times: dict[str, list[float]] = {name: [] for name in fns}
    for _ in range(rounds):
        for name, (fn, calls) in fns.items():
            turn = []
            for _ in range(calls):
                t0 = time.perf_counter()
                out[name] = fn()
                turn.append(time.perf_counter() - t0)
            times[name].append(statistics.median(turn))
    return {name: statistics.median(v) for name, v in times.items()}, out
