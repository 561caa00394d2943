"""A verification run written out: ``verify.json``, ``verify.md``, ``samples.csv`` and histograms."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..launch import metrics
from ..output import atomic_dir, write_json
from .plots import plt

_METRICS = (("steady_state_error_pct", "steady-state error [%]", metrics.REQ_ESS_PCT),
            ("t95_s", "t95 [s]", metrics.REQ_T95_S),
            ("overshoot_pct", "overshoot [%]", None),
            ("jerk_max", "max torque rate [N m/s]", None))


def plot_histograms(result: dict[str, Any], path: Path) -> None:
    """Histograms of the launch metrics over a verification run, with the requirement limits."""
    fig, axes = plt.subplots(1, len(_METRICS), figsize=(13, 3.2))
    for ax, (key, label, limit) in zip(axes, _METRICS):
        v = np.array([r["metrics"].get(key) for r in result["results"] if r["metrics"].get(key) is not None], dtype=float)
        v = v[np.isfinite(v)]
        ax.hist(v, bins=40, color="tab:blue", alpha=0.8)
        if limit is not None:
            ax.axvline(limit, color="tab:red", lw=1.5, label="requirement")
            ax.legend(fontsize=7)
        ax.set_xlabel(label, fontsize=9)
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("launches")
    fig.suptitle(f"verify {result['controller']}: {result['cases']} launches, all requirements met in "
                 f"{100 * result['pass_rate']:.1f} %", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def verify_table(result: dict[str, Any]) -> str:
    """Markdown: pass rates, metric percentiles, worst cases."""
    rate = result["pass_rate_per_requirement"]
    lines = [f"**{result['controller']}**: {result['cases']} launches ({result['samples']} random, "
             f"{result['cases'] - result['samples']} corners), seed {result['seed']}",
             "",
             "| requirement | pass rate |", "|---|---|",
             f"| steady-state error <= {metrics.REQ_ESS_PCT:g} % | {100 * rate['steady_state_error']:.1f} % |",
             f"| t95 < {metrics.REQ_T95_S:g} s | {100 * rate['response_time']:.1f} % |",
             f"| robust (t95 within {metrics.ROBUST_DT95:g} s, overshoot at most {metrics.ROBUST_OVERSHOOT:g} points above nominal) "
             f"| {100 * rate['robustness']:.1f} % |",
             f"| **all three** | **{100 * result['pass_rate']:.1f} %** |", "",
             "| metric | p5 | p50 | p95 | p99 | max |", "|---|---|---|---|---|---|"]
    for key, label, _ in _METRICS:
        p = result["percentiles"].get(key) or {}
        if p:
            lines.append(f"| {label} | " + " | ".join(f"{p[q]:.4g}" for q in ("p5", "p50", "p95", "p99", "max")) + " |")
    lines += ["", "Worst cases (replay with the command):", ""]
    for w in result["worst"][:5]:
        m = w["metrics"]
        fails = [k for k, ok in w["requirements"].items() if not ok]
        if not m or m.get("steady_state_error_pct") is None:
            figs = "no steady state"
        else:
            t95 = f"{m['t95_s']:.3f} s" if m.get("t95_s") is not None else "95 % never reached"
            ovs = f"{m['overshoot_pct']:.1f} %" if m.get("overshoot_pct") is not None else "n/a"
            figs = f"ess {m['steady_state_error_pct']:.2f} %, t95 {t95}, overshoot {ovs}"
        lines.append(f"- #{w['index']}: {figs}; fails: {', '.join(fails) or 'none'}  \n  `{w['replay']}`")
    return "\n".join(lines)


def write(result: dict[str, Any], out: str | Path) -> None:
    """``verify.json``, ``verify.md``, ``samples.csv`` and ``histograms.png``, written atomically."""
    with atomic_dir(out) as d:
        write_json(d / "verify.json", result)
        (d / "verify.md").write_text("# Verification\n\n" + verify_table(result) + "\n\n![histograms](histograms.png)\n")
        rows = [{"index": r["index"], "corner": r["corner"], **r["values"], **r["metrics"], **r["requirements"],
                 "all_pass": r["all_pass"]} for r in result["results"]]
        pd.DataFrame(rows).to_csv(d / "samples.csv", index=False)
        plot_histograms(result, d / "histograms.png")
