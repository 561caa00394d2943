"""A scenario run written out: ``signals.csv``, ``summary.json``, ``signals.png`` and the parameters used."""

from __future__ import annotations

from pathlib import Path

from .. import params as params_mod
from ..output import atomic_dir, write_json
from ..plant.scenarios import Result
from .plots import plot_signals


def write(res: Result, out: str | Path) -> None:
    """Write the run into ``out`` (replaced whole, atomically)."""
    with atomic_dir(out) as d:
        res.signals.to_csv(d / "signals.csv", index=False, float_format="%.10g")
        write_json(d / "summary.json", {"scenario": res.scenario, **res.summary})
        plot_signals(res.signals, res.scenario, d / "signals.png", title=f"wetclutch {res.scenario}")
        (d / "params.toml").write_text(params_mod.to_toml(res.params))
