"""The main job's report: nominal launches, the verification of design and baseline, ``report.md``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..launch import metrics
from ..launch.campaign import MainJob
from ..launch.settings import to_toml
from ..output import atomic_dir, write_json
from . import html
from .design import design_md
from .plots import plot_launch
from .verify import _METRICS, REQUIREMENT_LABELS, bins_table, headline, plot_histograms, verify_table


def same_samples(ver: dict[str, Any], base: dict[str, Any]) -> dict[str, float]:
    """Pass rates of design and baseline on the random samples both ran (the baseline's are a prefix of the
    design's; the corners where neither ran random samples), as the pass rates of a verification count."""
    theirs = [r for r in base["results"] if not r["corner"]] or base["results"]
    common = {r["index"] for r in theirs}
    mine = [r for r in ver["results"] if r["index"] in common]
    n = max(len(mine), 1)
    return {"samples": len(mine), "design": sum(r["all_pass"] for r in mine) / n,
            "baseline": sum(r["all_pass"] for r in theirs) / max(len(theirs), 1)}


def write(job: MainJob, out: str | Path) -> dict[str, Any]:
    """Write the main job's report into ``out`` (atomically); returns the content of ``summary.json``."""
    launches, ver, base = job.launches, job.verify, job.verify_baseline
    keys = ("pass_rate", "pass_rate_interval", "pass_rate_per_requirement",
            "pass_rate_corners", "corners_passed", "corners", "pass_rate_all_cases", "cases", "samples", "percentiles")
    with atomic_dir(out) as d:
        for i, (res, base_res) in enumerate(launches):
            plot_launch(res.signals, res.truth, res.summary, d / f"launch_{i}.png", extra=base_res.signals,
                        extra_label="baseline")
        plot_histograms(ver, d / "verify_launch.png")
        plot_histograms(base, d / "verify_baseline.png")
        write_json(d / "verify_launch.json", ver)
        write_json(d / "verify_baseline.json", base)
        (d / "controller.toml").write_text(to_toml(job.design))
        (d / "baseline.toml").write_text(to_toml(job.baseline))
        summary = {"nominal": [{"design": a.summary, "baseline": b.summary} for a, b in launches],
                   "verify": {k: ver[k] for k in keys}, "verify_baseline": {k: base[k] for k in keys},
                   "same_samples": same_samples(ver, base), "baseline_margins": job.margins,
                   "launch_margins": job.launch_margins}
        write_json(d / "summary.json", summary)
        md = _report_md(job, summary)
        (d / "report.md").write_text(md)
        html.write_main(d / "report.html", md, job, _METRICS)
    return summary


def _margins_md(rows: list[dict[str, Any]]) -> str:
    """Markdown: the smallest gain and phase margins of the baseline's PI loop over the corners, and where."""
    if not rows:
        return "(no corner ranges)"
    g = min(rows, key=lambda r: r["gain_margin"])
    p = min(rows, key=lambda r: r["phase_margin_deg"])
    where = lambda r: ", ".join(f"{k} {v:g}" for k, v in r["corner"].items())  # noqa: E731
    return ("The linearised loop (`wetclutch.launch.margins`: a first-order-plus-dead-time fit of the axle torque "
            "per volt on each corner plant through the design's map, the PI, a third-order Pade dead time) keeps a "
            f"gain margin of at least **{g['gain_margin']:.2f}** (at {where(g)}) and a phase margin of at least "
            f"**{p['phase_margin_deg']:.0f} deg** (at {where(p)}) over the {len(rows)} corners. What fails in the "
            "verification therefore fails in the nonlinear parts the linear loop leaves out (fill, kiss point, "
            "valve play), not by instability of the torque loop.")


def _launch_margins_md(rows: list[dict[str, Any]]) -> str:
    """Markdown: the launch controller's loop margins over the loop's corners, the smallest and where, and the
    corners whose driveline is unstable by itself (friction falling with slip: judder no pressure loop damps)."""
    if not rows:
        return "(no corner ranges)"
    where = lambda r: ", ".join(f"{k} {v:g}" for k, v in r["corner"].items())  # noqa: E731
    judder = [r for r in rows if r["damping"] <= 0.0]
    stable = [r for r in rows if r["damping"] > 0.0]
    text = ("The torque loop of the launch controller linearised about the launch's start (`wetclutch.launch.margins`: "
            "the valve's pressure path as a first-order-plus-dead-time fit on each corner plant, the clutch output's "
            "resonance on the axle seen through the ratio with the friction curve's damping, the friction-factor "
            "estimate and the torque integrator)")
    if stable:
        g = min(stable, key=lambda r: r["gain_margin"])
        p = min(stable, key=lambda r: r["phase_margin_deg"])
        text += (f" keeps a gain margin of at least **{g['gain_margin']:.2f}** (at {where(g)}; resonance "
                 f"{g['resonance_hz']:.1f} Hz, damping ratio {g['damping']:.2f}) and a phase margin of at least "
                 f"**{p['phase_margin_deg']:.0f} deg** (at {where(p)}) over {len(stable)} of the {len(rows)} corners.")
    if judder:
        w = min(judder, key=lambda r: r["damping"])
        text += (f" At {len(judder)} corners the driveline is unstable by itself: friction falling with slip outweighs "
                 f"the axle damping (damping ratio down to {w['damping']:.2f}, at {where(w)}); there the launch "
                 "judders whatever the torque loop does, until the slip has fallen below the friction curve's peak.")
    return text


def _fmt(v: Any, f: str) -> str:
    return "-" if v is None else format(v, f)


def _report_md(job: MainJob, summary: dict[str, Any]) -> str:
    ver, base, same = job.verify, job.verify_baseline, summary["same_samples"]
    ok = lambda b: "pass" if b else "**FAIL**"  # noqa: E731
    varied = ", ".join(f"{r['name']} ({r['low']:g}..{r['high']:g}{' x' if r['how'] == 'rel' else ''}"
                       f"{' offset' if r['how'] == 'offset' else ''}{' ' + r['unit'] if r['unit'] else ''})"
                       for r in ver["ranges"])
    lines = [
        "# wetclutch: torque control of a launch from standstill",
        "",
        "Requirements, on the measured axle torque `T_r`: " + "; ".join(REQUIREMENT_LABELS[k] for k in metrics.REQUIREMENTS)
        + ". The response time judged is the settled one (the last entry into the band above 95 % of the steady "
        "value before the steady window begins); the first crossing of 95 % is reported beside it. Metric "
        "definitions: `wetclutch.launch.metrics`.",
        "",
        f"**Verdict.** Over clutches that vary around this one ({varied}), each launched "
        f"{ver['sequence']} time(s) with the controller's adaptation carried over and judged on the last launch, the launch "
        f"controller meets every requirement in **{headline(ver)}** (the corners: every combination of the corner "
        f"ranges' extremes); {100 * ver['pass_rate_reachable']:.1f} % of the random clutches that some controller "
        "can pass (without those whose request is beyond the clutch's capacity or whose open plates' drag alone "
        "creeps beyond the limit). On the same "
        f"{same['samples']} samples it meets them in {100 * same['design']:.1f} %, "
        "the baseline (timed fill, "
        f"kiss-point hold, PI with anti-windup tuned by the SIMC rule on this plant) in {100 * same['baseline']:.1f} %.",
        "",
        "## Nominal launches",
        "",
        "| oil C | request N m | controller | ess % | t95 s | t95 settled s | overshoot % | ripple % | creep N m | "
        "t_sync s | " + " | ".join(metrics.REQUIREMENTS) + " |",
        "|---|---|---|---|---|---|---|---|---|---|" + "---|" * len(metrics.REQUIREMENTS),
    ]
    for a, b in job.launches:
        for res in (a, b):
            s = res.summary
            r = s["requirements"]
            lines.append(f"| {s['oil_temp_C']:g} | {s['t_ref_Nm']:g} | {s['controller']} | "
                         f"{_fmt(s['steady_state_error_pct'], '.2f')} | {_fmt(s['t95_s'], '.3f')} | "
                         f"{_fmt(s['t95_settled_s'], '.3f')} | {_fmt(s['overshoot_pct'], '.1f')} | "
                         f"{_fmt(s['ripple_pct'], '.1f')} | {_fmt(s['creep_Nm'], '.1f')} | {_fmt(s['t_sync_s'], '.2f')} | "
                         + " | ".join(ok(r[k]) for k in metrics.REQUIREMENTS) + " |")
    lines += ["", "![launch at 41 C, 100 N m](launch_1.png)", "",
              "## Verification: launch controller", "", verify_table(ver), "",
              "### Where it fails: pass rate per range bin", "", bins_table(ver), "",
              "![histograms](verify_launch.png)", "",
              "## Verification: baseline", "", verify_table(base), "", "![histograms](verify_baseline.png)", "",
              "### Loop margins over the corner plants", "", "Launch controller: " + _launch_margins_md(job.launch_margins),
              "", "Baseline: " + _margins_md(job.margins), "",
              "## The designs", "", design_md(job.design), design_md(job.baseline),
              "The controllers are in `controller.toml` and `baseline.toml` (`wetclutch launch --controller-file`).", ""]
    return "\n".join(lines)
