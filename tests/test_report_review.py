"""The reports as a control engineer shares them: every figure recomputable from the files beside it, the words
true to what was run (clutches or launches, which plant, which file, whether the controller adapts), the launch
plot readable on its own.

Verifications are built from hand-made sample rows through :func:`wetclutch.launch.verify.summarize`, as in
``test_report_text.py`` (seconds instead of minutes).
"""

from __future__ import annotations

import dataclasses
import re
from types import SimpleNamespace
from typing import Any

import numpy as np
import pandas as pd
import pytest

from wetclutch.launch import design as designs
from wetclutch.launch import metrics, ranges, verify
from wetclutch.params import Params, load
from wetclutch.report import design as design_report
from wetclutch.report import main as main_report
from wetclutch.report import plots
from wetclutch.report import verify as verify_report

RANGES = {"kiss": {"target": "hydraulics.p_prestress", "how": "offset", "low": -0.3e5, "high": 0.3e5, "corner": True},
          "request": {"target": "t_ref", "low": 60.0, "high": 120.0, "corner": True}}


def _row(i: int, corner: bool, ok: bool = True, first: bool = True, slams: int = 0, ripple: float = 1.0,
         kiss: float = 0.0) -> dict[str, Any]:
    m: dict[str, Any] = {k: 1.0 for k in verify.METRICS}
    m.update(overshoot_pct=3.0, contact_s=0.0, input_at_max_pct=0.0, t95_settled_s=0.15 if ok else 0.25,
             steady_state_error_pct=1.0, ripple_pct=ripple, oscillation_pct=0.5, creep_Nm=3.0, t_sync_s=None,
             slip_energy_J=None)
    req = {k: ok or k != "response_time" for k in metrics.REQUIREMENTS}
    return {"index": i, "corner": corner, "seed": i, "values": {"kiss": kiss, "request": 60.0 + i}, "metrics": m,
            "requirements": req, "all_pass": ok, "first_all_pass": first, "slams": slams, "fill_too_slow": False,
            "fill_after_response": False, "creep_of_the_drag": False, "beyond_capacity": False, "error": None,
            "replay": f"wetclutch launch --seed {i}"}


def verification(sequence: int = 1, kind: str = "launch", n: int = 20) -> dict[str, Any]:
    """``n`` random clutches (the first failing its first launch, the second slamming once, the third rippling) and
    4 corners (the first failing, each launch of the second a slam)."""
    rows = [_row(i, False, first=i != 0, slams=int(i == 1), ripple=6.0 if i == 2 else 1.0,
                 kiss=-0.3e5 + 0.6e5 * i / max(n - 1, 1)) for i in range(n)]
    rows += [_row(n + j, True, ok=j != 0, first=False, slams=sequence if j == 1 else 0, kiss=0.3e5 * (-1) ** j)
             for j in range(4)]
    ctx = SimpleNamespace(design=SimpleNamespace(kind=kind), ranges=ranges.parse(RANGES), limited=(),
                          sequence=sequence, through_lockup=False)
    return verify.summarize(rows, ctx, 0, n)


# ---------------------------------------------------------------- samples.csv holds what verify.md states


def test_samples_csv_recomputes_the_first_launch_rate_and_the_slams(tmp_path):
    res = verification(sequence=3)
    verify_report.write(res, tmp_path / "v", designs.cached(Params()))
    df = pd.read_csv(tmp_path / "v" / "samples.csv")
    rand = df[~df["corner"]]
    assert rand["first_all_pass"].mean() == pytest.approx(res["pass_rate_first_launch"])
    assert int(df[df["corner"]]["first_all_pass"].sum()) == 0
    assert int(df["slams"].sum()) == res["slams"] == 4
    md = (tmp_path / "v" / "verify.md").read_text()
    assert f"): {int(df['slams'].sum())} of the {3 * len(df)} (" in md


# ---------------------------------------------------------------- words true to what was run


def test_with_a_sequence_the_failures_are_counted_as_clutches():
    md = verify_report.verify_table(verification(sequence=3))
    assert "Of the 1 clutch that fails on the last launch (0 of the random clutches, 1 of the corners)" in md
    assert "launch that fails" not in md


def test_the_baseline_is_not_said_to_adapt():
    md = verify_report.verify_table(verification(sequence=3, kind="baseline"))
    assert "adaptation carried over" not in md and "before any adaptation" not in md
    assert "the baseline has no adaptation to carry over" in md
    assert "On the first launch 95.0 % of the random clutches met every requirement (corners 0 of 4) against" in md
    launch = verify_report.verify_table(verification(sequence=3))
    assert "adaptation carried over" in launch and "before any adaptation" in launch


def test_one_rippling_clutch_has_its_torque():
    md = verify_report.verify_table(verification())
    assert "Of the 20 random clutches, 1 has a ripple above 5 % of its torque" in md


