"""Verification of a launch controller over the range of conditions (Monte Carlo and corners).

Each sample is a rig that differs from the design rig the way real ones do, and
a launch on it with the controller designed on the defaults (see
:func:`wetclutch.launch.design.design_params`). :data:`RANGES` lists what varies and
over what range (uniform); :data:`CORNERS` adds the extreme combinations of the
four factors that matter most. Samples are drawn from one seed, each with its
own noise seed, so a run is deterministic and each sample can be replayed with
``wetclutch launch`` (the ``replay`` field).
"""

from __future__ import annotations

import functools
import itertools
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..errors import WetclutchError
from ..params import Params
from . import distributed
from . import loop as launch
from . import metrics
from .design import CONTROLLERS

#: name -> (parameter path or condition, low, high, how): "abs" sets the value, "rel" scales the default
RANGES: dict[str, tuple[str, float, float, str]] = {
    "oil_temp_C": ("condition", 20.0, 85.0, "abs"),
    # the study's mu over inputs above 1 V spread from 0.034 to 0.052 around about 0.043
    "friction.mu_scale": ("param", 0.034 / 0.043, 0.052 / 0.043, "abs"),
    # fill and dead time: supply line loss and piston stroke (the contact pressure moves with it)
    "hydraulics.line_length": ("param", 0.7, 1.3, "rel"),
    "hydraulics.x_contact": ("param", 0.85, 1.15, "rel"),
    "hydraulics.air_fraction": ("param", 0.002, 0.01, "abs"),
    "driveline.ratio": ("param", 0.4, 0.8, "abs"),
    "driveline.eta": ("param", 0.90, 0.97, "abs"),
    "driveline.k_a": ("param", 0.7, 1.3, "rel"),
    "engage.T_load": ("param", 0.0, 30.0, "abs"),
    "t_ref": ("condition", 50.0, 150.0, "abs"),
    "noise_scale": ("condition", 0.5, 2.0, "abs"),
}
#: corner cases: every combination of these extremes, the rest nominal
CORNERS = ("oil_temp_C", "friction.mu_scale", "driveline.ratio", "t_ref")
NOMINAL_LEVELS = np.array([50.0, 75.0, 100.0, 125.0, 150.0])


@dataclass(frozen=True)
class Sample:
    """One verification case: the varied values (by :data:`RANGES` name) and its noise seed."""

    index: int
    values: dict[str, float]
    seed: int
    corner: bool = False

    def params(self) -> Params:
        p = Params()
        defaults = p.model_dump()
        for name, (kind, _, _, how) in RANGES.items():
            if kind != "param" or name not in self.values:
                continue
            section, field = name.split(".")
            v = self.values[name]
            setattr(getattr(p, section), field, v * defaults[section][field] if how == "rel" else v)
        return p

    def conditions(self, profile: str = "step") -> launch.Conditions:
        return launch.Conditions(t_ref=self.values["t_ref"], oil_temp_C=self.values["oil_temp_C"], profile=profile,
                                 seed=self.seed, noise_scale=self.values["noise_scale"])

    def replay(self, controller: str) -> str:
        p = self.params()
        # full precision: a launch with stick/slip events is sensitive to the last digits
        sets = " ".join(f"--set {n}={_dotted(p, n)!r}" for n, r in RANGES.items() if r[0] == "param")
        return (f"wetclutch launch --out replay-{self.index} --controller {controller} --t-ref {self.values['t_ref']!r} "
                f"--oil-temp {self.values['oil_temp_C']!r} --seed {self.seed} --noise-scale {self.values['noise_scale']!r} {sets}")


def _dotted(p: Params, name: str) -> float:
    section, field = name.split(".")
    return float(getattr(getattr(p, section), field))


def _nominal_values() -> dict[str, float]:
    """Each range's value on the design rig: the default parameters and launch conditions."""
    p, c = Params().model_dump(), launch.Conditions()
    cond = {"oil_temp_C": p["rig"]["oil_temp_C"], "t_ref": c.t_ref, "noise_scale": c.noise_scale}
    out = {}
    for name, (kind, _, _, how) in RANGES.items():
        if kind == "condition":
            out[name] = cond[name]
        else:
            section, field = name.split(".")
            out[name] = 1.0 if how == "rel" else p[section][field]
    return out


