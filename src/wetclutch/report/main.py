"""The main job's report: nominal launches, the verification of design and baseline, ``report.md``."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ..launch import metrics
from ..launch.campaign import MainJob
from ..launch.settings import to_toml
from ..output import atomic_dir, write_json
from . import html
from .design import design_md
from .plots import plot_launch
from .text import demote, plural, times
from .verify import (REQUIREMENT_LABELS, bins_table, headline, metric_specs, plant_named, plot_histograms,
                     verify_table)


def same_samples(ver: dict[str, Any], base: dict[str, Any]) -> dict[str, float]:
    """Pass rates of design and baseline on the random samples both ran (the baseline's are a prefix of the
    design's; the corners where neither ran random samples), as the pass rates of a verification count."""
    theirs = [r for r in base["results"] if not r["corner"]] or base["results"]
    common = {r["index"] for r in theirs}
    mine = [r for r in ver["results"] if r["index"] in common]
    n = max(len(mine), 1)
    return {"samples": len(mine), "design": sum(r["all_pass"] for r in mine) / n,
            "baseline": sum(r["all_pass"] for r in theirs) / max(len(theirs), 1)}


def write(job: MainJob, out: str | Path, plant_file: str | Path | None = None,
          plant_changes: Sequence[str] = ()) -> dict[str, Any]:
    """Write the main job's report into ``out`` (atomically).

    Parameters
    ----------
    job
        The main job's results.
    out
        The output directory.
    plant_file
        The parameter file the plant was read from (None: none given, or not known to the caller).
    plant_changes
        The ``--set`` changes made to it (``"path=value"``).

    Returns
    -------
    dict
        The content of ``summary.json``.
    """
    launches, ver, base = job.launches, job.verify, job.verify_baseline
    keys = ("pass_rate", "pass_rate_interval", "pass_rate_per_requirement",
            "pass_rate_corners", "corners_passed", "corners", "pass_rate_all_cases", "cases", "samples", "percentiles")
    with atomic_dir(out) as d:
        for i, (res, base_res) in enumerate(launches):
            plot_launch(res.signals, res.truth, res.summary, d / f"launch_{i}.png", extra=base_res.signals,
                        extra_label="baseline", extra_summary=base_res.summary)
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
        md = _report_md(job, summary, plant_md(job, plant_file, plant_changes))
        (d / "report.md").write_text(md)
        html.write_main(d / "report.html", md, job, metric_specs(ver))
    return summary


def _where(r: dict[str, Any]) -> str:
    return ", ".join(f"{k} {v:g}" for k, v in r["corner"].items())


def _unstable(r: dict[str, Any]) -> bool:
    """Whether a corner's linearised closed loop is unstable: a gain margin below 1 (the loop gain already beyond the
    critical one) or a phase margin below zero."""
    return r["gain_margin"] < 1.0 or r["phase_margin_deg"] < 0.0


def _shared(rows: list[dict[str, Any]]) -> str:
    """What every one of ``rows`` has in common: the corner values they share (empty if none)."""
    first = rows[0]["corner"]
    common = {k: v for k, v in first.items() if all(r["corner"].get(k) == v for r in rows)}
    return ", ".join(f"{k} {v:g}" for k, v in common.items())


def _unstable_md(bad: list[dict[str, Any]], total: int) -> str:
    """A sentence: at how many of ``total`` corners the linearised loop is unstable, what those share and the
    smallest margins there."""
    if not bad:
        return ""
    g = min(bad, key=lambda r: r["gain_margin"])
    if len(bad) == 1:
        where = f", at {_where(bad[0])}"
    else:
        common = _shared(bad)
        where = f", all of them at {common}" if common else ""
    return (f" At {len(bad)} of the {plural(total, 'corner')} the linearised loop is **unstable** (gain margin below 1 "
            f"or phase margin below 0 deg){where}; the gain margin falls to {g['gain_margin']:.2f} there (at "
            f"{_where(g)}).")


def _margins_md(rows: list[dict[str, Any]]) -> str:
    """Markdown: the smallest gain and phase margins of the baseline's PI loop over the corners, and where; the
    corners where the linearised loop is unstable; the conclusion that failures are nonlinear only where every
    corner's loop is stable."""
    if not rows:
        return "(no corner ranges)"
    g = min(rows, key=lambda r: r["gain_margin"])
    p = min(rows, key=lambda r: r["phase_margin_deg"])
    bad = [r for r in rows if _unstable(r)]
    text = ("The linearised loop (`wetclutch.launch.margins`: a first-order-plus-dead-time fit of the axle torque "
            "per volt on each corner plant through the design's map, the PI, a third-order Pade dead time) has its "
            f"smallest gain margin, **{g['gain_margin']:.2f}**, at {_where(g)} and its smallest phase margin, "
            f"**{p['phase_margin_deg']:.0f} deg**, at {_where(p)}, over the {plural(len(rows), 'corner')}.")
    if bad:
        return (text + _unstable_md(bad, len(rows)) + " Failures of the verification there may be the torque loop's "
                "instability, not only the nonlinear parts the linear loop leaves out (fill, kiss point, valve play).")
    return (text + " The loop is stable at every corner: what fails in the verification therefore fails in the "
            "nonlinear parts the linear loop leaves out (fill, kiss point, valve play), not by instability of the "
            "torque loop.")


def _launch_margins_md(rows: list[dict[str, Any]]) -> str:
    """Markdown: the launch controller's loop margins over the loop's corners, the smallest and where, the corners
    whose linearised loop is unstable, and the corners whose driveline is unstable by itself (friction falling with
    slip: judder no pressure loop damps)."""
    if not rows:
        return "(no corner ranges)"
    judder = [r for r in rows if r["damping"] <= 0.0]
    stable = [r for r in rows if r["damping"] > 0.0]
    text = ("The torque loop of the launch controller linearised about the launch's start (`wetclutch.launch.margins`: "
            "the valve's pressure path as a first-order-plus-dead-time fit on each corner plant, the clutch output's "
            "resonance on the axle seen through the ratio with the friction curve's damping, the friction-factor "
            "estimate and the torque integrator), at each of its "
            f"{len(rows)} corners: every combination of the extremes of the ranges that enter that model "
            f"({', '.join(rows[0]['corner'])}), the other ranges at their nominal values; these are not the "
            "verification's corners")
    if stable:
        g = min(stable, key=lambda r: r["gain_margin"])
        p = min(stable, key=lambda r: r["phase_margin_deg"])
        bad = [r for r in stable if _unstable(r)]
        text += (f", over the {plural(len(stable), 'corner')} of the {len(rows)} whose driveline is damped, has its "
                 f"smallest gain margin, **{g['gain_margin']:.2f}**, at {_where(g)} (resonance "
                 f"{g['resonance_hz']:.1f} Hz, damping ratio {g['damping']:.2f}) and its smallest phase margin, "
                 f"**{p['phase_margin_deg']:.0f} deg**, at {_where(p)}.")
        text += (_unstable_md(bad, len(rows)) if bad else
                 (" The loop is stable at that corner." if len(stable) == 1 else
                  f" The loop is stable at every one of these {len(stable)} corners."))
    else:
        text += " has no corner whose driveline is damped."
    if judder:
        w = min(judder, key=lambda r: r["damping"])
        text += (f" At {plural(len(judder), 'corner')} the driveline is unstable by itself: friction falling with slip "
                 f"outweighs the axle damping (damping ratio down to {w['damping']:.2f}, at {_where(w)}); there the "
                 "launch judders whatever the torque loop does, until the slip has fallen below the friction curve's "
                 "peak.")
    return text


def _fmt(v: Any, f: str) -> str:
    return "-" if v is None else format(v, f)


def plant_md(job: MainJob, plant_file: str | Path | None, changes: Sequence[str] = ()) -> str:
    """Markdown, one paragraph: the plant the report is about, and whether the controllers were designed on it.

    Parameters
    ----------
    job
        The main job (its plant and designs).
    plant_file
        The parameter file the plant was read from, if known.
    changes
        The ``--set`` changes made to it.

    Returns
    -------
    str
        The parameter file (and changes) named; without a file, whether the plant is the default one.
    """
    what = plant_named(job.plant, plant_file, changes)
    own = [name for name, d in (("launch", job.design), ("baseline", job.baseline)) if d.plant == job.plant]
    other = [name for name, d in (("launch", job.design), ("baseline", job.baseline)) if d.plant != job.plant]
    text = f"**Plant.** Launches and verifications run on {what}."
    if own:
        text += (f" The {' and '.join(own)} controller{'s were' if len(own) > 1 else ' was'} designed on it (its "
                 "parameters: the `[plant]` section of "
                 + " and ".join(f"`{'controller' if n == 'launch' else 'baseline'}.toml`" for n in own) + ").")
    if other:
        text += (f" The {' and '.join(other)} controller{'s were' if len(other) > 1 else ' was'} designed on another "
                 "plant (the `[plant]` section of "
                 + " and ".join(f"`{'controller' if n == 'launch' else 'baseline'}.toml`" for n in other) + ").")
    return text


def _first_launch_md(ver: dict[str, Any]) -> str:
    """A sentence: the pass rate of a sequence's first launch, before any adaptation, and the launches that slammed."""
    corners = [r for r in ver["results"] if r["corner"]]
    text = (f"On the first launch of each clutch, before any adaptation, it meets them in "
            f"{100 * ver['pass_rate_first_launch']:.1f} % of the random clutches")
    if corners:
        text += f" (corners {sum(bool(r['first_all_pass']) for r in corners)} of {len(corners)})"
    launches = ver["sequence"] * len(ver["results"])
    return text + f"; {ver['slams']} of all {launches} launches slammed (see below)."


def _designed_on(d: Any, job: MainJob) -> str:
    """Which plant a controller was designed on, as the verdict says it: this one or another."""
    return "this plant" if d.plant == job.plant else "another plant"


def _launch_title(summary: dict[str, Any]) -> str:
    """A nominal launch's conditions: ``"41 C, 100 N m"``."""
    return f"{summary['oil_temp_C']:g} C, {summary['t_ref_Nm']:g} N m"


def _report_md(job: MainJob, summary: dict[str, Any], plant: str = "") -> str:
    ver, base, same = job.verify, job.verify_baseline, summary["same_samples"]
    ok = lambda b: "pass" if b else "**FAIL**"  # noqa: E731
    varied = ", ".join(f"{r['name']} ({r['low']:g}..{r['high']:g}{' x' if r['how'] == 'rel' else ''}"
                       f"{' offset' if r['how'] == 'offset' else ''}{' ' + r['unit'] if r['unit'] else ''})"
                       for r in ver["ranges"])
    lines = [
        "# wetclutch: torque control of a launch from standstill",
        "",
        *([plant, ""] if plant else []),
        "Requirements, on the measured axle torque `T_r`: " + "; ".join(REQUIREMENT_LABELS[k] for k in metrics.REQUIREMENTS)
        + ". The response time judged is the settled one (the last entry into the band above 95 % of the steady "
        "value before the steady window begins); the first crossing of 95 % is reported beside it. Metric "
        "definitions: `wetclutch.launch.metrics`.",
        "",
        f"**Verdict.** Over clutches that vary around this one ({varied}), "
        + (f"each launched {times(ver['sequence'])} with the controller's adaptation carried over and judged on the "
           "last launch, " if ver["sequence"] > 1 else "each launched once, ")
        + f"the launch controller meets every requirement in **{headline(ver)}** (the corners: every combination of "
        f"the corner ranges' extremes); {100 * ver['pass_rate_reachable']:.1f} % of the random clutches that some controller "
        "can pass (without those whose request is beyond the clutch's capacity, whose open plates' drag alone "
        "creeps beyond the limit, or whose fill the valve wide open does not complete within the response time "
        "after the request). " + (_first_launch_md(ver) + " " if ver["sequence"] > 1 else "") + "On the same "
        f"{plural(same['samples'], 'sample')} it meets them in {100 * same['design']:.1f} %, "
        "the baseline (timed fill, "
        # a baseline file designed on another plant was not tuned on this one: the mismatch is what is verified
        f"kiss-point hold, PI with anti-windup tuned by the SIMC rule on {_designed_on(job.baseline, job)}) in "
        f"{100 * same['baseline']:.1f} %.",
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
    # the launch shown, named by its own conditions (the caption is the HTML's alt text too)
    shown = f"![launch at {_launch_title(job.launches[1][0].summary)}](launch_1.png)" if len(job.launches) > 1 else ""
    lines += ["", *([shown, ""] if shown else []),
              "## Verification: launch controller", "", verify_table(ver), "",
              "### Where it fails: pass rate per range bin", "", bins_table(ver), "",
              "![histograms](verify_launch.png)", "",
              "## Verification: baseline", "", verify_table(base), "", "![histograms](verify_baseline.png)", "",
              "## Loop margins over the corner plants", "",
              "Launch controller: " + _launch_margins_md(job.launch_margins), "", "Baseline: " + _margins_md(job.margins), "",
              "## The designs", "", demote(design_md(job.design, "controller.toml"), 2),
              demote(design_md(job.baseline, "baseline.toml"), 2),
              "The controllers are in `controller.toml` and `baseline.toml` (`wetclutch launch --controller-file`).", ""]
    return "\n".join(lines)
