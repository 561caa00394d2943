"""Identification of the open plates' oil drag and of the valve's highest pressure (the supply pressure).

Virtual rig runs of clutches with known parameters, identified: the values are checked against the parameters the
runs were made with, and where the runs do not show a parameter, the prior is kept and the outputs say which run
would give it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from wetclutch import ident, params
from wetclutch.ident import drag
from wetclutch.physics import oil
from wetclutch.report import identify as identify_report
from wetclutch.report import rig as rig_report
from wetclutch.rig import experiments as rig

RUNS = {
    "step41": dict(experiment="step", level=1.8, oil_temp_C=41.0, seed=1),
    "step85": dict(experiment="step", level=2.5, oil_temp_C=85.0, seed=2),
    # up to full duty: the valve opens wide on the top steps
    "stair_full": dict(experiment="staircase", config="valve-only", input_mode="pwm", level=1.0, from_=0.0, seed=3),
}
#: a clutch whose open plates drag half as much again as the built-in rig's, fed at 10 bar (relief cracking there)
DRAGGY_10BAR = {"friction.drag_20C": 1.5 * params.Friction().drag_20C, "hydraulics.p_supply": 10e5,
                "hydraulics.p_relief": 10e5}
#: a clutch fed at 7 bar, the relief valve cracking at the built-in rig's 8 bar
SUPPLY_7BAR = {"hydraulics.p_supply": 7e5}
#: the drag to within 5 %: the axle torque's noise over a second of open plates is about 1 % of a 41 C run's drag
DRAG_REL = 0.05
#: the supply pressure to within 1 %: the model's valve wide open, at the run's conditions
SUPPLY_REL = 0.01


def _runs(root: Path, overrides: dict, names: tuple[str, ...]) -> list[ident.Recording]:
    p = params.load(overrides=overrides)
    recs = []
    for name in names:
        kw = dict(RUNS[name])
        rig_report.write(rig.run(kw.pop("experiment"), p, **kw), root / name)
        recs.append(ident.load(root / name / "measured.csv"))
    return recs


@pytest.fixture(scope="module")
def builtin_runs(tmp_path_factory):
    return _runs(tmp_path_factory.mktemp("builtin"), {}, tuple(RUNS))


@pytest.fixture(scope="module")
def draggy_10bar(tmp_path_factory):
    return ident.identify(_runs(tmp_path_factory.mktemp("draggy"), DRAGGY_10BAR, ("step41", "stair_full")))


def test_the_drag_law_is_the_oils_viscosity_ratio():
    assert drag.viscosity_factor(20.0) == pytest.approx(1.0)
    assert drag.viscosity_factor(85.0) == pytest.approx(oil.dynamic_viscosity(85.0) / oil.dynamic_viscosity(20.0))
    # out of the oil's range: its edge, not an error
    assert drag.viscosity_factor(500.0) == drag.viscosity_factor(150.0)


@pytest.mark.parametrize("overrides", [{}, DRAGGY_10BAR, SUPPLY_7BAR], ids=["builtin", "draggy-10bar", "7bar"])
def test_drag_and_supply_are_identified_from_open_plates_and_a_saturated_staircase(
        overrides, builtin_runs, draggy_10bar, tmp_path):
    if overrides is DRAGGY_10BAR:
        res = draggy_10bar
    elif overrides:
        res = ident.identify(_runs(tmp_path, overrides, ("step41", "stair_full")))
    else:
        res = ident.identify(builtin_runs)
    true = params.load(overrides=overrides)
    found = res.identified
    assert found.friction.drag_20C == pytest.approx(true.friction.drag_20C, rel=DRAG_REL)
    assert found.friction.drag_20C == res.estimates["drag_20C"].value
    assert 0.0 < res.estimates["drag_20C"].se < DRAG_REL * true.friction.drag_20C
    assert found.hydraulics.p_supply == pytest.approx(true.hydraulics.p_supply, rel=SUPPLY_REL)
    sources = res.sources()
    assert sources["friction.drag_20C"][0] == sources["hydraulics.p_supply"][0] == "identified"
    data = res.as_json()
    assert data["parameters"]["friction.drag_20C"] == data["parameters"]["hydraulics.p_supply"] == "identified"
    if true.hydraulics.p_relief > true.hydraulics.p_supply:
        # the relief valve never cracked: the prior's is kept, and said so
        assert found.hydraulics.p_relief == res.prior.hydraulics.p_relief
        assert sources["hydraulics.p_relief"][0] == "prior"
        assert "cracks above the highest pressure measured" in sources["hydraulics.p_relief"][1]
    else:
        assert found.hydraulics.p_relief == pytest.approx(true.hydraulics.p_relief, rel=SUPPLY_REL)
        assert sources["hydraulics.p_relief"][0] == "identified"


def test_each_runs_drag_at_its_oil_temperature(builtin_runs):
    """The drag at each run's temperature is the 20 C value times the viscosity ratio, both runs alike."""
    res = ident.identify(builtin_runs[:2])
    per_run = res.estimates["oil_drag_Nms"]
    d20 = params.Friction().drag_20C
    for rec, value, se in zip(builtin_runs, per_run.value, per_run.se):
        truth = d20 * oil.dynamic_viscosity(rec.oil_temp_C) / oil.dynamic_viscosity(20.0)
        assert abs(value - truth) < max(4.0 * se, 0.03 * truth)