def test_worst_cases_name_the_settled_t95_and_whether_they_are_corners():
    res = verification()
    md = verify_report.verify_table(res)
    worst = [ln for ln in md.splitlines() if ln.startswith("- #")]
    assert worst[0].startswith("- #20 (corner): ess 1.00 %, t95 (settled) 0.250 s,")
    assert all(re.match(r"- #\d+ \((corner|random)\): ", ln) for ln in worst)
    assert not any(re.search(r"t95 \d", ln) for ln in worst)


def test_bin_edges_are_written_in_full():
    table = verify_report.bins_table(verification())
    assert "e+" not in table
    assert "| kiss | hydraulics.p_prestress + | -30000..-15000: " in table and "| 15000..30000: " in table


# ---------------------------------------------------------------- the design's files and plant


def test_the_baselines_tables_are_in_baseline_toml(tmp_path):
    launch, base = designs.cached(Params()), designs.cached(Params(), "baseline")
    design_report.write([launch, base], tmp_path / "d")
    text = (tmp_path / "d" / "design.md").read_text()
    launch_part, base_part = text.split("# Controller design: baseline")
    assert "Tables (in `controller.toml`)" in launch_part and "Tables (in `baseline.toml`)" in base_part
    # the baseline designed alone is written to controller.toml, and its section says so
    design_report.write([base], tmp_path / "b")
    assert "Tables (in `controller.toml`)" in (tmp_path / "b" / "design.md").read_text()
    job, summary = _job()
    md = main_report._report_md(job, summary)
    assert md.split("### Controller design: baseline")[1].count("Tables (in `baseline.toml`)") == 1


def _summary(oil: float, t_ref: float, kind: str) -> dict[str, Any]:
    return {"oil_temp_C": oil, "t_ref_Nm": t_ref, "controller": kind, "steady_state_error_pct": 1.0, "t95_s": 0.15,
            "t95_settled_s": 0.15, "overshoot_pct": 2.0, "ripple_pct": 1.0, "creep_Nm": 3.0, "t_sync_s": 3.0,
            "requirements": {k: True for k in metrics.REQUIREMENTS}}


def _job(baseline_plant: Params | None = None, launches: list | None = None) -> tuple[SimpleNamespace, dict]:
    ver, base = verification(sequence=3), verification(sequence=3, n=10, kind="baseline")
    b = designs.cached(Params(), "baseline")
    if baseline_plant is not None:
        b = dataclasses.replace(b, plant=baseline_plant)
    job = SimpleNamespace(plant=Params(), design=designs.cached(Params()), baseline=b, launches=launches or [],
                          verify=ver, verify_baseline=base,
                          margins=[{"corner": {"oil_temp": 10.0}, "gain_margin": 3.0, "phase_margin_deg": 60.0}],
                          launch_margins=[{"corner": {"oil_temp": 10.0}, "gain_margin": 3.0, "phase_margin_deg": 60.0,
                                           "damping": 0.3, "resonance_hz": 20.0}])
    return job, {"same_samples": main_report.same_samples(ver, base)}


def test_the_verdict_says_on_which_plant_the_baseline_was_tuned():
    job, summary = _job()
    assert "tuned by the SIMC rule on this plant)" in main_report._report_md(job, summary)
    other, summary = _job(baseline_plant=load(overrides={"driveline.ratio": 0.7}))
    md = main_report._report_md(other, summary)
    assert "tuned by the SIMC rule on another plant)" in md and "on this plant" not in md


def test_the_launch_shown_is_captioned_by_its_own_conditions():
    pairs = [tuple(SimpleNamespace(summary=_summary(oil, t, k)) for k in ("launch", "baseline"))
             for oil, t in ((20.0, 60.0), (85.0, 120.0))]
    job, summary = _job(launches=pairs)
    md = main_report._report_md(job, summary)
    assert "![launch at 85 C, 120 N m](launch_1.png)" in md and "41 C" not in md


# ---------------------------------------------------------------- the launch plot on its own


def _step_launch() -> tuple[pd.DataFrame, pd.DataFrame]:
    """Measured and true signals of a made-up launch: a 100 N m step at 1 s, answered at once."""
    t = np.linspace(0.0, 2.0, 201)
    step = np.where(t > 1.0, 100.0, 0.0)
    sig = pd.DataFrame({"time": t, "t_ref": step, "T_r": step, "p_clutch": 1e5 + 1e3 * step, "u": 1.0 + 0.01 * step,
                        "omega_p": 150.0 - 10 * t, "omega_1": 10 * t, "omega_s": 5 * t})
    truth = pd.DataFrame({"time": t, "T_r": step})
    return sig, truth


