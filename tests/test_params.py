"""Parameter record: dotted paths, TOML round trip, one-line errors (property-based where it pays)."""

from __future__ import annotations

import tomllib

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import wetclutch as wc
from wetclutch import params as pm
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
