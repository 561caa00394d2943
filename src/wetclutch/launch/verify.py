"""Verification of a launch controller over the range of plants and conditions (Monte Carlo and corners).

A controller is designed on one plant (its :class:`~wetclutch.launch.design.Design`
carries that plant) and verified on plants drawn around another (the plant under
test; the same one unless a mismatch is what is being verified). What varies, and how,
is data (:mod:`wetclutch.launch.ranges`). Each sample is a plant and a launch on it; the
corner cases take every combination of the corner ranges' extremes. Samples are drawn
from one seed, each with its own noise seed, so a run is deterministic and each sample
can be replayed with ``wetclutch launch`` (the ``replay`` field).

The result (:func:`run`) holds the pass rate of every requirement, overall and per
range bin (:data:`N_BINS` equal bins of each range: where it fails, not only how often),
metric percentiles, the worst cases and every sample. The pass rate is that of the random
samples, an estimate of the share of the ranges' clutches that pass (with its 95 %
confidence interval, Wilson's); the corners are the worst-case figure beside it
(``corners_passed`` of ``corners``), and ``pass_rate_all_cases`` counts both.

The requirements judge a launch's response up to :data:`wetclutch.launch.metrics.STEADY_END`
after the request (and its standby before it), so a verification launch stops
:data:`HORIZON` after the request: the simulation up to then is the same, step for step,
as that of the whole launch, and so is every requirement's verdict and the adaptation a
sequence carries over, in a fraction of the time (a cold, gentle launch slips for ten
seconds before lock-up). Lock-up time and slip energy then remain unknown (None);
``through_lockup`` runs every launch to its lock-up, as ``wetclutch launch`` does.
"""

from __future__ import annotations

import functools
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy.stats import binomtest

from ..errors import WetclutchError, check_flag, check_instance, check_integer, kind_of, named
from ..params import Params
from . import distributed
from . import loop as launch
from . import metrics
from . import ranges as ranges_mod
from .design import Design
from .loop import NOMINAL_LEVELS, Grid, nominal_at, nominal_grid

#: a launch whose torque peaks above this multiple of the steady value slams
SLAM_FACTOR = 1.5
#: how long after the request a verification launch runs (s), unless it is run through lock-up: past the end of the
#: requirements' steady window by the 0.1 s it keeps from a lock-up (a lock-up before then cuts the window short, so
#: the launch must have seen it) and 0.05 s more
HORIZON = metrics.STEADY_END + 0.15
#: figures that need the launch run to lock-up
LOCKUP_METRICS = ("slip_energy_J", "t_sync_s")
N_BINS = 4
METRICS = ("steady_state_error_pct", "t95_s", "t95_settled_s", "overshoot_pct", "ripple_pct", "oscillation_pct",
           "jerk_max", "creep_Nm", "standby_peak_Nm", "slip_energy_J", "t_sync_s", "contact_s", "input_at_max_pct")
#: a failure with the valve input at the top of its range and the torque short of the request in at least this
#: share of the steady window (%) is counted as one at the clutch's capacity
CAPACITY_SHARE = 10.0


@dataclass(frozen=True)
class Sample:
    """One verification case: the sampled value of each range (by range name) and its noise seed."""

    index: int
    values: dict[str, float]
    seed: int
    corner: bool = False


@dataclass(frozen=True)
class Context:
    """What every sample of a run shares: the design, the plant under test, the ranges, how to replay."""

    design: Design
    plant: Params
    ranges: list[ranges_mod.Range]
    profile: str = "step"
    replay_args: str = ""
    sequence: int = 1
    through_lockup: bool = False
    #: the ranges limited to the plant's physical range (:func:`wetclutch.launch.ranges.fit`), a sentence each
    limited: tuple[str, ...] = ()

    def case(self, sample: Sample) -> tuple[Params, launch.Conditions]:
        plant, cond = ranges_mod.apply(self.ranges, sample.values, self.plant)
        base = launch.Conditions()
        t_max = base.horizon if self.through_lockup else min(base.horizon, base.t_request + HORIZON)
        return plant, launch.Conditions(t_ref=cond.get("t_ref", base.t_ref), oil_temp_C=cond.get("oil_temp_C"),
                                        profile=self.profile, seed=sample.seed,
                                        noise_scale=cond.get("noise_scale", base.noise_scale), t_max=t_max)

    def replay(self, sample: Sample, plant: Params, cond: launch.Conditions) -> str:
        """The ``wetclutch launch`` command that runs ``sample`` (its plant and conditions from :meth:`case`) again."""
        # full precision: a launch with stick/slip events is sensitive to the last digits
        sets = " ".join(f"--set {r.target}={_dotted(plant, r.target)!r}" for r in self.ranges if not r.is_condition)
        temp = plant.rig.oil_temp_C if cond.oil_temp_C is None else cond.oil_temp_C
        request = f"--t-ref {cond.t_ref!r}" if cond.profile in launch.PROFILES else f"--profile {cond.profile}"
        return (f"wetclutch launch --out replay-{sample.index}{self.replay_args} {request} "
                f"--oil-temp {temp!r} --seed {sample.seed} --noise-scale {cond.noise_scale!r} {sets}").rstrip()


