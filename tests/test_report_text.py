"""The reports' sentences and tables say what their numbers say: loop margins, launches per clutch, lock-up
figures, what the percentiles are over, the plant and the outline, counts with their nouns.

Verifications are built from hand-made sample rows through :func:`wetclutch.launch.verify.summarize` (the
result a real run returns, in seconds instead of minutes).
"""

from __future__ import annotations

import re
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from wetclutch.launch import design as designs
from wetclutch.launch import loop, metrics, ranges, verify
from wetclutch.params import Params, load
from wetclutch.report import main as main_report
from wetclutch.report import tune as tune_report
from wetclutch.report import verify as verify_report
from wetclutch.report.text import demote, plural, times

RANGES = {"kiss": {"target": "hydraulics.p_prestress", "how": "offset", "low": -0.05e5, "high": 0.05e5, "corner": True},
          "request": {"target": "t_ref", "low": 60.0, "high": 120.0, "corner": True}}


def _row(i: int, corner: bool, overshoot: float, ok: bool = True, first: bool = True, slams: int = 0,
         lockup: bool = False) -> dict[str, Any]:
    m: dict[str, Any] = {k: 1.0 for k in verify.METRICS}
    m.update(overshoot_pct=overshoot, contact_s=0.0, input_at_max_pct=0.0, t95_settled_s=0.15,
             steady_state_error_pct=1.0, ripple_pct=1.0, oscillation_pct=0.5, creep_Nm=3.0,
             t_sync_s=2.0 + 0.1 * i if lockup else None, slip_energy_J=1000.0 + 10.0 * i if lockup else None)
    return {"index": i, "corner": corner, "seed": i, "values": {"kiss": 0.0, "request": 60.0 + i}, "metrics": m,
            "requirements": {k: ok for k in metrics.REQUIREMENTS}, "all_pass": ok, "first_all_pass": first,
            "slams": slams, "fill_too_slow": False, "fill_after_response": False, "creep_of_the_drag": False,
            "beyond_capacity": False, "error": None, "replay": f"wetclutch launch --seed {i}"}


def verification(sequence: int = 1, lockup: bool = False, n: int = 20, kind: str = "launch") -> dict[str, Any]:
    """A verification of ``n`` random clutches (overshoot 2-6 %, the first one failing its first launch) and 4
    corners (overshoot 150 %, each launch of them a slam, one failing)."""
    rows = [_row(i, False, 2.0 + 4.0 * i / max(n - 1, 1), first=i != 0, lockup=lockup) for i in range(n)]
    rows += [_row(n + j, True, 150.0, ok=j != 0, first=False, slams=sequence, lockup=lockup) for j in range(4)]
    ctx = SimpleNamespace(design=SimpleNamespace(kind=kind), ranges=ranges.parse(RANGES), limited=(),
                          sequence=sequence, through_lockup=lockup)
    return verify.summarize(rows, ctx, 0, n)


def _table(md: str, caption: str) -> dict[str, list[str]]:
    """The rows of the markdown table after the line that starts with ``caption``: first cell -> other cells."""
    lines = md.splitlines()
    start = next(i for i, ln in enumerate(lines) if ln.startswith(caption))
    out = {}
    for ln in lines[start + 3:]:
        if not ln.startswith("|"):
            break
        cells = [c.strip() for c in ln.strip("|").split("|")]
        out[cells[0]] = cells[1:]
    return out


# ---------------------------------------------------------------- loop margins

def _corner(gm: float, pm: float, fill: float, temp: float, **extra: float) -> dict[str, Any]:
    return {"corner": {"fill_volume": fill, "oil_temp": temp}, "gain_margin": gm, "phase_margin_deg": pm, **extra}


def test_baseline_margins_name_the_unstable_corners_and_draw_no_stability_conclusion():
    rows = [_corner(0.53, -79.0, 1.3, 10.0), _corner(0.88, -12.0, 1.3, 10.0), _corner(4.0, 60.0, 0.7, 10.0),
            _corner(3.0, 50.0, 1.3, 100.0)]
    text = main_report._margins_md(rows)
    assert "At 2 of the 4 corners the linearised loop is **unstable**" in text
    assert "all of them at fill_volume 1.3, oil_temp 10" in text
    assert "not by instability" not in text and "at least" not in text
    stable = main_report._margins_md(rows[2:])
    assert "unstable" not in stable and "stable at every corner" in stable and "not by instability" in stable


