"""A launch written out: signals, true signals, figures and a plot."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import pandas as pd

from ..launch.loop import LaunchResult
from ..output import atomic_dir, write_json
from ..params import Params
from .plots import plot_launch


def write(result: LaunchResult, out: str | Path, params: Params, runs: list[LaunchResult] | None = None) -> None:
    """``signals.csv``, ``truth.csv``, ``summary.json``, ``plot.png`` and, for the launch controller,
    ``adaptation.toml`` of a launch (the last of a sequence ``runs``, whose figures go to ``sequence.csv``), written
    atomically. (The baseline learns nothing: it has no adaptation to write.)"""
    with atomic_dir(out) as d:
        if result.summary["controller"] == "launch":
            (d / "adaptation.toml").write_text(result.adaptation.to_toml())
        if runs and len(runs) > 1:
            keys = ("t95_s", "t95_settled_s", "overshoot_pct", "creep_Nm", "standby_peak_Nm", "steady_state_error_pct",
                    "kiss_start_Pa", "kiss_found_Pa", "hold_margin_Pa", "friction_factor_found", "friction_slope_found",
                    "output_inertia_found_kg_m2", "request_shaped", "limit_cycles_seen", "all_pass")
            pd.DataFrame([{"launch": i + 1, **{k: r.summary.get(k) for k in keys}} for i, r in enumerate(runs)]).to_csv(
                d / "sequence.csv", index=False)
        result.signals.to_csv(d / "signals.csv", index=False, float_format="%.8g")
        result.truth.to_csv(d / "truth.csv", index=False, float_format="%.8g")
        conditions = json.loads(json.dumps(asdict(result.conditions), default=str))
        write_json(d / "summary.json", {**result.summary, "conditions": conditions, "params": params.model_dump()})
        plot_launch(result.signals, result.truth, result.summary, d / "plot.png")