def _dotted(p: Params, name: str) -> float:
    section, key = name.split(".")
    return float(getattr(getattr(p, section), key))


def samples(ctx: Context, n: int, seed: int, corners: bool = True) -> list[Sample]:
    """``n`` random samples of ``ctx.ranges`` and, if ``corners``, the corner cases (first)."""
    rng = np.random.default_rng(seed)
    base = launch.Conditions()
    nominal = ranges_mod.nominal(ctx.ranges, ctx.plant, {"oil_temp_C": ctx.plant.rig.oil_temp_C, "t_ref": base.t_ref,
                                                         "noise_scale": base.noise_scale})
    out: list[Sample] = []
    if corners:
        for combo in ranges_mod.corners(ctx.ranges):
            out.append(Sample(len(out), nominal | combo, int(rng.integers(2**31)), True))
    for _ in range(n):
        out.append(Sample(len(out), ranges_mod.draw(ctx.ranges, rng), int(rng.integers(2**31))))
    return out


def run_sample(ctx: Context, sample: Sample, grid: Grid) -> dict[str, Any]:
    """Launches on one sample; its values, metrics and pass/fail (failures of the simulation recorded, not raised).

    With ``ctx.sequence`` > 1 the sample is one clutch launched that many times, the controller's adaptation
    carried from launch to launch (each launch its own noise seed); the metrics and requirements are those of
    the last launch, ``first`` those of the first, ``slams`` counts launches whose torque peaked above
    :data:`SLAM_FACTOR` times the request.
    """
    plant, cond = ctx.case(sample)
    runs, seq = [], []
    try:
        runs = launch.sequence(plant, ctx.design, cond, ctx.sequence, nominal=nominal_at(grid, cond.t_ref))
        seq = [r.summary for r in runs]
        s = seq[-1]
        figures = {k: None if k in LOCKUP_METRICS and not ctx.through_lockup else s[k] for k in METRICS}
        req, error = s["requirements"], None
    except WetclutchError as e:
        figures, req, error = {}, {k: False for k in metrics.REQUIREMENTS}, str(e)
    first = seq[0]["all_pass"] if seq else False
    slams = sum(1 for x in seq if x["overshoot_pct"] is not None and x["overshoot_pct"] > 100.0 * (SLAM_FACTOR - 1))
    # a failure whose plates touched only after the request: would the valve wide open from the start have filled
    # the clutch in time? (only then is the late fill the controller's)
    late = not all(req.values()) and (figures.get("contact_s") or 0.0) > 0.0
    try:
        # one open-loop fill on to the response time after the request answers both: not before the request, and
        # not within the response time after it either (the torque rises only once the plates touch, so no launch
        # of this clutch answers in time)
        fastest = launch.fastest_contact(plant, cond, metrics.REQ_T95_S) if late else None
        too_slow = late and (fastest is None or fastest > 0.0)
        too_late = late and fastest is None
    except WetclutchError:
        too_slow = too_late = False  # the open-loop fill failed to simulate: unknown, so not counted
    # a failed standby: would the plates held open from the start have pushed the waiting vehicle as hard?
    try:
        drag = not req["standby"] and launch.open_plates_creep(plant, cond) > metrics.REQ_CREEP_NM
    except WetclutchError:
        drag = False
    # a failure with the valve input at the top of its range: could any launch on this clutch have held the request
    # within the error and the ripple? (only then is the shortfall the controller's)
    at_max = bool(runs) and not all(req.values()) and (figures.get("input_at_max_pct") or 0.0) >= CAPACITY_SHARE
    try:
        beyond = at_max and not launch.capacity_allows(plant, runs[-1])
    except WetclutchError:
        beyond = False  # the valve's highest pressure failed to simulate: unknown, so not counted
    return {"index": sample.index, "corner": sample.corner, "seed": sample.seed, "values": sample.values,
            "metrics": figures, "requirements": req, "all_pass": all(req.values()), "first_all_pass": first,
            "slams": slams, "fill_too_slow": too_slow, "fill_after_response": too_late, "creep_of_the_drag": drag,
            "beyond_capacity": beyond, "error": error, "replay": ctx.replay(sample, plant, cond)}


