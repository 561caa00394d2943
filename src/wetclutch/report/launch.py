"""A launch written out: signals, true signals, figures and a plot."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

from ..launch.loop import LaunchResult
from ..output import atomic_dir, write_json
from ..params import Params
from .plots import plot_launch


def write(result: LaunchResult, out: str | Path, params: Params) -> None:
    """``signals.csv``, ``truth.csv``, ``summary.json`` and ``plot.png`` of a launch, written atomically."""
    with atomic_dir(out) as d:
        result.signals.to_csv(d / "signals.csv", index=False, float_format="%.8g")
        result.truth.to_csv(d / "truth.csv", index=False, float_format="%.8g")
        conditions = json.loads(json.dumps(asdict(result.conditions), default=str))
        write_json(d / "summary.json", {**result.summary, "conditions": conditions, "params": params.model_dump()})
        plot_launch(result.signals, result.truth, result.summary, d / "plot.png")
