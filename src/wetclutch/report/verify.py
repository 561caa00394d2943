"""A verification run written out: ``verify.json``, ``verify.md``, ``samples.csv`` and histograms."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from ..launch import metrics, verify
from ..launch.design import Design
from ..launch.settings import to_toml
from ..output import atomic_dir, write_json
from ..params import Params
from . import html
from .plots import plt
from .text import plural, times

_METRICS = (("steady_state_error_pct", "steady-state error [%]", metrics.REQ_ESS_PCT),
            ("t95_settled_s", "t95, settled [s]", metrics.REQ_T95_S),
            ("overshoot_pct", "overshoot [%]", None),
            ("ripple_pct", "ripple [%]", metrics.REQ_RIPPLE_PCT),
            ("oscillation_pct", "oscillation [%]", None),
            ("creep_Nm", "creep before request [N m]", metrics.REQ_CREEP_NM))
#: how each requirement reads in a table
REQUIREMENT_LABELS = {
    "steady_state_error": f"steady-state error <= {metrics.REQ_ESS_PCT:g} %",
    "response_time": f"t95 (settled) < {metrics.REQ_T95_S:g} s",
    "robustness": (f"robust: t95 at most {metrics.ROBUST_DT95:g} s later and overshoot at most "
                   f"{metrics.ROBUST_OVERSHOOT:g} points above the nominal's, ripple <= {metrics.REQ_RIPPLE_PCT:g} %"),
    "standby": f"creep before the request <= {metrics.REQ_CREEP_NM:g} N m",
}


#: figures only a launch run to lock-up has (``--through-lockup``): shown when the run has them
_LOCKUP_METRICS = (("t_sync_s", "lock-up time t_sync [s]", None),
                   ("slip_energy_J", "slip energy [J]", None))
_QUANTILES = ("p5", "p50", "p95", "p99", "max")


def metric_specs(result: dict[str, Any]) -> tuple[tuple[str, str, float | None], ...]:
    """The metrics a verification's report shows: ``(key, label, requirement limit or None)``.

    Parameters
    ----------
    result
        A verification (:func:`wetclutch.launch.verify.run`).

    Returns
    -------
    tuple
        The launch metrics, and the lock-up time and slip energy where any launch has them (a run to lock-up).
    """
    extra = tuple(spec for spec in _LOCKUP_METRICS
                  if any(r["metrics"].get(spec[0]) is not None for r in result["results"]))
    return _METRICS + extra


def plot_histograms(result: dict[str, Any], path: Path) -> None:
    """Histograms of the launch metrics over a verification run, with the requirement limits: the random samples
    and the corners stacked, each in its own colour."""
    specs = metric_specs(result)
    fig, axes = plt.subplots(1, len(specs), figsize=(2.5 * len(specs), 3.2))
    parts = [(rows, lab, c) for rows, lab, c in ((_random(result), "random", "tab:blue"),
                                                 (_corners(result), "corners", "tab:orange")) if rows]
    for ax, (key, label, limit) in zip(axes, specs):
        vs = [verify.metric_values(rows, key) for rows, _, _ in parts]
        if any(v.size for v in vs):
            ax.hist(vs, bins=40, stacked=True, color=[c for _, _, c in parts], label=[lab for _, lab, _ in parts],
                    alpha=0.8)
        if limit is not None:
            ax.axvline(limit, color="tab:red", lw=1.5, label="requirement")
        ax.legend(fontsize=7)
        ax.set_xlabel(label, fontsize=9)
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("cases")
    fig.suptitle(f"verify {result['controller']}: all requirements met in {headline(result)}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _pct(v: float | None) -> str:
    return "-" if v is None or v != v else f"{100 * v:.1f} %"


def _random(result: dict[str, Any]) -> list[dict[str, Any]]:
    return [r for r in result["results"] if not r["corner"]]


def _corners(result: dict[str, Any]) -> list[dict[str, Any]]:
    return [r for r in result["results"] if r["corner"]]


def headline(result: dict[str, Any], detail: str = "") -> str:
    """One line: the pass rate of the random samples with its 95 % interval (and ``detail`` beside it), and the
    corners that pass."""
    n, k = result["samples"], result.get("corners", 0)
    ci = result.get("pass_rate_interval")
    inside = [f"95 % interval {100 * ci[0]:.1f}-{100 * ci[1]:.1f} %"] if n and ci is not None else []
    inside += [detail] if detail else []
    what = plural(n, "random clutch", "random clutches") if n else plural(k, "corner")
    text = f"{100 * result['pass_rate']:.1f} % of {what}"
    text += f" ({'; '.join(inside)})" if inside else ""
    if n and k:
        text += f"; corners {result['corners_passed']} of {k}"
    return text


def sequence_md(result: dict[str, Any]) -> str:
    """Markdown, one paragraph: how often each clutch was launched and which launch is judged, the first launch's
    pass rate beside it (with a sequence), and the launches that slammed.

    Parameters
    ----------
    result
        A verification (:func:`wetclutch.launch.verify.run`).

    Returns
    -------
    str
        The paragraph.
    """
    seq = result.get("sequence", 1)
    rand, corners = _random(result), _corners(result)
    launches = seq * len(result["results"])
    if seq > 1 and result.get("controller") == "baseline":
        # the baseline learns nothing: its launches of a clutch differ in their noise seeds only, and a sentence of
        # adaptation would credit it with one
        text = (f"Each clutch was launched {times(seq)} in a row; the baseline has no adaptation to carry over, so its "
                "launches of a clutch differ in their sensor noise only. The pass rates and metrics below are those of "
                f"the last launch. On the first launch {_pct(result['pass_rate_first_launch'])} of the random "
                "clutches met every requirement")
    elif seq > 1:
        text = (f"Each clutch was launched {times(seq)} in a row, the controller's adaptation carried over from launch "
                "to launch; the pass rates and metrics below are those of the last launch. On the first "
                f"launch, before any adaptation, {_pct(result['pass_rate_first_launch'])} of the random clutches "
                "met every requirement")
    if seq > 1:
        if corners:
            first = sum(bool(r["first_all_pass"]) for r in corners)
            text += f" (corners {first} of {len(corners)})"
        text += f" against {_pct(result['pass_rate'])} on the last. "
    else:
        text = "Each clutch was launched once. "
    slams = result["slams"]
    text += (f"Launches that slammed (torque peak above {verify.SLAM_FACTOR:g} times the steady value, an overshoot "
             f"above {100 * (verify.SLAM_FACTOR - 1):g} %): {slams} of the {launches}")
    if slams and rand and corners:
        text += (f" ({sum(r['slams'] for r in rand)} of the random clutches' launches, "
                 f"{sum(r['slams'] for r in corners)} of the corners')")
    return text + "."


def _percentile_rows(pct: dict[str, dict[str, float]], specs: Any) -> list[str]:
    """Table rows: each metric's count of cases with a value and its percentiles (``pct``, as the verification
    gives)."""
    out = []
    for key, label, _ in specs:
        p = pct.get(key, {})
        if p.get("n"):
            out.append(f"| {label} | {p['n']} | " + " | ".join(f"{p[q]:.4g}" for q in _QUANTILES) + " |")
        else:
            out.append(f"| {label} | 0 | " + " | ".join("-" for _ in _QUANTILES) + " |")
    return out


def percentiles_md(result: dict[str, Any]) -> str:
    """Markdown: the metric percentiles over the random samples (the population the pass rates estimate), and
    those of the corners apart (the worst-case set beside it, no draw of the ranges).

    Parameters
    ----------
    result
        A verification (:func:`wetclutch.launch.verify.run`).

    Returns
    -------
    str
        One table per set of launches that the run holds, each saying what it is over.
    """
    specs = metric_specs(result)
    # a case is a clutch judged on its last launch (with a sequence, one of several launches)
    head = ["| metric | cases with a value | p5 | p50 | p95 | p99 | max |", "|---|---|---|---|---|---|---|"]
    lines: list[str] = []
    for count, pct, what, why in (
            (result["cases"] - result["corners"], result["percentiles"], ("random clutch", "random clutches"),
             "the population the pass rates above estimate"),
            (result["corners"], result["percentiles_corners"], ("corner", "corners"),
             "every combination of the corner ranges' extremes, apart from the random clutches")):
        if not count:
            continue
        lines += [f"Metrics over the {plural(count, *what)} ({why}):",
                  "", *head, *_percentile_rows(pct, specs), ""]
    return "\n".join(lines).rstrip("\n")


def nominal_md(result: dict[str, Any]) -> list[str]:
    """Markdown lines: the request levels whose nominal launch did not settle and the level whose response the
    robustness requirement took there instead (none: every nominal launch settled)."""
    nom = result.get("nominal") or {}
    moved = [(a, b) for a, b in zip(nom.get("request_Nm", []), nom.get("taken_from_Nm", [])) if a != b]
    if not moved:
        return []
    where = "; ".join(f"at {a:g} N m that of {b:g} N m" for a, b in moved)
    return [f"The design's nominal launch on its own clutch does not settle at every request level (it synchronises "
            "before the judged window, as with a light primary flywheel or an overdrive CVT ratio, or the request is "
            "beyond that clutch's capacity): the robustness requirement compares with the nominal response of the "
            f"nearest level that settles, {where}.", ""]


def verify_table(result: dict[str, Any]) -> str:
    """Markdown: pass rates, the launches per clutch, metric percentiles (random samples and corners apart), worst
    cases."""
    rate = result["pass_rate_per_requirement"]
    cases = plural(result['cases'], 'clutch', 'clutches')
    lines = [f"**{result['controller']}**: {cases} ({result['samples']} random, "
             f"{plural(result['cases'] - result['samples'], 'corner')}), seed {result['seed']}; all requirements met "
             f"in {headline(result)}. The pass rates below are the random samples' (an estimate of the share of the "
             "ranges' clutches that pass); the corners, every combination of the corner ranges' extremes, are the "
             f"worst case beside them ({_pct(result['pass_rate_all_cases'])} of all cases together).",
             "", sequence_md(result), "",
             "| requirement | pass rate |", "|---|---|"]
    lines += [f"| {REQUIREMENT_LABELS[k]} | {_pct(rate.get(k))} |" for k in metrics.REQUIREMENTS]
    lines += [f"| **all** | **{_pct(result['pass_rate'])}** |", ""]
    lines += nominal_md(result)
    if result.get("horizon_s") is not None:
        lines += [f"Each launch ran to {result['horizon_s']:g} s after the request, past the window the requirements "
                  "judge, not to lock-up: lock-up times and slip energies are not part of this run "
                  "(`--through-lockup` runs each launch to lock-up; the verdicts are the same).", ""]
    failed = [r for r in result["results"] if not r["all_pass"]]
    if failed:
        n_rand = sum(1 for r in failed if not r["corner"])
        verb = "fails" if len(failed) == 1 else "fail"
        # each row is a clutch judged on its last launch: with a sequence, "launches" would count a third of them
        what = (plural(len(failed), "clutch", "clutches") + f" that {verb} on the last launch"
                if result.get("sequence", 1) > 1 else f"{plural(len(failed), 'launch', 'launches')} that {verb}")
        lines += [f"Of the {what} ({n_rand} of the random clutches, "
                  f"{len(failed) - n_rand} of the corners), {result['failures_unfilled']} had the plates touch only "
                  "after the request: the fill was not complete when torque was asked for, and the response time "
                  f"counts the rest of it ({result['failures_fill_too_slow']} of them would not have been filled in "
                  "time with the valve wide open from the start either: no controller fills those before the "
                  f"request, and {result['failures_fill_after_response']} not within the response time after it: "
                  "no controller answers those in time); "
                  f"{result['failures_at_capacity']} had the valve input at the top of its range and the torque "
                  f"short of the request in at least {verify.CAPACITY_SHARE:g} % of the judged window: the "
                  "controller asked for all the valve gives, the clutch at or beyond its capacity there (supply "
                  f"pressure, friction, CVT ratio, request), and for {result['failures_beyond_capacity']} of "
                  "them no torque that the plates carry at the valve's highest static pressure, along the launch's "
                  "slip, meets both the steady-state error and the ripple over the judged window: no controller "
                  "passes those; "
                  f"{result['failures_creep_of_the_drag']} crept beyond {metrics.REQ_CREEP_NM:g} N m where the open "
                  "plates' oil drag alone, with the valve input at the bottom of its range from the start, pushes "
                  "the waiting vehicle as hard: no controller holds those within the limit. Without the random "
                  "clutches that fail whatever the controller (those beyond the capacity, creeping by the drag or "
                  "not filled within the response time), "
                  f"{_pct(result['pass_rate_reachable'])} pass.", ""]
    if result["samples"]:
        lines += [f"Of the {plural(result['samples'], 'random clutch', 'random clutches')}, {result['rippling']} "
                  f"{'has' if result['rippling'] == 1 else 'have'} a ripple above "
                  f"{metrics.REQ_RIPPLE_PCT:g} % of {'its' if result['rippling'] == 1 else 'their'} torque over the "
                  f"judged window, {result['oscillating']} of "
                  "them an oscillation (the ripple about the torque's straight line: what oscillates rather than "
                  "drifts) above it.", ""]
    lines += [percentiles_md(result)]
    lines += ["", "Worst cases (replay with the command):", ""]
    corner_of = {r["index"]: r["corner"] for r in result["results"]}
    for w in result["worst"][:5]:
        m = w["metrics"]
        fails = [k for k, ok in w["requirements"].items() if not ok]
        if not m or m.get("steady_state_error_pct") is None:
            figs = "no steady state"
        else:
            t95 = f"{m['t95_settled_s']:.3f} s" if m.get("t95_settled_s") is not None else "95 % never reached"
            ovs = f"{m['overshoot_pct']:.1f} %" if m.get("overshoot_pct") is not None else "n/a"
            # the response time judged is the settled t95, not the first crossing the nominal table shows beside it
            figs = (f"ess {m['steady_state_error_pct']:.2f} %, t95 (settled) {t95}, overshoot {ovs}, "
                    f"ripple {m['ripple_pct']:.1f} %, creep {m['creep_Nm']:.1f} N m")
            if (m.get("contact_s") or 0.0) > 0.0:
                figs += f", plates touched {m['contact_s']:.3f} s after the request"
            if (m.get("input_at_max_pct") or 0.0) >= verify.CAPACITY_SHARE:
                figs += (f", valve input at the top of its range, the torque short, in {m['input_at_max_pct']:.0f} % "
                         "of the window")
            if m.get("t_sync_s") is not None:
                figs += f", lock-up {m['t_sync_s']:.2f} s"
            if m.get("slip_energy_J") is not None:
                figs += f", slip energy {m['slip_energy_J']:.0f} J"
        # a corner is no draw of the ranges: say which set the case belongs to, as the tables above keep them apart
        kind = {True: " (corner)", False: " (random)"}.get(corner_of.get(w["index"]), "")
        lines.append(f"- #{w['index']}{kind}: {figs}; fails: {', '.join(fails) or 'none'}  \n  `{w['replay']}`")
    return "\n".join(lines)


def _edge(v: float) -> str:
    """A bin edge: four significant digits, but a large one (a pressure offset in Pa) in full, as the ranges are
    written elsewhere in the reports (``-30000``, not ``-3e+04``)."""
    text = f"{v:.4g}"
    return f"{v:.0f}" if "e+" in text else text


def bins_table(result: dict[str, Any]) -> str:
    """Markdown: the pass rate of all requirements in each bin of each range (random samples; with a sequence, of
    the last launch and of the first, the one right after a change, apart), and what fails most in the worst
    bin."""
    seq = result.get("sequence", 1) > 1
    lines = [f"Each cell: the bin, the pass rate {'of the last launch / of the first launch ' if seq else ''}and the "
             "samples in it.", "",
             "| range | varies | " + " | ".join(f"bin {i + 1}" for i in range(4)) + " | fails most in the worst bin |",
             "|---|---|" + "---|" * 4 + "---|"]
    if result.get("ranges_limited"):
        lines[:0] = ["Ranges limited to what this plant can physically take: " + "; ".join(result["ranges_limited"])
                     + ".", ""]
    for rg in result["ranges"]:
        table = result["bins"][rg["name"]]
        how = {"abs": "", "rel": " x", "offset": " +"}[rg["how"]]
        unit = f" {rg['unit']}" if rg["unit"] else ""
        cells = [f"{_edge(t['low'])}..{_edge(t['high'])}: {_pct(t['pass_rate'].get('all'))}"
                 + (f" / {_pct(t['pass_rate_first_launch'])}" if seq else "") + f" ({t['samples']})" for t in table]
        worst = min((t for t in table if t["samples"]), key=lambda t: t["pass_rate"]["all"], default=None)
        fails = ""
        if worst is not None and worst["pass_rate"]["all"] < 1.0:
            k = min(metrics.REQUIREMENTS, key=lambda r: worst["pass_rate"][r])
            fails = f"{k} ({_pct(worst['pass_rate'][k])} pass)"
        lines.append(f"| {rg['name']} | {rg['target']}{how}{unit} | " + " | ".join(cells) + f" | {fails or 'none'} |")
    return "\n".join(lines)


def value_column(rg: dict[str, Any]) -> str:
    """The ``samples.csv`` column of range ``rg`` (as in ``verify.json``), named with what its values are: a factor
    on the plant's value (``fill_volume_factor``), an offset (``kiss_point_offset_Pa``) or a value in its unit
    (``oil_temp_C``, ``request_Nm``); a value without a unit keeps the range's name."""
    unit = rg.get("unit", "").replace(" ", "")
    if rg["how"] == "rel":
        return f"{rg['name']}_factor"
    if rg["how"] == "offset":
        return f"{rg['name']}_offset" + (f"_{unit}" if unit not in ("", "-") else "")
    return rg["name"] + (f"_{unit}" if unit not in ("", "-") else "")