def unreachable(row: dict[str, Any]) -> bool:
    """Whether a sample fails whatever the controller: its request beyond the clutch's capacity, the open plates'
    drag alone creeping beyond the limit, or plates that the valve wide open from the start touches only the
    response time asked for after the request or later. (A fill that the valve wide open does not complete before
    the request, but sooner than that after it, is not counted: a response can still make its time.)"""
    return bool(row["beyond_capacity"] or row["creep_of_the_drag"] or row["fill_after_response"])


_SHARED: tuple[Context, Grid] | None = None


def _worker(sample: Sample) -> dict[str, Any]:
    assert _SHARED is not None
    return run_sample(_SHARED[0], sample, _SHARED[1])


def _warm(one: Any, sample: Sample) -> None:
    """Compile the closed loop on this process, or load it from the numba cache (a sweep's workers)."""
    one(sample)


#: the most local worker processes: each is started at once, and more than the cores only share them
MAX_WORKERS = 256


def check_options(n: int, seed: int, workers: int | None, samples_option: str = "--samples",
                  seed_option: str = "--seed", workers_option: str = "--workers") -> None:
    """Refuse a bad sample count, seed or worker count (one-line errors naming the option, or the argument of a
    Python call: ``samples_option``, ``seed_option``, ``workers_option``)."""
    if check_integer(n, samples_option) < 0:
        raise WetclutchError(f"{samples_option} must be >= 0 (got {n})")
    if check_integer(seed, seed_option) < 0:
        raise WetclutchError(f"{seed_option} must be >= 0 (got {seed})")
    if workers is not None and not 1 <= check_integer(workers, workers_option) <= MAX_WORKERS:
        raise WetclutchError(f"{workers_option} must be in 1..{MAX_WORKERS} (got {workers})")


def _check_run(design: Design, plant: Params | None, ranges: list[ranges_mod.Range] | None,
               scheduler: str | None, replay_args: str) -> None:
    """Refuse arguments of :func:`run` of the wrong kind (one line naming the argument)."""
    if isinstance(design, Params):
        raise WetclutchError("design must be a controller design (wetclutch.launch.design.design(params, kind)), "
                             "not a parameter set (the plant goes second: run(design, plant, ...))")
    check_instance(design, Design, "design", "a controller design (wetclutch.launch.design.design(params, kind))")
    if isinstance(plant, Design):
        raise WetclutchError("plant must be a parameter set (wetclutch.load_params(...)) or None, not a Design "
                             "(the design goes first: run(design, plant, ...))")
    if plant is not None:
        check_instance(plant, Params, "plant", "a parameter set (wetclutch.load_params(...)) or None")
    if ranges is not None:
        if not isinstance(ranges, (list, tuple)):
            raise WetclutchError(f"ranges must be a list of ranges (wetclutch.launch.ranges.load(path)) or None, not "
                                 f"{kind_of(ranges)}")
        for i, r in enumerate(ranges):
            check_instance(r, ranges_mod.Range, f"ranges[{i}]", "a range (wetclutch.launch.ranges.load(path))")
    if scheduler is not None:
        check_instance(scheduler, str, "scheduler", "a dask scheduler's address (str) or None")
    check_instance(replay_args, str, "replay_args", "a string of command-line options")