def test_launch_margins_count_unstable_loops_apart_from_judder():
    kw = {"resonance_hz": 20.0}
    rows = [_corner(0.8, 20.0, 1.3, 10.0, damping=0.3, **kw), _corner(3.0, 60.0, 0.7, 10.0, damping=0.4, **kw),
            _corner(0.0, -180.0, 1.3, 100.0, damping=-0.5, **kw)]
    text = main_report._launch_margins_md(rows)
    assert "At 1 of the 3 corners the linearised loop is **unstable**" in text
    assert "at fill_volume 1.3, oil_temp 10" in text
    assert "At 1 corner the driveline is unstable by itself" in text
    assert "stable at every one" not in text
    ok = main_report._launch_margins_md(rows[1:])
    assert "**unstable**" not in ok and "The loop is stable at that corner." in ok
    # the loop's own corners, not the verification's
    assert "at each of its 3 corners: every combination of the extremes of the ranges that enter that model (" in text
    assert "these are not the verification's corners" in text


# ---------------------------------------------------------------- launches per clutch, first launch, slams

def test_a_sequence_says_how_often_each_clutch_was_launched_its_first_launch_and_the_slams():
    res = verification(sequence=3)
    md = verify_report.verify_table(res)
    assert "launched 3 times in a row" in md and "those of the last launch" in md
    assert f"On the first launch, before any adaptation, {100 * res['pass_rate_first_launch']:.1f} %" in md
    assert res["pass_rate_first_launch"] == pytest.approx(19 / 20)
    assert "(corners 0 of 4)" in md
    # 4 corners, each of their 3 launches a slam; 24 clutches launched 3 times
    assert res["slams"] == 12 and "): 12 of the 72 (0 of the random clutches' launches, 12 of the corners')" in md
    once = verify_report.verify_table(verification(sequence=1))
    assert "Each clutch was launched once." in once and "first launch" not in once and ": 4 of the 24" in once


def test_the_main_report_says_how_often_and_the_first_launch(tmp_path):
    job, summary = _job(sequence=3)
    md = main_report._report_md(job, summary)
    verdict = next(ln for ln in md.splitlines() if ln.startswith("**Verdict.**"))
    assert "each launched 3 times" in verdict and "time(s)" not in md
    assert f"before any adaptation, it meets them in {100 * job.verify['pass_rate_first_launch']:.1f} %" in verdict
    assert f"{job.verify['slams']} of all 72 launches slammed" in verdict
    job1, summary1 = _job(sequence=1)
    verdict1 = next(ln for ln in main_report._report_md(job1, summary1).splitlines() if ln.startswith("**Verdict.**"))
    assert "each launched once" in verdict1 and "first launch" not in verdict1


# ---------------------------------------------------------------- lock-up figures

def test_lockup_time_and_slip_energy_are_tabled_when_the_run_has_them():
    res = verification(lockup=True)
    md = verify_report.verify_table(res)
    rows = _table(md, "Metrics over the 20 random clutches")
    t = np.array([r["metrics"]["t_sync_s"] for r in res["results"] if not r["corner"]])
    assert rows["lock-up time t_sync [s]"][0] == "20"
    assert float(rows["lock-up time t_sync [s]"][3]) == pytest.approx(np.percentile(t, 95), rel=1e-3)
    assert "slip energy [J]" in rows
    without = verify_report.verify_table(verification(lockup=False))
    assert "lock-up time" not in _table(without, "Metrics over the 20 random clutches")
    assert "slip energy [J]" not in without


# ---------------------------------------------------------------- what the percentiles are over

def test_percentiles_are_over_the_random_clutches_with_the_corners_apart():
    res = verification()
    md = verify_report.verify_table(res)
    rand = _table(md, "Metrics over the 20 random clutches (the population the pass rates above estimate)")
    corners = _table(md, "Metrics over the 4 corners")
    over = np.array([2.0 + 4.0 * i / 19 for i in range(20)])
    # the random clutches' p95 (below 6 %), not that of all cases mixed (pulled up by the corners' 150 %)
    assert float(rand["overshoot [%]"][3]) == pytest.approx(np.percentile(over, 95), rel=1e-3)
    assert float(rand["overshoot [%]"][5]) == pytest.approx(6.0)
    # the verification's own figures, which the tables show: over the random clutches and over the corners apart
    assert res["percentiles"]["overshoot_pct"]["p95"] == pytest.approx(np.percentile(over, 95))
    assert res["percentiles"]["overshoot_pct"]["n"] == 20 and res["percentiles_corners"]["overshoot_pct"]["n"] == 4
    assert corners["overshoot [%]"][0] == "4" and float(corners["overshoot [%]"][3]) == pytest.approx(150.0)


def test_failures_are_split_into_random_clutches_and_corners():
    md = verify_report.verify_table(verification())
    assert "Of the 1 launch that fails (0 of the random clutches, 1 of the corners)" in md


# ---------------------------------------------------------------- the plant and the outline

def _job(sequence: int = 1, plant: Params | None = None) -> tuple[SimpleNamespace, dict[str, Any]]:
    p = plant or Params()
    ver, base = verification(sequence=sequence), verification(sequence=sequence, n=10, kind="baseline")
    margins = [_corner(2.0, 45.0, 0.7, 10.0)]
    launch_margins = [_corner(2.0, 45.0, 0.7, 10.0, damping=0.3, resonance_hz=20.0)]
    job = SimpleNamespace(plant=p, design=designs.cached(Params()), baseline=designs.cached(Params(), "baseline"),
                          launches=[], verify=ver, verify_baseline=base, margins=margins,
                          launch_margins=launch_margins)
    return job, {"same_samples": main_report.same_samples(ver, base)}