def samples(n: int, seed: int, corners: bool = True) -> list[Sample]:
    """``n`` random samples (uniform over :data:`RANGES`) and, if ``corners``, the corner cases."""
    rng = np.random.default_rng(seed)
    nominal = _nominal_values()
    out: list[Sample] = []
    if corners:
        for combo in itertools.product(*[(RANGES[c][1], RANGES[c][2]) for c in CORNERS]):
            out.append(Sample(len(out), {**nominal, **dict(zip(CORNERS, combo))}, int(rng.integers(2**31)), True))
    for _ in range(n):
        values = {k: float(rng.uniform(lo, hi)) for k, (_, lo, hi, _) in RANGES.items()}
        out.append(Sample(len(out), values, int(rng.integers(2**31))))
    return out


def nominal_grid(controller: str, profile: str = "step", gains: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """t95 and overshoot of the nominal launch at :data:`NOMINAL_LEVELS` (interpolated in between)."""
    rows = [launch.nominal_response(controller, launch.Conditions(t_ref=float(lv), profile=profile), gains)
            for lv in NOMINAL_LEVELS]
    return np.array([r.t95_s for r in rows]), np.array([r.overshoot_pct for r in rows])


def _nominal_at(grid: tuple[np.ndarray, np.ndarray], t_ref: float) -> metrics.Response:
    t95 = float(np.interp(t_ref, NOMINAL_LEVELS, grid[0]))
    ovs = float(np.interp(t_ref, NOMINAL_LEVELS, grid[1]))
    return replace(metrics.Response.empty(), t95_s=t95, overshoot_pct=ovs)


def run_sample(sample: Sample, controller: str, grid: tuple[np.ndarray, np.ndarray], profile: str = "step",
               gains: Any = None) -> dict[str, Any]:
    """Launch on one sample; its values, metrics and pass/fail (failures of the simulation recorded, not raised).

    ``gains``: the controller's settings (None: its defaults), for tuning experiments.
    """
    try:
        res = launch.simulate(sample.params(), controller, sample.conditions(profile), gains=gains,
                              nominal=_nominal_at(grid, sample.values["t_ref"]))
        s = res.summary
        metrics_ = {k: s[k] for k in ("steady_state_error_pct", "t95_s", "overshoot_pct", "jerk_max", "slip_energy_J", "t_sync_s")}
        req, error = s["requirements"], None
    except WetclutchError as e:
        metrics_, req, error = {}, {"steady_state_error": False, "response_time": False, "robustness": False}, str(e)
    return {"index": sample.index, "corner": sample.corner, "seed": sample.seed, "values": sample.values,
            "metrics": metrics_, "requirements": req, "all_pass": all(req.values()), "error": error,
            "replay": sample.replay(controller)}


_GRID: tuple[np.ndarray, np.ndarray] | None = None


def _worker(args: tuple[Sample, str, str, Any]) -> dict[str, Any]:
    assert _GRID is not None
    return run_sample(args[0], args[1], _GRID, args[2], args[3])


def _warm() -> None:
    """Compile the closed loop on this process, or load it from the numba cache (a sweep's workers)."""
    launch.simulate(Params(), "launch", launch.Conditions())


def check_options(n: int, seed: int, workers: int | None, samples_option: str = "--samples") -> None:
    """Refuse a bad sample count, seed or worker count (one-line errors naming the option)."""
    if n < 0:
        raise WetclutchError(f"{samples_option} must be >= 0 (got {n})")
    if seed < 0:
        raise WetclutchError(f"--seed must be >= 0 (got {seed})")
    if workers is not None and workers < 1:
        raise WetclutchError(f"--workers must be >= 1 (got {workers})")


def run(n: int = 1000, seed: int = 0, workers: int | None = None, controller: str = "launch", profile: str = "step",
        corners: bool = True, progress: bool = True, gains: Any = None, scheduler: str | None = None) -> dict[str, Any]:
    """Verify ``controller`` on ``n`` random samples (plus corners); returns the ``verify.json`` content.

    ``gains`` replaces the controller's default settings (a :class:`~wetclutch.launch.design.LaunchGains`
    or :class:`~wetclutch.launch.design.PIGains`), in the samples and in the nominal launches alike.
    ``scheduler``: the address of a ``dask.distributed`` scheduler to run the samples on (default
    ``$DASK_SCHEDULER_ADDRESS``; neither: local processes); the result is the same bit for bit.
    """
    global _GRID
    check_options(n, seed, workers)
    if controller not in CONTROLLERS:
        raise WetclutchError(f"unknown controller '{controller}'")
    workers = workers or os.cpu_count() or 1
    cases = samples(n, seed, corners)
    # the design's feedforward table and the nominal responses, made once here and
    # inherited by the forked workers
    _GRID = nominal_grid(controller, profile, gains)
    jobs = [(c, controller, profile, gains) for c in cases]
    results: list[dict[str, Any]] = []
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    cols = (TextColumn("verify {task.fields[ctrl]}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
            TimeElapsedColumn(), TimeRemainingColumn())
    with Progress(*cols, disable=not progress, transient=False) as bar:
        task = bar.add_task("verify", total=len(jobs), ctrl=controller)
        address = distributed.scheduler_address(scheduler)
        if address is not None:
            one = functools.partial(run_sample, controller=controller, grid=_GRID, profile=profile, gains=gains)
            results = distributed.map_batches(one, cases, address, warm=_warm,
                                              on_batch=lambda k: bar.advance(task, k))
        elif workers == 1:
            for j in jobs:
                results.append(_worker(j))
                bar.advance(task)
        else:
            import multiprocessing as mp

            with ProcessPoolExecutor(workers, mp_context=mp.get_context("fork")) as pool:
                for r in pool.map(_worker, jobs, chunksize=max(1, len(jobs) // (workers * 20))):
                    results.append(r)
                    bar.advance(task)
    return summarize(results, controller, seed, n)


def summarize(results: list[dict[str, Any]], controller: str, seed: int, n: int) -> dict[str, Any]:
    """Pass rates, metric percentiles and the worst cases of a verification run."""
    names = ("steady_state_error", "response_time", "robustness")
    total = len(results)
    rate = {k: sum(r["requirements"][k] for r in results) / total for k in names} if total else {}
    keys = ("steady_state_error_pct", "t95_s", "overshoot_pct", "jerk_max", "slip_energy_J", "t_sync_s")
    pct = {}
    for k in keys:
        v = np.array([r["metrics"].get(k) if r["metrics"].get(k) is not None else np.nan for r in results], dtype=float)
        v = v[np.isfinite(v)]
        pct[k] = {f"p{q}": float(np.percentile(v, q)) for q in (5, 50, 95, 99)} | {"max": float(v.max())} if v.size else {}

    def badness(r: dict[str, Any]) -> float:
        m = r["metrics"]
        if not m:
            return np.inf
        e = (m["steady_state_error_pct"] if m["steady_state_error_pct"] is not None else np.inf) / metrics.REQ_ESS_PCT
        t = (m["t95_s"] if m["t95_s"] is not None else np.inf) / metrics.REQ_T95_S
        return max(e, t) + (0 if r["all_pass"] else 10)

    worst = sorted(results, key=badness, reverse=True)[:10]
    return {
        "controller": controller,
        "seed": seed,
        "samples": n,
        "cases": total,
        "ranges": {k: {"low": lo, "high": hi, "how": how} for k, (_, lo, hi, how) in RANGES.items()},
        "pass_rate": sum(r["all_pass"] for r in results) / total if total else float("nan"),
        "pass_rate_per_requirement": rate,
        "pass_rate_random_samples": (sum(r["all_pass"] for r in results if not r["corner"])
                                     / max(1, sum(not r["corner"] for r in results))),
        "percentiles": pct,
        "worst": [{k: r[k] for k in ("index", "values", "metrics", "requirements", "replay")} for r in worst],
        "results": results,
    }