def plant_named(plant: Params, plant_file: str | Path | None, changes: Sequence[str] = ()) -> str:
    """Where a plant came from, as a report names it: its parameter file (and ``--set`` changes), or whether it is the
    default one."""
    sets = f", with {', '.join(f'`{c}`' for c in changes)}" if changes else ""
    if plant_file is not None:
        return f"the parameter file `{plant_file}`{sets}"
    if changes:
        return f"the default parameters{sets}"
    return "the default parameters" if plant == Params() else "a plant other than the defaults"


def write(result: dict[str, Any], out: str | Path, design: Design, plant: Params | None = None,
          plant_file: str | Path | None = None, changes: Sequence[str] = ()) -> None:
    """``verify.json``, ``verify.md``, ``samples.csv``, ``histograms.png`` and the verified ``controller.toml``
    (which the replay commands name), written atomically.

    Parameters
    ----------
    result
        What :func:`wetclutch.launch.verify.run` returned.
    design
        The controller verified.
    plant, plant_file, changes
        The plant the ranges varied around (default the design's), the parameter file it was read from and the
        ``--set`` changes made to it: ``verify.md`` names them, and whether the controller was designed on it.
    """
    plant = design.plant if plant is None else plant
    own = ("designed on it" if design.plant == plant
           else "designed on another plant (the `[plant]` section of `controller.toml`)")
    head = (f"**Plant.** The ranges vary around {plant_named(plant, plant_file, changes)}; the {design.kind} "
            f"controller verified was {own}.\n\n")
    with atomic_dir(out) as d:
        (d / "controller.toml").write_text(to_toml(design))
        write_json(d / "verify.json", result)
        md = ("# Verification\n\n" + head + verify_table(result) + "\n\n## Pass rate per range bin\n\n"
              + bins_table(result) + "\n\n![histograms](histograms.png)\n")
        (d / "verify.md").write_text(md)
        named = {rg["name"]: value_column(rg) for rg in result["ranges"]}
        rows = [{"index": r["index"], "corner": r["corner"], **{named.get(k, k): v for k, v in r["values"].items()},
                 **r["metrics"], **r["requirements"],
                 "all_pass": r["all_pass"],
                 # the first launch's verdict and the slams of a sequence: the figures verify.md states about them
                 # can then be recomputed from this file alone
                 "first_all_pass": r["first_all_pass"], "slams": r["slams"], "fill_too_slow": r["fill_too_slow"],
                 "fill_after_response": r["fill_after_response"], "creep_of_the_drag": r["creep_of_the_drag"],
                 "beyond_capacity": r["beyond_capacity"]}
                for r in result["results"]]
        pd.DataFrame(rows).to_csv(d / "samples.csv", index=False)
        plot_histograms(result, d / "histograms.png")
        html.write_verify(d / "verify.html", md, result, metric_specs(result))
