"""Parameter record: dotted paths, TOML round trip, one-line errors (property-based where it pays)."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import wetclutch as wc
from wetclutch import params as pm
from wetclutch.params import Friction
from wetclutch.cli import main
from wetclutch.errors import ParameterError

PATHS = [row[0] for row in pm.describe(wc.Params())]


def test_defaults_and_describe_cover_every_field():
    rows = pm.describe(wc.Params())
    assert {"driveline.J_p", "driveline.ratio", "driveline.eta", "driveline.k_a", "driveline.omega_p0"} <= set(PATHS)
    assert all(unit and desc for _, _, unit, desc in rows)
    assert wc.Params().driveline.omega_p0 == 150.0
    assert wc.Params().driveline.eta == 0.95


def test_export_loads_back_identically(tmp_path):
    p = wc.load_params(overrides={"driveline.ratio": 0.73, "engage.T_cap": 55.5, "driveline.b_1": 1.234e-7})
    f = tmp_path / "p.toml"
    f.write_text(pm.to_toml(p))
    assert wc.load_params(f) == p
    tomllib.loads(f.read_text())  # valid TOML


@pytest.mark.parametrize(
    ("override", "fragment"),
    [
        ({"driveline.nope": 1.0}, "unknown parameter 'driveline.nope'"),
        ({"nosection.x": 1.0}, "unknown parameter 'nosection.x'"),
        ({"driveline.J_p": -1.0}, "driveline.J_p"),
        ({"driveline.eta": 1.2}, "driveline.eta"),
        ({"driveline.ratio": "fast"}, "driveline.ratio"),
        ({"driveline": 3.0}, "'driveline' is a section"),
        ({"friction.mu_slip_poly": [float("nan")]}, "friction.mu_slip_poly.0"),
        ({"friction.mu_slip_poly": [1e-3, float("inf")]}, "friction.mu_slip_poly.1"),
        ({"valve.play_exponent": 7.5}, "parameter 'valve.play_exponent': must be a whole number (got 7.5)"),
        ({"valve.play_exponent": 0.0}, "valve.play_exponent"),
    ],
)
def test_bad_values_name_the_field(override, fragment):
    with pytest.raises(ParameterError) as err:
        wc.load_params(overrides=override)
    assert fragment in str(err.value)
    assert "\n" not in str(err.value)


def test_malformed_toml_file(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text("[driveline\nJ_p = 1")
    with pytest.raises(ParameterError, match="not valid TOML"):
        wc.load_params(f)


def test_parse_set_reads_toml_literals():
    assert pm.parse_set("driveline.ratio=1.2") == ("driveline.ratio", 1.2)
    assert pm.parse_set("a.b = [1, 2.5]") == ("a.b", [1, 2.5])
    with pytest.raises(ParameterError, match="expected PATH=VALUE"):
        pm.parse_set("driveline.ratio")
    with pytest.raises(ParameterError, match="not a TOML value"):
        pm.parse_set("driveline.ratio=fast")


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=40))
def test_parse_set_never_crashes(item):
    try:
        path, _ = pm.parse_set(item)
    except ParameterError as err:
        assert "\n" not in str(err)
    else:
        assert "=" in item and path == item.partition("=")[0].strip()


@settings(max_examples=200, deadline=None)
@given(
    st.sampled_from(PATHS + ["driveline.x", "x.y", "engage"]),
    st.one_of(st.floats(allow_nan=True), st.integers(), st.text(max_size=5), st.booleans(), st.lists(st.floats())),
)
def test_any_override_validates_or_fails_in_one_line(path, value):
    try:
        p = wc.load_params(overrides={path: value})
    except ParameterError as err:
        assert "\n" not in str(err) and str(err)
    else:
        # a boolean or a string is never read as a number, however it would convert
        flat = value if isinstance(value, list) else [value]
        assert not any(isinstance(v, (bool, str)) for v in flat)
        section, key = path.split(".")
        got = getattr(getattr(p, section), key)
        if isinstance(got, list):
            assert got == pytest.approx([float(v) for v in value])
        else:
            assert got == pytest.approx(float(value))


@settings(max_examples=100, deadline=None)
@given(st.text(max_size=200))
def test_random_toml_files_never_crash(tmp_path_factory, text):
    f = tmp_path_factory.mktemp("p") / "f.toml"
    f.write_text(text)
    try:
        wc.load_params(f)
    except ParameterError as err:
        assert "\n" not in str(err)


NUMERIC = [path for path, value, _, _ in pm.describe(wc.Params()) if not isinstance(value, list)]


def _refused(overrides: dict) -> str:
    with pytest.raises(ParameterError) as err:
        wc.load_params(overrides=overrides)
    msg = str(err.value)
    assert "\n" not in msg
    return msg


# --- friction law: mu(slip) positive over the slips of a run


@pytest.mark.parametrize(("poly", "got"), [([0.0], "it is 0 at 0 rad/s"), ([-0.03], "it is -0.03 at 0 rad/s"),
                                           ([-1e-4, 0.0], "at 150 rad/s")])
def test_a_friction_law_without_friction_is_refused_by_name(poly, got):
    msg = _refused({"friction.mu_slip_poly": poly})
    assert msg.startswith("friction.mu_slip_poly")
    assert "must be > 0 for slip 0..150 rad/s" in msg and "driveline.omega_p0" in msg and got in msg


def test_a_dip_of_mu_between_grid_points_is_found():
    # negative only within 0.03 rad/s of 75.1 rad/s: the least value lies where the derivative vanishes
    poly = [1e-3, -2 * 75.1e-3, 75.1**2 * 1e-3 - 1e-6]
    assert np.polyval(poly, 75.0) > 0 and np.polyval(poly, 75.1) < 0
    assert "at 75.1 rad/s" in _refused({"friction.mu_slip_poly": poly})


def test_the_slip_range_is_the_primarys_starting_speed():
    # the default curve crosses zero at 226 rad/s
    assert wc.load_params(overrides={"driveline.omega_p0": 220.0}).driveline.omega_p0 == 220.0
    msg = _refused({"driveline.omega_p0": 300.0})
    assert "friction.mu_slip_poly" in msg and "slip 0..300 rad/s" in msg and "at 300 rad/s" in msg


def test_the_steepness_that_turns_mu_negative_is_refused_and_named():
    assert wc.load_params(overrides={"friction.mu_slope": 1.5}).friction.mu_slope == 1.5
    msg = _refused({"friction.mu_slope": 10.0})
    assert "friction.mu_slip_poly" in msg and "friction.mu_slope" in msg


@settings(max_examples=300, deadline=None)
@given(
    st.lists(st.floats(-1e-2, 1e-2, allow_subnormal=False), min_size=2, max_size=2),
    st.floats(-0.05, 0.1, allow_subnormal=False),
    st.floats(0.5, 2.0), st.floats(0.0, 3.0), st.floats(0.0, 300.0), st.floats(0.0, 400.0),
)
def test_a_quadratic_friction_law_loads_if_and_only_if_mu_is_positive(ab, c, scale, slope, span, w0):
    a, b = ab[0] * 1e-4, ab[1] * 1e-2
    coef = Friction(mu_slip_poly=[a, b, c], mu_scale=scale, mu_slope=slope, mu_slip_span=span).curve()
    # the least of a quadratic on 0..w0: at an end or at its vertex
    cand = [0.0, w0] + ([-coef[1] / (2 * coef[0])] if coef[0] > 0 else [])
    least = min(float(np.polyval(coef, s)) for s in cand if 0.0 <= s <= w0)
    assume(abs(least) > 1e-12)  # no verdict on a law that touches zero within rounding
    over = {"friction.mu_slip_poly": [a, b, c], "friction.mu_scale": scale, "friction.mu_slope": slope,
            "friction.mu_slip_span": span, "driveline.omega_p0": w0}
    if least > 0:
        wc.load_params(overrides=over)
    else:
        assert "friction.mu_slip_poly" in _refused(over)


def test_the_temperature_law_keeps_friction_at_every_oil_temperature():
    assert wc.load_params(overrides={"thermal.mu_temp": -2e-3, "thermal.T_mu_ref_C": 40.0}).thermal.mu_temp == -2e-3
    msg = _refused({"thermal.mu_temp": 0.01})
    assert "thermal.mu_temp 0.01" in msg and "thermal.T_mu_ref_C 85" in msg and "-30 C" in msg
    assert "150 C" in _refused({"thermal.mu_temp": -0.01, "thermal.T_mu_ref_C": 0.0})


# --- types: numbers only, integers included


@settings(max_examples=100, deadline=None)
@given(st.sampled_from(NUMERIC), st.one_of(st.booleans(), st.text(max_size=5)))
def test_a_boolean_or_a_string_is_never_a_number(path, value):
    msg = _refused({path: value})
    assert f"parameter '{path}': must be a number (got " in msg


@pytest.mark.parametrize(("value", "shown"), [(True, "true"), (False, "false"), ("0.5", '"0.5"')])
def test_the_reported_type_mistakes_are_refused(value, shown):
    for path in ("driveline.ratio", "valve.play_exponent"):
        assert _refused({path: value}) == f"parameter '{path}': must be a number (got {shown})"


def test_integers_still_pass_as_numbers(tmp_path):
    p = wc.load_params(overrides={"driveline.ratio": 1, "valve.play_exponent": 4, "friction.mu_slip_poly": [0, 1, 3]})
    assert p.driveline.ratio == 1.0 and isinstance(p.driveline.ratio, float)
    assert p.valve.play_exponent == 4.0 and p.friction.mu_slip_poly == [0.0, 1.0, 3.0]
    f = tmp_path / "p.toml"
    f.write_text("[driveline]\nratio = 1\n")
    assert wc.load_params(f).driveline.ratio == 1.0


def test_a_boolean_in_a_parameter_file_is_refused(tmp_path):
    f = tmp_path / "p.toml"
    f.write_text("[driveline]\nratio = true\n")
    with pytest.raises(ParameterError, match=r"^parameter file '.*p.toml': parameter 'driveline.ratio': must be a number "
                       r"\(got true\)$"):
        wc.load_params(f)


def test_a_string_in_a_list_is_refused_by_index():
    assert _refused({"friction.mu_slip_poly": [1e-3, "2"]}) == \
        "parameter 'friction.mu_slip_poly.1': must be a number (got \"2\")"


# --- what was given, and why it is wrong


@pytest.mark.parametrize(("path", "value", "shown"), [
    ("engage.T_cap", float("nan"), "nan"), ("engage.T_cap", float("inf"), "inf"),
    ("driveline.eta", -math.inf, "-inf"), ("friction.mu_slip_poly", [0.01, float("nan")], None),
])
def test_a_value_that_is_not_finite_is_said_to_be_so(path, value, shown):
    msg = _refused({path: value})
    assert "must be a finite number" in msg and "less than" not in msg and "greater than" not in msg
    if shown:
        assert msg == f"parameter '{path}': must be a finite number (got {shown})"


@pytest.mark.parametrize(("value", "shown"), [({"a": 1}, "{a = 1}"), ([1.0, 2.0], "[1.0, 2.0]")])
def test_a_table_or_an_array_given_for_a_number_is_shown(value, shown):
    assert _refused({"engage.T_cap": value}) == f"parameter 'engage.T_cap': must be a number (got {shown})"


# --- parameters that must fit together, checked as the record is built


@pytest.mark.parametrize(("overrides", "names"), [
    ({"driveline.ratio_min": 3.0}, ("driveline.ratio_min 3", "driveline.ratio_max 2.5")),
    ({"hydraulics.p_relief": 1.0}, ("hydraulics.p_relief 1 Pa", "hydraulics.p_prestress 50000 Pa")),
    ({"hydraulics.p_prestress": 9e5}, ("hydraulics.p_supply 800000 Pa", "hydraulics.p_prestress 900000 Pa")),
    # the stroke alone lifts the kiss point above the supply: 50000 Pa + k_reset 0.05 m / 0.0105 m^2
    ({"hydraulics.x_contact": 0.05, "hydraulics.A_p": 0.0105}, ("hydraulics.p_supply", "hydraulics.p_prestress")),
])
def test_parameters_that_do_not_fit_together_are_refused_naming_both(overrides, names):
    msg = _refused(overrides)
    assert all(n in msg for n in names), msg


@pytest.mark.parametrize("item", ["driveline.ratio_min=3", "hydraulics.p_relief=1", "hydraulics.p_prestress=900000",
                                  "friction.mu_slip_poly=[-0.03]", "driveline.ratio=true", "engage.T_cap={a=1}"])
def test_params_show_refuses_in_one_line(capsys, item):
    assert main(["params", "show", "--set", item]) == 2
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("wetclutch: error: ") and item.split("=")[0] in err[0]
    assert "Traceback" not in captured.err


@settings(max_examples=200, deadline=None)
@given(st.floats(0.06, 20.0), st.floats(0.06, 20.0), st.floats(0.06, 20.0))
def test_the_cvt_limits_load_if_and_only_if_they_are_in_order(ratio, lo, hi):
    # the launch ratio itself may lie outside them (an identified ratio a little below the CVT's lowest, a rig's
    # fixed gear): only the post-sync hold, which shifts within them, asks for it inside
    over = {"driveline.ratio": ratio, "driveline.ratio_min": lo, "driveline.ratio_max": hi}
    if lo <= hi:
        assert wc.load_params(overrides=over).driveline.ratio == ratio
    else:
        msg = _refused(over)
        assert ("driveline.ratio_min" in msg) and ("driveline.ratio_max" in msg)


@settings(max_examples=200, deadline=None)
@given(st.floats(0.0, 5e6), st.floats(1e3, 5e6), st.floats(1e3, 5e6), st.floats(1e-4, 0.05))
def test_the_kiss_point_loads_if_and_only_if_below_supply_and_relief(prestress, supply, relief, stroke):
    over = {"hydraulics.p_prestress": prestress, "hydraulics.p_supply": supply, "hydraulics.p_relief": relief,
            "hydraulics.x_contact": stroke}
    h = wc.Params().hydraulics
    kiss = prestress + h.k_reset * stroke / h.A_p
    if kiss < min(supply, relief):
        wc.load_params(overrides=over)
    else:
        msg = _refused(over)
        assert "hydraulics.p_prestress" in msg and ("hydraulics.p_supply" in msg or "hydraulics.p_relief" in msg)


def test_a_section_changed_in_place_is_checked_too():
    p = wc.Params()
    with pytest.raises(ValueError, match="driveline.ratio_max"):
        p.driveline.ratio_min = 3.0
    with pytest.raises(pm.ParameterError, match=r"^parameter 'driveline.ratio': must be a number \(got true\)$"):
        p.driveline.ratio = True
    assert p.driveline.ratio_min == 0.4 and p.driveline.ratio == 0.5


def test_overrides_take_numpy_arrays_tuples_and_numbers():
    # np.polyfit's coefficients are what an engineer passes for a friction curve
    coef = np.polyfit([0.0, 50.0, 100.0], [0.026, 0.035, 0.036], 2)
    p = pm.load(overrides={"friction.mu_slip_poly": coef, "driveline.ratio": np.float32(0.6)})
    assert p.friction.mu_slip_poly == coef.tolist() and p.driveline.ratio == pytest.approx(0.6)
    assert pm.load(overrides={"friction.mu_slip_poly": tuple(coef)}).friction.mu_slip_poly == coef.tolist()
    with pytest.raises(pm.ParameterError, match=r"friction.mu_slip_poly.0.: must be a number"):
        pm.load(overrides={"friction.mu_slip_poly": np.array([True, False])})


def test_a_parameter_file_with_a_byte_order_mark_loads(tmp_path):
    # Windows editors (Notepad) start a UTF-8 file with a byte-order mark, which TOML's parser takes for a statement
    f = tmp_path / "bom.toml"
    f.write_bytes(b"\xef\xbb\xbf[driveline]\nratio = 0.6\n")
    assert pm.load(f).driveline.ratio == 0.6


@pytest.mark.parametrize("text, fragment", [("kind = 'launch'\n", "unknown parameter 'kind'"),
                                            ("[driveline]\nratio = -1\n", "driveline.ratio")])
def test_an_error_in_a_parameter_file_names_the_file(tmp_path, text, fragment):
    # a controller file given as a parameter file, or a value out of range: the file is named, with or without
    # overrides on top
    f = tmp_path / "plant.toml"
    f.write_text(text)
    for overrides in (None, {"driveline.J_1": 0.002}):
        with pytest.raises(pm.ParameterError, match=f"^parameter file '{f}': .*{fragment}"):
            pm.load(f, overrides)
