"""The calibration report: the rig's figures against the study's, as ``report.md``, ``report.json`` and plots."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..output import atomic_dir, write_json
from ..rig.calibration import Figure, explanation
from . import html
from .plots import plt

#: bar: the up-down difference of the staircases above which the hysteresis counts as visible
#: (``wetclutch.rig.calibration.run``)
VISIBLE = 0.02


def write(figs: list[Figure], out: str | Path) -> None:
    """``report.md``, ``report.json`` and overlay plots for the figures, written atomically into ``out``."""
    with atomic_dir(out) as d:
        rows = []
        for f in figs:
            rows.append({
                "figure": f.name, "published": f.published, "simulated": f.simulated, "error": f.error,
                "error_kind": f.error_kind, "tolerance": f.tolerance, "unit": f.unit, "pass": f.passed,
                "note": f.note, "explanation": "" if f.passed else explanation(f.name),
            })
        write_json(d / "report.json", {"figures": rows, "passed": sum(r["pass"] for r in rows), "total": len(rows)})
        # the rig calibrated is the command's plant (the built-in default, or its parameter file and --set): the
        # figures are the study's own rig's, so a plant of another clutch is expected to miss some
        lines = ["# Calibration of the rig against the study (WFW 96.071)", "",
                 f"{sum(r['pass'] for r in rows)} of {len(rows)} figures within tolerance. The figures are those "
                 "the study measured on its rig (the built-in default parameters); a clutch of other parameters "
                 "(`--param-file`, `--set`) is expected to miss those its changes move.", "",
                 "| figure | published | simulated | error | tolerance | result |", "|---|---|---|---|---|---|"]

        def fmt(v: Any) -> str:
            if isinstance(v, float):
                # a dead time or contact pressure that is not a number: the torque never rose past the onset
                return f"{v:.3f}" if np.isfinite(v) else "no torque onset"
            if isinstance(v, list):
                return ", ".join(f"{x:.2f}" for x in v)
            return str(v)

        for r in rows:
            err = f"{100 * r['error']:+.1f} %" if r["error_kind"] == "relative" else f"{r['error']:+.3f} {r['unit']}"
            tol = f"{100 * r['tolerance']:.0f} %" if r["error_kind"] == "relative" else f"{r['tolerance']} {r['unit']}"
            if isinstance(r["published"], str):
                # a qualitative figure (the hysteresis is visible): the up-down difference against the threshold
                err, tol = "-", f"> {VISIBLE:g} {r['unit']} up-down"
            elif not np.isfinite(r["error"]):
                err = "-"
            lines.append(f"| {r['figure']} | {fmt(r['published'])} | {fmt(r['simulated'])} | {err} | {tol} | "
                         f"{'pass' if r['pass'] else 'FAIL'} |")
        lines.append("")
        for r in rows:
            if r["note"]:
                lines.append(f"* {r['figure']}: {r['note']}")
        failed = [r for r in rows if not r["pass"] and r["explanation"]]
        if failed:
            lines += ["", "## Why some figures are not met", ""]
            for r in failed:
                lines += [f"**{r['figure']}.** {r['explanation']}", ""]
        lines += ["", "Every figure against the study's, with its tolerance band:", "", "![figures](figures.png)", ""]
        md = "\n".join(lines)
        (d / "report.md").write_text(md)
        plot_figures(figs, d / "figures.png")
        html.write_calibration(d / "report.html", md, figs, _band)


def _band(f: Figure, ref):
    """Lower and upper edge of the tolerance band around the published value(s) ``ref``."""
    ref = np.asarray(ref, dtype=float)
    if f.error_kind == "relative":
        return ref * (1.0 - f.tolerance), ref * (1.0 + f.tolerance)
    return ref - f.tolerance, ref + f.tolerance


def plot_figures(figs: list[Figure], path: Path) -> None:
    """One panel per figure: the study's value or curve, its tolerance band (shaded) and the model."""
    n = len(figs)
    cols = 4
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.3 * rows), squeeze=False)
    for ax, f in zip(axes.flat, figs):
        colour = "tab:green" if f.passed else "tab:red"
        c = f.curve
        if c and "published" in c:
            xkey = next(iter(c))
            x = np.asarray(c[xkey])
            lo, hi = _band(f, c["published"])
            ax.fill_between(x, lo, hi, color="0.85", label=f"tolerance {_tol(f)}")
            ax.plot(x, c["published"], "k--", label="study (fit)")
            for k in ("simulated", "up", "down"):
                if k in c:
                    ax.plot(x, c[k], "o-", ms=3, color=None if k != "simulated" else colour,
                            label="model" if k == "simulated" else f"model {k}")
            ax.set_xlabel(xkey)
            ax.set_ylabel(f"p [{f.unit}]")
        elif isinstance(f.published, (int, float)):
            lo, hi = _band(f, f.published)
            ax.axhspan(float(lo), float(hi), color="0.85", label=f"tolerance {_tol(f)}")
            ax.axhline(f.published, color="k", ls="--", label="study")
            ax.plot([0.0], [f.simulated], "o", ms=8, color=colour, label="model")
            ax.set_xticks([])
            ax.set_ylabel(f.unit)
        else:
            # a qualitative figure (the hysteresis is visible): the model's value against the threshold
            ax.axhspan(0.0, VISIBLE, color="0.85", label=f"not visible (< {VISIBLE:g} bar)")
            ax.plot([0.0], [f.simulated], "o", ms=8, color=colour, label="model")
            ax.set_xticks([])
            ax.set_ylabel(f"up-down difference [{f.unit}]")
        ax.set_title(f.name, fontsize=7)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=6)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _tol(f: Figure) -> str:
    return f"{100 * f.tolerance:.0f} %" if f.error_kind == "relative" else f"{f.tolerance:g} {f.unit}"
