"""A rig run written like a real rig: measurement files, true states, metadata and a plot."""

from __future__ import annotations

from pathlib import Path

from ..output import atomic_dir, write_csv
from ..rig.experiments import RigResult
from ..rig.files import write_measurement
from .plots import plot_rig


def write(result: RigResult, out: str | Path) -> None:
    """``measured.csv``/``.mf4``/``.mat``, ``truth.csv``, ``meta.json`` and ``plot.png`` into ``out``, atomically."""
    with atomic_dir(out) as d:
        write_measurement(d, result.measured, result.meta["units"], result.meta)
        write_csv(result.truth, d / "truth.csv")
        plot_rig(result.measured, result.truth, d / "plot.png", title=f"wetclutch rig {result.meta['experiment']}",
                 u_unit=result.meta.get("units", {}).get("u"))
