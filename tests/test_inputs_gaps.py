"""Inputs that were taken for something else than they said: a launch profile with a row longer than its header, a
request beside a profile that gives its own, a parameter section built from Python, a kiss point written in bar, a
controller file that names no plant, a pinned corner range and an oil temperature varied twice. Each is refused in
one line naming the field (or, for the pinned corner, run once), from Python and from the command line; no test
launches a clutch."""

from __future__ import annotations

import tempfile
import tomllib
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import tomli_w
from hypothesis import given, settings
from hypothesis import strategies as st

from wetclutch.cli import main
from wetclutch.errors import ParameterError, WetclutchError
from wetclutch.ident.friction import commanded_ratio
from wetclutch.launch import adaptation, design, ranges
from wetclutch.launch import loop as launch
from wetclutch.launch import settings as files
from wetclutch.params import (Clutch, Driveline, Engage, Friction, Hydraulics, Params, Rig, Thermal, Valve,
                              load as load_params)


@pytest.fixture
def no_work(monkeypatch):
    """Designs, launches and verifications fail the test: what is checked must be checked before them."""
    def work(*a, **kw):
        raise AssertionError("work started before the inputs were checked")
    for name in ("wetclutch.launch.design.design", "wetclutch.launch.loop.sequence", "wetclutch.launch.verify.run"):
        monkeypatch.setattr(name, work)