def run(design: Design, plant: Params | None = None, n: int = 1000, seed: int = 0, workers: int | None = None,
        ranges: list[ranges_mod.Range] | None = None, corners: bool = True, profile: str = "step",
        progress: bool = True, replay_args: str = "", sequence: int = 1,
        scheduler: str | None = None, through_lockup: bool = False) -> dict[str, Any]:
    """Verify ``design`` on ``n`` random samples (plus corners) around ``plant``; returns the ``verify.json`` content.

    Parameters
    ----------
    design
        The controller (designed on any plant).
    plant
        The plant under test, around which the ranges vary (default: the design's own).
    n, seed
        The number of random samples of the ranges and the seed they are drawn with (their noise seeds too).
    workers
        Local processes (default: one per core).
    ranges
        What varies (default: :data:`wetclutch.launch.ranges.DEFAULT_FILE`).
    replay_args
        Options every replay command carries (e.g. `` --param-file F --controller-file C``). Without them a
        replay runs on the built-in rig's parameters with the sample's changes and designs its controller on that
        changed plant, not ``design``: it does not reproduce the sample. The design under test saved as a
        controller file (the text of :func:`wetclutch.launch.settings.to_toml`), the plant as a parameter file,
        and ``--param-file`` and ``--controller-file`` with them make the replay exact (``wetclutch verify`` passes
        the controller file it writes beside its results, and its parameter file if any).
    sequence
        Launches per sample, the adaptation carried over (see :func:`run_sample`).
    scheduler
        A ``dask.distributed`` scheduler to run the samples on (default ``$DASK_SCHEDULER_ADDRESS``;
        neither: local processes); the result is the same bit for bit
        (:mod:`wetclutch.launch.distributed`).
    through_lockup
        Run every launch to its lock-up (lock-up times and slip energies), not only to :data:`HORIZON` after
        the request, which decides every requirement.
    corners
        Whether the corner cases (every combination of the extremes of the ranges marked ``corner``) run before
        the random samples.
    profile
        The request's profile (``step``, ``ramp`` or a CSV file; :class:`wetclutch.launch.loop.Conditions`).
    progress
        Show a progress bar (rich).

    Returns
    -------
    dict
        The content of ``verify.json`` (:func:`summarize`): pass rates overall, per requirement and per range bin,
        of the first launch and of the corners, percentiles, worst cases and every sample's row (``results``).
    """
    global _SHARED
    _check_run(design, plant, ranges, scheduler, replay_args)
    # the command line checks its options before this; these are a Python caller's arguments
    check_options(n, seed, workers, "n", "seed", "workers")
    sequence = launch.check_sequence(sequence, "sequence")
    corners, progress, through_lockup = (check_flag(corners, "corners"), check_flag(progress, "progress"),
                                         check_flag(through_lockup, "through_lockup"))
    # the profile as each launch checks it, before any is made
    launch.Conditions(profile=profile).checked()
    plant = plant if plant is not None else design.plant
    rs, limited = ranges_mod.fit(ranges if ranges is not None else ranges_mod.load(), plant)
    if profile not in launch.PROFILES:
        # a CSV profile gives the request itself: a request range would be drawn and reported, never run
        dropped = [r for r in rs if r.target == "t_ref"]
        rs = [r for r in rs if r.target != "t_ref"]
        limited = [*limited, *(f"{r.name}: not varied, the profile '{profile}' gives the request" for r in dropped)]
    ctx = Context(design, plant, rs, profile, replay_args + (f" --sequence {sequence}" if sequence > 1 else ""),
                  sequence, through_lockup, tuple(limited))
    workers = workers or os.cpu_count() or 1
    cases = samples(ctx, n, seed, corners)
    if not cases:
        # no pass rate to give: refused rather than a NaN
        why = "corners=False" if not corners else "the ranges have no corner ranges"
        raise WetclutchError(f"nothing to verify: {named('n', '--samples')} is 0 (no random samples) and there are "
                             f"no corner cases ({why})")
    # the design's nominal responses, made once here and inherited by the forked workers
    grid = nominal_grid(design, profile)
    _SHARED = (ctx, grid)
    results: list[dict[str, Any]] = []
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    cols = (TextColumn("verify {task.fields[ctrl]}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
            TimeElapsedColumn(), TimeRemainingColumn())
    with Progress(*cols, disable=not progress, transient=False) as bar:
        task = bar.add_task("verify", total=len(cases), ctrl=design.kind)
        address = distributed.scheduler_address(scheduler)
        if address is not None and cases:
            one = functools.partial(run_sample, ctx, grid=grid)
            results = distributed.map_batches(one, cases, address, warm=functools.partial(_warm, one, cases[0]),
                                              on_batch=lambda k: bar.advance(task, k))
        elif workers == 1 or len(cases) < 2:
            for c in cases:
                results.append(_worker(c))
                bar.advance(task)
        else:
            import multiprocessing as mp

            with ProcessPoolExecutor(workers, mp_context=mp.get_context("fork")) as pool:
                for r in pool.map(_worker, cases, chunksize=max(1, len(cases) // (workers * 20))):
                    results.append(r)
                    bar.advance(task)
    return summarize(results, ctx, seed, n, grid)


def _interval(passed: int, n: int) -> list[float] | None:
    """Wilson's 95 % confidence interval of a pass rate of ``passed`` in ``n`` samples (None: no samples)."""
    if n == 0:
        return None
    ci = binomtest(passed, n).proportion_ci(confidence_level=0.95, method="wilson")
    return [float(ci.low), float(ci.high)]


def _above(rows: list[dict[str, Any]], metric: str, limit: float) -> int:
    """How many of ``rows`` have ``metric`` above ``limit``."""
    return sum(1 for r in rows if (r["metrics"].get(metric) or 0.0) > limit)


def _share(rows: list[dict[str, Any]], key: str) -> float:
    """The share of ``rows`` whose ``key`` is true (NaN: no rows)."""
    return sum(r[key] for r in rows) / len(rows) if rows else float("nan")


def _rate(rows: list[dict[str, Any]]) -> dict[str, float]:
    if not rows:
        return {}
    out = {k: sum(r["requirements"][k] for r in rows) / len(rows) for k in metrics.REQUIREMENTS}
    return out | {"all": sum(r["all_pass"] for r in rows) / len(rows)}


def bins(results: list[dict[str, Any]], rs: list[ranges_mod.Range], n_bins: int = N_BINS) -> dict[str, list[dict]]:
    """Pass rates per range bin: for each range, :data:`N_BINS` equal bins of ``[low, high]`` over the random
    samples (corners excluded: they sit on the edges), of the launch judged and of the first of a sequence."""
    rows = [r for r in results if not r["corner"]]
    out = {}
    for rg in rs:
        edges = np.linspace(rg.low, rg.high, n_bins + 1)
        table = []
        for i in range(n_bins):
            lo, hi = edges[i], edges[i + 1]
            inside = [r for r in rows if lo <= r["values"][rg.name] < hi or (i == n_bins - 1 and r["values"][rg.name] == hi)]
            table.append({"low": float(lo), "high": float(hi), "samples": len(inside), "pass_rate": _rate(inside),
                          "pass_rate_first_launch": _share(inside, "first_all_pass")})
        out[rg.name] = table
    return out


def metric_values(results: list[dict[str, Any]], key: str) -> np.ndarray:
    """The finite values of metric ``key`` over ``results`` (a launch without it, or that failed, has none)."""
    v = np.array([r["metrics"].get(key) for r in results if r["metrics"].get(key) is not None], dtype=float)
    return v[np.isfinite(v)]


def percentiles(results: list[dict[str, Any]]) -> dict[str, dict[str, float]]:
    """Per metric of :data:`METRICS`: the number ``n`` of ``results`` with a finite value, and their 5th, 50th, 95th
    and 99th percentiles and largest value (only ``n`` where there is none)."""
    out = {}
    for k in METRICS:
        v = metric_values(results, k)
        out[k] = {"n": int(v.size)} | ({f"p{q}": float(np.percentile(v, q)) for q in (5, 50, 95, 99)}
                                       | {"max": float(v.max())} if v.size else {})
    return out


def summarize(results: list[dict[str, Any]], ctx: Context, seed: int, n: int,
              grid: Grid | None = None) -> dict[str, Any]:
    """Pass rates (overall, per requirement, per range bin), metric percentiles and the worst cases; with ``grid``
    (:func:`wetclutch.launch.loop.nominal_grid`) the nominal responses the robustness requirement compared with."""
    total = len(results)

    def badness(r: dict[str, Any]) -> float:
        m = r["metrics"]
        if not m:
            return np.inf
        e = (m["steady_state_error_pct"] if m["steady_state_error_pct"] is not None else np.inf) / metrics.REQ_ESS_PCT
        t = (m["t95_settled_s"] if m["t95_settled_s"] is not None else np.inf) / metrics.REQ_T95_S
        return max(e, t) + (0 if r["all_pass"] else 10)

    worst = sorted(results, key=badness, reverse=True)[:10]
    random_rows = [r for r in results if not r["corner"]]
    corner_rows = [r for r in results if r["corner"]]
    # the pass rate estimates the share of the ranges' clutches that pass: the random samples'. The corners, every
    # combination of the corner ranges' extremes, are no draws of the ranges: mixed in, they would weigh by the
    # sample count (a sixth of 300 samples, a sixteenth of 1,000); they are the worst-case figure beside it
    judged = random_rows or results
    passed = sum(r["all_pass"] for r in judged)
    return {
        "controller": ctx.design.kind,
        "seed": seed,
        "samples": n,
        "cases": total,
        "ranges": [{"name": r.name, "target": r.target, "how": r.how, "dist": r.dist, "low": r.low, "high": r.high,
                    "corner": r.corner, "unit": r.unit} for r in ctx.ranges],
        "ranges_limited": list(ctx.limited),
        "pass_rate": _share(judged, "all_pass"),
        "pass_rate_interval": _interval(passed, len(judged)),
        "pass_rate_per_requirement": _rate(judged),
        "pass_rate_corners": _rate(corner_rows).get("all", float("nan")),
        "corners_passed": sum(r["all_pass"] for r in corner_rows),
        "corners": len(corner_rows),
        "pass_rate_all_cases": _rate(results).get("all", float("nan")),
        "sequence": ctx.sequence,
        "horizon_s": None if ctx.through_lockup else HORIZON,
        # the nominal responses the robustness requirement compared with, and the request level each was taken
        # from (another than its own: that level's nominal launch did not settle)
        "nominal": None if grid is None else {
            "request_Nm": NOMINAL_LEVELS.tolist(),
            "t95_settled_s": [float(x) if np.isfinite(x) else None for x in grid[0]],
            "overshoot_pct": [float(x) if np.isfinite(x) else None for x in grid[1]],
            "taken_from_Nm": grid[2].tolist()},
        "pass_rate_first_launch": _share(judged, "first_all_pass"),
        "pass_rate_first_launch_corners": _share(corner_rows, "first_all_pass"),
        "slams": sum(r["slams"] for r in results),
        # failures whose plates first touched after the request: the fill was not complete when torque was asked for
        "failures_unfilled": sum(1 for r in results if not r["all_pass"] and (r["metrics"].get("contact_s") or 0) > 0),
        # of those, the ones whose valve wide open from the start would not have filled the clutch before the
        # request either: no controller fills them in time
        "failures_fill_too_slow": sum(1 for r in results if r["fill_too_slow"]),
        # and of those, the ones it would not have filled within the response time after the request: no launch
        # answers in time
        "failures_fill_after_response": sum(1 for r in results if r["fill_after_response"]),
        "failures_creep_of_the_drag": sum(1 for r in results if r["creep_of_the_drag"]),
        # failures where the controller asked for all the valve gives: the clutch at or beyond its capacity
        "failures_at_capacity": sum(1 for r in results if not r["all_pass"]
                                    and (r["metrics"].get("input_at_max_pct") or 0) >= CAPACITY_SHARE),
        # of those, the ones where no torque under the plates' capacity meets the error and the ripple
        # (:func:`wetclutch.launch.loop.capacity_allows`): no controller passes them
        "failures_beyond_capacity": sum(1 for r in results if r["beyond_capacity"]),
        # the random samples' pass rate without those that fail whatever the controller (:func:`unreachable`)
        "pass_rate_reachable": _share([r for r in judged if not unreachable(r)], "all_pass"),
        # launches (random samples) whose torque oscillates about its trend by more than the ripple allowed: a
        # sustained oscillation, told apart from a drift (a sag at the clutch's capacity) that fails the ripple too
        "oscillating": _above(random_rows, "oscillation_pct", metrics.REQ_RIPPLE_PCT),
        "rippling": _above(random_rows, "ripple_pct", metrics.REQ_RIPPLE_PCT),
        "bins": bins(results, ctx.ranges),
        # over the random samples, as the pass rates; the corners' apart
        "percentiles": percentiles(random_rows),
        "percentiles_corners": percentiles(corner_rows),
        "worst": [{k: r[k] for k in ("index", "values", "metrics", "requirements", "replay")} for r in worst],
        "results": results,
    }
