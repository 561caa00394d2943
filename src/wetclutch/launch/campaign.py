"""The main job: nominal launches of the design and the baseline on a plant, and the verification of both."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..params import Params
from . import loop, margins, verify
from .design import Design
from .ranges import Range, fit
from .ranges import load as load_ranges

#: the nominal launches: oil temperatures (C) and requests (N m)
NOMINAL_TEMPS = (41.0, 85.0)
NOMINAL_REQUESTS = (50.0, 100.0, 150.0)


@dataclass
class MainJob:
    """Nominal launches (design, baseline) and the verification of design and baseline on the same samples."""

    plant: Params
    design: Design
    baseline: Design
    launches: list[tuple[loop.LaunchResult, loop.LaunchResult]]
    verify: dict[str, Any]
    verify_baseline: dict[str, Any]
    margins: list[dict[str, Any]]
    launch_margins: list[dict[str, Any]]


def main_job(plant: Params, design: Design, baseline: Design, ranges: list[Range] | None = None, samples: int = 1000,
             baseline_samples: int = 200, seed: int = 0, workers: int | None = None, progress: bool = True,
             replay_args: str = "", baseline_replay_args: str = "", scheduler: str | None = None,
             sequence: int = 1, through_lockup: bool = False) -> MainJob:
    """Run the main job on ``plant`` (see :mod:`wetclutch.report.main` for what is written).

    The baseline's samples are the first ``baseline_samples`` of the design's (same seed,
    same ranges), so that the two are compared on the same plants. ``replay_args`` and
    ``baseline_replay_args``: the options each replay command carries. ``scheduler``: a
    ``dask.distributed`` scheduler to run the verifications on, ``sequence`` the launches per
    sample and ``through_lockup`` whether verified launches run to lock-up (see :func:`verify.run`).
    """
    # refuse bad options before minutes of launches, not after
    verify.check_options(samples, seed, workers)
    verify.check_options(baseline_samples, seed, workers, "--baseline-samples")
    rs = ranges if ranges is not None else load_ranges()
    fit(rs, plant)  # and ranges that leave the plant's physical range
    launches = []
    for temp in NOMINAL_TEMPS:
        for t_ref in NOMINAL_REQUESTS:
            cond = loop.Conditions(t_ref=t_ref, oil_temp_C=temp)
            launches.append((loop.simulate(plant, design, cond), loop.simulate(plant, baseline, cond)))
    ver = verify.run(design, plant, samples, seed, workers, ranges, progress=progress, replay_args=replay_args,
                     scheduler=scheduler, sequence=sequence, through_lockup=through_lockup)
    base = verify.run(baseline, plant, baseline_samples, seed, workers, ranges, progress=progress,
                      replay_args=baseline_replay_args, scheduler=scheduler, sequence=sequence,
                      through_lockup=through_lockup)
    return MainJob(plant, design, baseline, launches, ver, base, margins.over_corners(baseline, plant, rs),
                   margins.launch_over_corners(design, plant, rs))