def test_the_launch_plot_keeps_one_colour_per_launch_and_names_its_conditions(tmp_path, monkeypatch):
    sig, truth = _step_launch()
    figs = []
    monkeypatch.setattr(plots.plt, "close", figs.append)
    plots.plot_launch(sig, truth, _summary(41.0, 100.0, "launch"), tmp_path / "l.png", extra=sig, extra_label="baseline")
    assert (tmp_path / "l.png").is_file()
    fig = figs[0]

    def colours(word: str) -> set[str]:
        return {line.get_color() for ax in fig.axes[:3] for line in ax.get_lines() if word in line.get_label()}

    assert len(colours("baseline")) == 1 and len(colours("measured, launch") | colours("u, launch")) == 1
    assert colours("baseline").isdisjoint(colours("launch") | colours("true"))
    # nor does a speed take the colour that stands for the second launch or the true torque
    speeds = {line.get_color() for line in fig.axes[3].get_lines()}
    assert speeds.isdisjoint(colours("baseline") | colours("true"))
    # every panel's lines say whose they are
    assert all(any("launch" in line.get_label() for line in ax.get_lines()) for ax in fig.axes[:4])
    title = fig._suptitle.get_text()
    assert "41 C" in title and "100 N m" in title and "launch controller" in title


def test_the_launch_plot_gives_the_compared_launchs_verdicts_too(tmp_path, monkeypatch):
    sig, truth = _step_launch()
    base = _summary(41.0, 100.0, "baseline")
    base["requirements"] = {k: k != "response_time" for k in metrics.REQUIREMENTS}
    figs = []
    monkeypatch.setattr(plots.plt, "close", figs.append)
    plots.plot_launch(sig, truth, _summary(41.0, 100.0, "launch"), tmp_path / "l.png", extra=sig,
                      extra_label="baseline", extra_summary=base)
    lines = figs[0]._suptitle.get_text().splitlines()
    assert lines[1].startswith("launch: ") and "FAIL" not in lines[1]
    assert lines[2].startswith("baseline: ") and "response_time FAIL" in lines[2]


def test_the_rig_plot_gives_the_commands_unit(tmp_path, monkeypatch):
    t = np.linspace(0.0, 1.0, 11)
    df = pd.DataFrame({"time": t, "u": 0.2 + 0.0 * t, "p_clutch": 1e5 + 0.0 * t})
    figs = []
    monkeypatch.setattr(plots.plt, "close", figs.append)
    plots.plot_rig(df, df, tmp_path / "r.png", "wetclutch rig step", u_unit="duty")
    assert figs[0].axes[0].get_title(loc="left") == "Command u [duty]"


# ---------------------------------------------------------------- the calibration report on a clutch of its own


def test_the_calibration_report_neither_calls_another_clutch_the_default_nor_prints_nan(tmp_path):
    from wetclutch.report import calibration as calibration_report
    from wetclutch.rig.calibration import Figure

    figs = [Figure("contact pressure (torque onset)", 0.7, 1.1, 0.4, 0.1, "absolute", "bar"),
            Figure("dead time pdc 0.05 at 41 C", 0.5, float("nan"), float("nan"), 0.2, unit="s"),
            Figure("valve hysteresis visible (up vs down staircase)", "visible", 0.153, 0.0, 0.0, "absolute", "bar")]
    calibration_report.write(figs, tmp_path / "cal")
    md = (tmp_path / "cal" / "report.md").read_text()
    assert "default rig" not in md and "nan" not in md.lower()
    rows = {ln.split("|")[1].strip(): [c.strip() for c in ln.strip("|").split("|")] for ln in md.splitlines()
            if ln.startswith("| ") and not ln.startswith("| figure")}
    assert rows["dead time pdc 0.05 at 41 C"][2:4] == ["no torque onset", "-"]
    assert rows["valve hysteresis visible (up vs down staircase)"][3:5] == ["-", "> 0.02 bar up-down"]


def test_verify_md_names_the_plant_and_whether_the_controller_was_designed_on_it(tmp_path):
    res = verification()
    own = designs.cached(Params())
    verify_report.write(res, tmp_path / "own", own)
    md = (tmp_path / "own" / "verify.md").read_text()
    assert "vary around the default parameters; the launch controller verified was designed on it." in md
    other = load(overrides={"driveline.ratio": 0.6})
    verify_report.write(res, tmp_path / "mismatch", own, other, "my.toml", ["driveline.ratio=0.6"])
    md = (tmp_path / "mismatch" / "verify.md").read_text()
    assert "vary around the parameter file `my.toml`, with `driveline.ratio=0.6`" in md
    assert "was designed on another plant (the `[plant]` section of `controller.toml`)" in md


def test_html_tables_align_the_first_columns_header_with_its_cells():
    from wetclutch.report import html

    page = html.page("t", "| requirement | pass rate |\n|---|---|\n| creep | 100.0 % |\n", {})
    css = re.search(r"<style>(.*?)</style>", page, re.S).group(1)
    rule = next(r for r in css.split("}") if "td:first-child" in r)
    assert "th:first-child" in rule and "text-align: left" in rule