def test_a_step_to_the_top_of_a_clutch_in_cold_oil_is_no_supply_pressure(builtin_runs, tmp_path):
    """At 41 C the valve still regulates at 5 V (about 6 bar): a single plateau at full input is not taken for the
    supply, which stays the prior's, and the outputs say which run would give it."""
    p = params.load(overrides=SUPPLY_7BAR)
    rig_report.write(rig.run("step", p, level=5.0, oil_temp_C=41.0, seed=4), tmp_path / "full41")
    res = ident.identify([ident.load(tmp_path / "full41" / "measured.csv")])
    assert res.identified.hydraulics.p_supply == res.prior.hydraulics.p_supply
    assert "supply_pressure_Pa" not in res.estimates
    status, why = res.sources()["hydraulics.p_supply"]
    assert status == "prior"
    assert "still raises the pressure" in why and "staircase up to the top of the input range" in why
    data = res.as_json()
    assert data["supply_pressure_Pa"]["value"] is None and "not identified" in data["supply_pressure_Pa"]["note"]
    report = identify_report._report(res, [])
    assert f"| hydraulics.p_supply | prior | {why} |" in report


def test_runs_that_show_neither_keep_the_prior_and_say_which_run_would(builtin_runs):
    """The valve's staircase alone: no clutch run for the drag; a staircase that stays low: no saturated top."""
    stair = builtin_runs[2]
    low = ident.Recording(stair.path, {k: v[stair.t < 4.0] for k, v in stair.data.items()}, stair.experiment,
                          stair.config, stair.input_mode, stair.meta)  # its first two steps, both rising
    res = ident.identify([low])
    prior = res.prior
    assert res.identified.friction.drag_20C == prior.friction.drag_20C
    assert res.identified.hydraulics.p_supply == prior.hydraulics.p_supply
    sources = res.sources()
    assert sources["friction.drag_20C"] == ("prior", "no suitable runs (needs a clutch run whose primary slips "
                                            "against the resting output with the plates apart for at least 0.2 s "
                                            "before its first command change (a step from an empty clutch))")
    assert sources["hydraulics.p_supply"][0] == "prior"
    assert "the valve is not wide open there" in sources["hydraulics.p_supply"][1]
    assert np.isfinite(res.estimates["valve_gain_poly"].value[0])


def test_the_identify_report_names_the_source_of_drag_and_supply(draggy_10bar):
    report = identify_report._report(draggy_10bar, [])
    assert "| friction.drag_20C | identified | from drag_20C |" in report
    assert "| hydraulics.p_supply | identified | from supply_pressure_Pa |" in report
    assert "| drag_20C |" in report and "| supply_pressure_Pa |" in report
