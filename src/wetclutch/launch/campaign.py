"""The main job: nominal launches of the design and the baseline, and the verification of both."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..params import Params
from . import loop, verify

#: the nominal launches: oil temperatures (C) and requests (N m)
NOMINAL_TEMPS = (41.0, 85.0)
NOMINAL_REQUESTS = (50.0, 100.0, 150.0)


@dataclass
class MainJob:
    """Nominal launches (design, baseline) and the verification of design and baseline."""

    launches: list[tuple[loop.LaunchResult, loop.LaunchResult]]
    verify: dict[str, Any]
    verify_baseline: dict[str, Any]


def main_job(samples: int = 1000, baseline_samples: int = 200, seed: int = 0, workers: int | None = None,
             progress: bool = True, scheduler: str | None = None) -> MainJob:
    """Run the main job on the default rig (see :mod:`wetclutch.report.main` for what is written); the two
    verifications on the ``dask.distributed`` scheduler ``scheduler`` if one is given (see :func:`verify.run`)."""
    # refuse bad options before minutes of launches, not after
    verify.check_options(samples, seed, workers)
    verify.check_options(baseline_samples, seed, workers, "--baseline-samples")
    p = Params()
    launches = []
    for temp in NOMINAL_TEMPS:
        for t_ref in NOMINAL_REQUESTS:
            cond = loop.Conditions(t_ref=t_ref, oil_temp_C=temp)
            launches.append((loop.simulate(p, "launch", cond), loop.simulate(p, "pi", cond)))
    ver = verify.run(samples, seed, workers, "launch", progress=progress, scheduler=scheduler)
    base = verify.run(baseline_samples, seed, workers, "pi", progress=progress, scheduler=scheduler)
    return MainJob(launches, ver, base)