def test_the_main_report_names_its_plant_and_keeps_one_outline():
    job, summary = _job()
    md = main_report._report_md(job, summary, main_report.plant_md(job, "rig/params.toml", ["driveline.ratio=0.6"]))
    head = md.split("## ")[0]
    assert "`rig/params.toml`" in head and "`driveline.ratio=0.6`" in head
    levels = [len(m.group(1)) for m in re.finditer(r"^(#+) ", md, flags=re.M)]
    assert levels.count(1) == 1 and levels[0] == 1
    assert all(b - a <= 1 for a, b in zip(levels, levels[1:])), levels  # no level skipped going down
    titles = re.findall(r"^(#+) (.*)$", md, flags=re.M)
    assert ("###", "Controller design: launch") in titles and ("###", "Controller design: baseline") in titles
    assert ("##", "Loop margins over the corner plants") in titles


def test_the_plant_without_a_file_name():
    job, _ = _job()
    assert "run on the default parameters." in main_report.plant_md(job, None)
    changed, _ = _job(plant=load(overrides={"driveline.ratio": 0.7}))
    text = main_report.plant_md(changed, None)
    assert "a plant other than the defaults" in text and "designed on another plant" in text


def test_demote_deepens_headings_only():
    assert demote("# A\n\ntext # not\n## B\n`#x`\n", 2) == "### A\n\ntext # not\n#### B\n`#x`\n"
    assert demote("###### deep\n", 3) == "###### deep\n"


# ---------------------------------------------------------------- counts and their nouns

def test_counts_take_their_nouns():
    assert plural(1, "random clutch", "random clutches") == "1 random clutch"
    assert plural(0, "corner") == "0 corners" and plural(2, "file") == "2 files"
    assert [times(n) for n in (1, 2, 5)] == ["once", "twice", "5 times"]
    one = verification(n=1)
    assert "of 1 random clutch (" in verify_report.headline(one)
    md = verify_report.verify_table(one)
    assert "Metrics over the 1 random clutch (" in md and "Of the 1 random clutch," in md
    assert not re.search(r"\b1 (random clutches|launches|corners|times)\b", md)
    assert tune_report._launched(1) == "each launched once"
    assert tune_report._launched(3).startswith("each launched 3 times, the adaptation carried over")


def test_a_step_model_that_does_not_describe_its_step_says_so():
    from types import SimpleNamespace

    from wetclutch.report.identify import step_rows

    rec = SimpleNamespace(path="runs/step41/measured.csv")
    good = SimpleNamespace(rec=rec, order=1, gain=1e5, theta=0.02, params={"tau_s": 0.03}, vaf=97.0)
    poor = SimpleNamespace(rec=rec, order=2, gain=1e5, theta=0.0, params={"omega_n_rad_s": 2.8e6, "zeta": 1.1e5},
                           vaf=37.0)
    rows = step_rows([good, poor])
    assert rows[0].endswith("| 97.0 |") and rows[1].endswith("| 37.0 (poor fit: not used) |")


def test_the_sample_table_names_each_range_column_with_what_its_values_are():
    from wetclutch.launch import ranges
    from wetclutch.report.verify import value_column

    cols = {r.name: value_column({"name": r.name, "how": r.how, "unit": r.unit}) for r in ranges.load()}
    assert cols["kiss_point"] == "kiss_point_offset_Pa" and cols["fill_volume"] == "fill_volume_factor"
    assert cols["oil_temp"] == "oil_temp_C" and cols["request"] == "request_Nm" and cols["cvt_ratio"] == "cvt_ratio"


def test_the_verification_says_where_the_nominal_was_taken_from_another_request_level():
    nan = float("nan")
    rows = verification()["results"]
    ctx = SimpleNamespace(design=SimpleNamespace(kind="launch"), ranges=ranges.parse(RANGES), limited=(),
                          sequence=1, through_lockup=False)
    moved = verify.summarize(rows, ctx, 0, 20, loop.held_where_settled([0.15, 0.15, 0.15, nan, nan], [2.0] * 5))
    assert moved["nominal"]["taken_from_Nm"] == [25.0, 50.0, 100.0, 100.0, 100.0]
    text = verify_report.verify_table(moved)
    assert "at 150 N m that of 100 N m; at 200 N m that of 100 N m" in text
    # every level settled: nothing to say
    own = verify.summarize(rows, ctx, 0, 20, loop.held_where_settled([0.15] * 5, [2.0] * 5))
    assert "does not settle" not in verify_report.verify_table(own)
