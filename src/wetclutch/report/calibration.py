"""The calibration report: the default rig's figures against the study's, as ``report.md``, ``report.json`` and plots."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..output import atomic_dir, write_json
from ..rig.calibration import Figure, explanation
from .plots import plt


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
        lines = ["# Calibration of the default rig against the study (WFW 96.071)", "",
                 f"{sum(r['pass'] for r in rows)} of {len(rows)} figures within tolerance.", "",
                 "| figure | published | simulated | error | tolerance | result |", "|---|---|---|---|---|---|"]

        def fmt(v: Any) -> str:
            if isinstance(v, float):
                return f"{v:.3f}"
            if isinstance(v, list):
                return ", ".join(f"{x:.2f}" for x in v)
            return str(v)

        for r in rows:
            err = f"{100 * r['error']:+.1f} %" if r["error_kind"] == "relative" else f"{r['error']:+.3f} {r['unit']}"
            tol = f"{100 * r['tolerance']:.0f} %" if r["error_kind"] == "relative" else f"{r['tolerance']} {r['unit']}"
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
        lines += ["", "![static curves](curves.png)", "", "![dead times](dead_times.png)", ""]
        (d / "report.md").write_text("\n".join(lines))

        curves = [f for f in figs if f.curve]
        fig, axes = plt.subplots(1, len(curves), figsize=(4.5 * len(curves), 3.6), squeeze=False)
        for ax, f in zip(axes[0], curves):
            c = f.curve
            xkey = next(iter(c))
            ax.plot(c[xkey], c["published"], "k--", label="study (fit)")
            for k in ("simulated", "up", "down"):
                if k in c:
                    ax.plot(c[xkey], c[k], "o-", ms=3, label=f"model {k}" if k != "simulated" else "model")
            ax.set_xlabel(xkey)
            ax.set_ylabel("p [bar]")
            ax.set_title(f.name, fontsize=8)
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(d / "curves.png", dpi=110)
        plt.close(fig)

        dts = [f for f in figs if f.name.startswith("dead time")]
        fig, ax = plt.subplots(figsize=(6, 3.2))
        x = np.arange(len(dts))
        ax.bar(x - 0.2, [f.published for f in dts], 0.4, label="study")
        ax.bar(x + 0.2, [f.simulated for f in dts], 0.4, label="model")
        ax.set_xticks(x, [f.name.replace("dead time ", "") for f in dts], fontsize=8)
        ax.set_ylabel("dead time [s]")
        ax.legend()
        fig.tight_layout()
        fig.savefig(d / "dead_times.png", dpi=110)
        plt.close(fig)