def _refused(capsys, args: list[str], message: str, out: Path) -> None:
    """``wetclutch ARGS --out OUT`` exits 2 with the one line ``wetclutch: error: MESSAGE`` and writes nothing."""
    assert main([*args, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err == f"wetclutch: error: {message}\n", err
    assert not out.exists()


# --- a launch profile with a row longer than its header ---------------------------------------------------------------


@pytest.mark.parametrize(("text", "line"), [
    ("time,t_ref\n0,10,5\n0.5,20\n1,30\n", 2),      # the first data row: pandas took the times for an index
    ("time,t_ref\n0,10,1\n0.5,20,5\n1,30,3\n", 2),  # every row: the request was read shifted, without a word
    ("time,t_ref\n0,10\n0.5,20,5\n1,30\n", 3),      # a later row: pandas could not tokenize it
    ("time,t_ref\n\n0,10\n\n0.5,20,\n1,30\n", 5),   # a trailing comma; the line counts the blank lines too
    ("time,t_ref\n0,10,5\n1,20,5\n2,30,5\n", 2),    # whole seconds: pandas's index of them looked like no index
], ids=["first-row", "every-row", "later-row", "trailing-comma", "integer-times"])
def test_a_profile_row_longer_than_its_header_is_named_by_its_line(tmp_path, capsys, no_work, text, line):
    f = tmp_path / "profile.csv"
    f.write_text(text)
    with pytest.raises(WetclutchError) as e:
        launch.reference(launch.Conditions(profile=str(f)), np.zeros(3))
    assert str(e.value) == f"profile {f}: line {line} is malformed: it has 3 fields, the header 2"
    _refused(capsys, ["launch", "--profile", str(f)],
             f"--profile {f}: line {line} is malformed: it has 3 fields, the header 2", tmp_path / "l")


_times = st.lists(st.floats(0.001, 10.0), min_size=2, max_size=6).map(lambda d: np.cumsum(d).tolist())


@settings(max_examples=150, deadline=None)
@given(times=_times, data=st.data())
def test_any_profile_reads_as_written_or_names_its_first_long_row(times, data):
    n = len(times)
    refs = data.draw(st.lists(st.floats(0.0, 1000.0), min_size=n, max_size=n).filter(lambda r: max(r) > 0.0))
    blank = data.draw(st.lists(st.booleans(), min_size=n, max_size=n))          # a blank line before the row
    extra = data.draw(st.lists(st.integers(0, 2), min_size=n, max_size=n))      # fields beyond the header's two
    lines, first_long = ["time,t_ref"], None
    for t, r, b, k in zip(times, refs, blank, extra):
        if b:
            lines.append("")
        lines.append(",".join([repr(t), repr(r)] + ["7"] * k))
        if k and first_long is None:
            first_long = (len(lines), 2 + k)
    with tempfile.TemporaryDirectory() as d:
        f = Path(d) / "p.csv"
        f.write_text("\n".join(lines) + "\n")
        cond = launch.Conditions(profile=str(f), t_request=0.0)
        tau = np.linspace(-1.0, times[-1] + 1.0, 50)
        if first_long is None:
            expected = np.where(tau >= 0.0, np.interp(tau, times, refs), 0.0)
            np.testing.assert_allclose(launch.reference(cond, tau), expected, rtol=1e-12, atol=0.0)
            return
        with pytest.raises(WetclutchError) as e:
            launch.reference(cond, tau)
        assert str(e.value) == (f"profile {f}: line {first_long[0]} is malformed: it has {first_long[1]} fields, "
                                "the header 2")


# --- a request beside a profile that gives its own --------------------------------------------------------------------


def test_a_request_beside_a_csv_profile_is_refused_naming_both(tmp_path):
    f = tmp_path / "profile.csv"
    f.write_text("time,t_ref\n0,0\n0.2,80\n2,80\n")
    with pytest.raises(WetclutchError) as e:
        launch.Conditions(profile=str(f), t_ref=70).checked()
    assert str(e.value) == f"t_ref 70 N m is given with profile '{f}', which gives the request itself; leave t_ref out"
    # the profile alone, and the built-in profiles with any request, are taken as before
    assert launch.Conditions(profile=str(f)).checked().profile == str(f)
    assert launch.Conditions(profile="ramp", t_ref=70).checked().t_ref == 70.0


# --- a parameter section built from Python ----------------------------------------------------------------------------


@pytest.mark.parametrize(("section", "values"), [
    (Driveline, {"ratio": -1}), (Driveline, {"ratio_min": 3.0}), (Clutch, {"peak": 0.5}), (Engage, {"t_ramp": 0}),
    (Engage, {"zz": 1}), (Valve, {"play_exponent": 2.5}), (Hydraulics, {"p_supply": 1e4}),
    (Friction, {"mu_slip_poly": []}), (Thermal, {"mu_temp": 0.05}), (Rig, {"oil_temp_C": "85"}),
], ids=lambda v: v.__name__ if isinstance(v, type) else next(iter(v)))
def test_a_section_built_from_python_refuses_in_the_line_a_parameter_file_gives(tmp_path, section, values):
    name = next(k for k, info in Params.model_fields.items() if info.annotation is section)
    f = tmp_path / "p.toml"
    f.write_text(tomli_w.dumps({name: values}))
    with pytest.raises(ParameterError) as from_file:
        load_params(f)
    with pytest.raises(ParameterError) as built:
        section(**values)
    assert f"parameter file '{f}': {built.value}" == str(from_file.value) and "\n" not in str(built.value)
    with pytest.raises(ParameterError) as validated:
        section.model_validate(values)
    assert str(validated.value) == str(built.value)


def test_a_section_names_the_parameter_as_a_file_does():
    with pytest.raises(ParameterError) as e:
        Driveline(ratio=-1)
    assert str(e.value) == "parameter 'driveline.ratio': Input should be greater than 0.05 (got -1)"


_SECTIONS = [Driveline, Clutch, Engage, Valve, Hydraulics, Friction, Thermal, Rig]
_values = st.one_of(st.floats(), st.integers(-10**6, 10**6), st.booleans(), st.text(max_size=3),
                    st.lists(st.floats(-1.0, 1.0), max_size=3))


@settings(max_examples=200, deadline=None)
@given(section=st.sampled_from(_SECTIONS), data=st.data())
def test_any_value_a_section_refuses_a_parameter_file_refuses_in_the_same_words(section, data):
    key = data.draw(st.sampled_from(sorted(section.model_fields)))
    value = data.draw(_values)
    try:
        section(**{key: value})
    except ParameterError as e:
        name = next(k for k, info in Params.model_fields.items() if info.annotation is section)
        with tempfile.TemporaryDirectory() as d:
            f = Path(d) / "p.toml"
            f.write_text(tomli_w.dumps({name: {key: value}}))
            with pytest.raises(ParameterError) as from_file:
                load_params(f)
        assert str(from_file.value) == f"parameter file '{f}': {e}" and "\n" not in str(e)


@pytest.mark.parametrize(("ratio", "expected"), [(0.6, 0.6), (-1, None), ("0.6", None), (float("nan"), None)])
def test_a_recordings_commanded_ratio_is_read_or_left_out(ratio, expected):
    rec = SimpleNamespace(meta={"params": {"driveline": {"ratio": ratio}}})
    assert commanded_ratio(rec) == expected


# --- a kiss point written in bar --------------------------------------------------------------------------------------


def _state(kiss) -> str:
    return tomli_w.dumps({"band_C": 20.0, "band": [{"from_C": 70.0, "to_C": 90.0, "kiss_Pa": kiss, "launches": 2}]})


def test_a_kiss_point_in_bar_is_refused_with_a_hint(tmp_path, capsys, no_work):
    with pytest.raises(WetclutchError) as e:
        adaptation.loads(_state(1.2), "a.toml")
    assert str(e.value) == ("a.toml: band[0].kiss_Pa: 1.2 Pa is below 1000 Pa, the least kiss point a state may hold "
                            "(in Pa, not bar?)")
    a = tmp_path / "a.toml"
    a.write_text(_state(0.7))
    _refused(capsys, ["launch", "--adaptation", str(a)],
             f"{a}: band[0].kiss_Pa: 0.7 Pa is below 1000 Pa, the least kiss point a state may hold (in Pa, not bar?)",
             tmp_path / "l")


@settings(max_examples=100, deadline=None)
@given(kiss=st.floats(0.0, 5e6))
def test_a_kiss_point_loads_from_the_floor_up(kiss):
    if kiss < adaptation.KISS_MIN_PA:
        with pytest.raises(WetclutchError, match=r"in Pa, not bar\?\)$"):
            adaptation.loads(_state(kiss))
    else:
        assert adaptation.loads(_state(kiss)).kiss_Pa == {adaptation.band(70.0): kiss}


@settings(max_examples=50, deadline=None)
@given(found=st.floats(0.0, 5e6), before=st.none() | st.floats(0.0, 5e6))
def test_a_learnt_state_loads_again_whatever_kiss_point_a_launch_found(found, before):
    # a clutch whose plates touch at once (no prestress, a short stroke) finds its kiss point within the
    # pressure sensor's noise of zero
    state = adaptation.Adaptation()
    if before is not None:
        state = state.learn(70.0, before)
    state = state.learn(70.0, found)
    back = adaptation.loads(state.to_toml())
    assert back.kiss_Pa == state.kiss_Pa
    assert back.kiss_Pa[adaptation.band(70.0)] >= adaptation.KISS_MIN_PA


def test_the_floor_lies_below_every_kiss_point_the_shipped_ranges_reach():
    # the lowest on the built-in rig: the prestress 0.3 bar lower and the stroke 30 % shorter
    h = Params().hydraulics
    lowest = h.p_prestress - 0.3e5 + h.k_reset * 0.7 * h.x_contact / h.A_p
    assert adaptation.KISS_MIN_PA < lowest / 30.0


# --- a controller file that names no plant ----------------------------------------------------------------------------


def _controller_text() -> str:
    """A launch controller file of the built-in rig without a simulation: its settings as a design takes them, a
    feedforward map rising over the valve's input range."""
    plant = Params()
    values = {k: v for k, (v, _) in design.plant_settings(plant).items()} | dict(design.LAUNCH_DEFAULTS)
    values = {k: values[k] for k in design.SETTINGS["launch"]}
    table = np.tile(np.linspace(0.2, 5.0, design.MAP_PRESSURES.size), (design.MAP_TEMPS.size, 1))
    return files.to_toml(design.Design("launch", plant, values, {}, design.MAP_TEMPS.copy(),
                                       design.MAP_PRESSURES.copy(), table))


@pytest.mark.parametrize("plant", [{}, {"driveline": {}, "hydraulics": {}}], ids=["empty", "empty-sections"])
def test_a_controller_file_with_an_empty_plant_is_refused(tmp_path, capsys, no_work, plant):
    data = tomllib.loads(_controller_text())
    assert files.loads(tomli_w.dumps(data), "c.toml").plant == Params()  # the whole [plant] loads
    data["plant"] = plant
    message = ("[plant] is empty: it must hold the parameter set the controller was designed on (wetclutch design "
               "writes it)")
    with pytest.raises(files.ControllerFileError) as e:
        files.loads(tomli_w.dumps(data), "c.toml")
    assert str(e.value) == f"c.toml: {message}"
    c = tmp_path / "c.toml"
    c.write_text(tomli_w.dumps(data))
    _refused(capsys, ["launch", "--controller-file", str(c)], f"{c}: {message}", tmp_path / "l")


# --- verification ranges: a pinned corner, an oil temperature varied twice --------------------------------------------


def _range(target, low, high, corner=True):
    return {"target": target, "how": "abs", "low": low, "high": high, "corner": corner}


def test_a_pinned_corner_range_holds_its_value_in_each_corner_case_once():
    rs = ranges.parse({"request": _range("t_ref", 150.0, 150.0), "oil": _range("oil_temp_C", 10.0, 100.0),
                       "ratio": _range("driveline.ratio", 0.4, 1.0)})
    assert ranges.corners(rs) == [{"request": 150.0, "oil": t, "ratio": r} for t in (10.0, 100.0) for r in (0.4, 1.0)]


def test_the_corner_limit_counts_the_ranges_that_make_corner_cases():
    # ten spanning ranges make 1,024 cases, the most allowed; a pinned one beside them adds none, an eleventh doubles
    spanning = {f"r{i}": _range(t, 1.0, 2.0) for i, t in enumerate(
        ["driveline.J_p", "driveline.J_s", "driveline.J_1", "driveline.k_a", "driveline.d_a", "driveline.eta",
         "engage.T_load", "hydraulics.p_supply", "hydraulics.A_p", "hydraulics.x_contact"])}
    spanning["r7"] = _range("hydraulics.p_supply", 6e5, 8e5)
    pinned = spanning | {"oil": _range("oil_temp_C", 40.0, 40.0)}
    assert len(ranges.corners(ranges.parse(pinned))) == 1024
    with pytest.raises(WetclutchError, match="more than 10 corner ranges"):
        ranges.parse(spanning | {"oil": _range("oil_temp_C", 10.0, 100.0)})


_corner_range = st.tuples(st.floats(0.5, 2.0), st.floats(0.0, 1.0), st.booleans()).map(
    lambda t: (t[0], t[0] + t[1] if t[2] else t[0]))


@settings(max_examples=100, deadline=None)
@given(ends=st.lists(_corner_range, min_size=1, max_size=6))
def test_corner_cases_are_every_distinct_combination_of_the_extremes(ends):
    rs = ranges.parse({f"r{i}": {"target": "noise_scale" if i == 0 else t, "how": "abs", "low": lo, "high": hi,
                                 "corner": True}
                       for i, ((lo, hi), t) in enumerate(zip(ends, ["", "driveline.ratio", "driveline.eta",
                                                                        "engage.T_load", "driveline.k_a",
                                                                        "driveline.J_p"]))})
    cases = ranges.corners(rs)
    spanning = sum(lo != hi for lo, hi in ends)
    assert len(cases) == 2 ** spanning
    assert len({tuple(sorted(c.items())) for c in cases}) == len(cases)
    for i, (lo, hi) in enumerate(ends):
        assert {c[f"r{i}"] for c in cases} == {lo, hi}


def test_an_oil_temperature_varied_as_parameter_and_condition_is_refused_naming_both(tmp_path, capsys, no_work):
    data = {"warm_oil": _range("rig.oil_temp_C", 20.0, 40.0, False), "oil": _range("oil_temp_C", 10.0, 100.0)}
    message = ("[warm_oil] (target 'rig.oil_temp_C') and [oil] (target 'oil_temp_C') both vary the oil temperature, "
               "and a launch takes the condition's: keep one of the two")
    with pytest.raises(ranges.RangesError) as e:
        ranges.parse(data, "r.toml")
    assert str(e.value) == f"r.toml: {message}"
    # either alone is taken
    assert [r.target for r in ranges.parse({"warm_oil": data["warm_oil"]})] == ["rig.oil_temp_C"]
    assert [r.target for r in ranges.parse({"oil": data["oil"]})] == ["oil_temp_C"]
    r = tmp_path / "r.toml"
    r.write_text(tomli_w.dumps(data))
    _refused(capsys, ["verify", "--samples", "1", "--ranges", str(r)], f"{r}: {message}", tmp_path / "v")


def test_a_verification_on_a_csv_profile_runs_it_and_says_the_request_range_does_not_apply(tmp_path):
    # the profile gives the request: the shipped request range is set aside (and said so), every launch runs the
    # profile, and the replay command names the profile rather than a --t-ref the launch never took
    from wetclutch.launch import verify

    prof = tmp_path / "p.csv"
    prof.write_text("time,t_ref\n0,0\n0.1,60\n2,60\n")
    d = design.cached(Params())
    r = verify.run(d, n=2, seed=3, workers=1, corners=False, profile=str(prof), progress=False)
    assert any("gives the request" in s for s in r["ranges_limited"])
    rows = r["results"]
    assert len(rows) == 2 and all("request" not in row["values"] for row in rows)
    assert all(f"--profile {prof}" in row["replay"] and "--t-ref" not in row["replay"] for row in rows)
    # the steady state judged against the profile's 60 N m, not the default request of 100 N m
    assert all(row["metrics"]["steady_state_error_pct"] < 10.0 for row in rows)
