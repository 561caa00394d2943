"""Designs of a plant, controller files, verification ranges: closed forms, round trips, bad input."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
import tomli_w
from hypothesis import given, settings
from hypothesis import strategies as st

from wetclutch.errors import WetclutchError
from wetclutch.launch import design as designs
from wetclutch.launch import ranges
from wetclutch.launch import settings as files
from wetclutch.params import Friction, Params, load
from wetclutch.physics import oil


@pytest.fixture(scope="module")
def plant():
    return load(overrides={"hydraulics.p_prestress": 0.7e5, "driveline.ratio": 0.7, "friction.mu_scale": 1.1})


@pytest.fixture(scope="module", params=["launch", "baseline"])
def design(request, plant):
    return designs.design(plant, request.param, {"driveline.ratio": "identified"})


def test_the_design_takes_the_plants_kiss_point_ratio_and_friction(plant):
    d = designs.design(plant, "launch", {"hydraulics.p_prestress": "identified"})
    h = plant.hydraulics
    assert d.settings["p_kiss"] == pytest.approx(h.p_prestress + h.k_reset * h.x_contact / h.A_p)
    assert d.settings["ratio"] == 0.7
    assert d.settings["mu0"] == pytest.approx(2.6e-2 * 1.1)
    assert "identified" in d.sources["p_kiss"] and "default" in d.sources["p_kiss"]


def test_the_rate_gain_feeds_back_the_same_flow_where_the_oil_is_stiffer():
    # Merritt's oil with entrained air, isothermal: air volume x0 p_atm / p_abs per atmospheric volume, and
    # 1/K_eff = (1 - x)/K_oil + x/p_abs with x the air's share of the volume
    p_atm, x0 = 101325.0, 0.005
    k_oil = oil.bulk_modulus(designs.RATE_GAIN_TEMP_C, air_fraction=0.0)

    def compliance(p):
        v = x0 * p_atm / (p_atm + p)
        x = v / (v + 1.0 - x0)
        return (1.0 - x) / k_oil + x / (p_atm + p)

    ref = Params()
    p_ref = ref.hydraulics.p_prestress + ref.hydraulics.k_reset * ref.hydraulics.x_contact / ref.hydraulics.A_p
    high = load(overrides={"hydraulics.p_prestress": 1.8e5, "hydraulics.air_fraction": x0})
    d = designs.design(high, "launch")
    share = compliance(d.settings["p_kiss"]) / compliance(p_ref)
    assert d.settings["kd_p"] == pytest.approx(designs.LAUNCH_DEFAULTS["kd_p"] * share, rel=1e-9)
    # air alone would make it the square of the absolute pressures' ratio; the oil's own compliance a little more
    assert ((p_atm + p_ref) / (p_atm + d.settings["p_kiss"])) ** 2 < share < 0.5
    assert "compliance" in d.sources["kd_p"]
    # the default rig and lower kiss points keep the default
    for p in (ref, load(overrides={"hydraulics.p_prestress": 0.2e5})):
        assert designs.design(p, "launch").settings["kd_p"] == designs.LAUNCH_DEFAULTS["kd_p"]


def test_the_high_dither_starts_at_the_default_rigs_absolute_pressure():
    def kiss(p):
        h = p.hydraulics
        return h.p_prestress + h.k_reset * h.x_contact / h.A_p

    default = designs.LAUNCH_DEFAULTS["dither_high_above"]
    start = kiss(Params()) + default  # gauge pressure from which the default rig's torque dither is the high one
    for prestress in (0.2e5, 0.5e5, 0.9e5, 1.3e5, 1.8e5, 2.5e5):
        p = load(overrides={"hydraulics.p_prestress": prestress})
        above = designs.design(p, "launch").settings["dither_high_above"]
        if kiss(p) <= kiss(Params()):
            assert above == default
        else:
            assert above == pytest.approx(max(start - kiss(p), 0.0), abs=1e-6)
    assert designs.design(load(overrides={"hydraulics.p_prestress": 1.8e5}), "launch").settings["dither_high_above"] == 0.0


def test_friction_curve_slope_keeps_the_mean_over_the_slip_span():
    poly = [-1.7e-6, 2.7e-4, 2.6e-2]
    w = np.linspace(0.0, 150.0, 30001)
    for slope in (0.0, 0.5, 1.0, 2.0):
        c = Friction(mu_slip_poly=poly, mu_scale=1.2, mu_slope=slope, mu_slip_span=150.0).curve()
        # the mean friction over the launch's slip (trapezoidal quadrature) is the level alone
        assert np.trapezoid(np.polyval(c, w), w) / 150.0 == pytest.approx(
            1.2 * np.trapezoid(np.polyval(poly, w), w) / 150.0, rel=1e-9)
        # the change of mu with slip scales with the slope
        assert np.polyval(c, 150.0) - np.polyval(c, 0.0) == pytest.approx(
            1.2 * slope * (np.polyval(poly, 150.0) - np.polyval(poly, 0.0)))
    # no slope: a flat curve at the mean (about 0.0335 for the study's fit)
    assert Friction(mu_slip_poly=poly, mu_slope=0.0).curve()[-1] == pytest.approx(0.0335, abs=1e-4)
    np.testing.assert_array_equal(Friction(mu_slip_poly=poly).curve(), np.array(poly))


def test_two_point_fit_recovers_a_first_order_plus_dead_time_step():
    t = np.arange(0.0, 2.0, 1e-4)
    k, tau, theta, t0 = 40.0, 0.03, 0.012, 1.0
    s = np.maximum(t - t0 - theta, 0.0)
    y = 5.0 + k * (1.0 - np.exp(-s / tau))
    rise, tau_f, theta_f = designs.step_fit(t, y, t0)
    assert rise == pytest.approx(k, rel=1e-4)
    assert tau_f == pytest.approx(tau, abs=3e-4) and theta_f == pytest.approx(theta, abs=3e-4)


def test_a_controller_file_round_trips_bit_for_bit(design):
    back = files.loads(files.to_toml(design))
    assert back.kind == design.kind and back.plant == design.plant and back.settings == design.settings
    np.testing.assert_array_equal(designs.record(back), designs.record(design))
    assert back.sources == design.sources


KI_T = f"[settings.ki_t]\nvalue = {designs.LAUNCH_DEFAULTS['ki_t']!r}"


def _edit(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


@pytest.mark.parametrize(("change", "fragment"), [
    (lambda t: _edit(t, 'kind = "launch"', 'kind = "fuzzy"'), "kind"),
    (lambda t: _edit(t, "[settings.hold_offset]", "[settings.hold_offsett]"), "settings.hold_offsett"),
    (lambda t: _edit(t, f'{KI_T}\nunit = "1/s"', f'{KI_T}\nunit = "1/min"'), "settings.ki_t.unit"),
    (lambda t: _edit(t, KI_T, '[settings.ki_t]\nvalue = -8.0'), "settings.ki_t.value"),
    (lambda t: _edit(t, KI_T, '[settings.ki_t]\nvalue = "fast"'), "settings.ki_t.value"),
    (lambda t: _edit(t, "temps_C = [", "temps_C = [10.0, "), "tables.temps_C"),
    (lambda t: _edit(t, "[plant.driveline]", "[plant.driveline]\nwarp = 9"), "plant"),
    (lambda t: t + "\n[extra]\na = 1\n", "unknown section 'extra'"),
    (lambda t: t[: len(t) // 2] + "= =", "TOML"),
])
def test_bad_controller_files_are_one_line_errors_naming_the_field(change, fragment):
    text = files.to_toml(designs.cached(Params(), "launch"))
    with pytest.raises(files.ControllerFileError) as e:
        files.loads(change(text), "c.toml")
    msg = str(e.value)
    assert fragment in msg and "\n" not in msg


def test_a_controller_file_of_another_kind_is_refused():
    text = files.to_toml(designs.cached(Params(), "baseline"))
    with pytest.raises(files.ControllerFileError, match="baseline controller, but a launch controller"):
        files.loads(text, "b.toml", "launch")


# ---------------------------------------------------------------- ranges


def test_the_shipped_ranges_cover_what_drifts():
    rs = {r.name: r for r in ranges.load()}
    assert rs["kiss_point"].how == "offset" and rs["kiss_point"].high == pytest.approx(0.3e5)
    assert (rs["fill_volume"].low, rs["fill_volume"].high) == (0.7, 1.3)
    assert (rs["oil_temp"].low, rs["oil_temp"].high) == (10.0, 100.0)
    assert rs["output_inertia"].high == 10.0 and (rs["cvt_ratio"].low, rs["cvt_ratio"].high) == (0.4, 1.0)
    assert rs["request"].low == 25.0 and rs["request"].high == 200.0
    # on the built-in rig every shipped range lies within the physical range: nothing is limited
    _, notes = ranges.fit(list(rs.values()), Params())
    assert notes == []


def test_ranges_apply_relative_offset_and_absolute_values(plant):
    rs = ranges.parse({"a": {"target": "driveline.J_1", "how": "rel", "low": 1, "high": 10},
                       "b": {"target": "hydraulics.p_prestress", "how": "offset", "low": -0.3e5, "high": 0.3e5},
                       "c": {"target": "driveline.ratio", "low": 0.4, "high": 1.0},
                       "d": {"target": "oil_temp_C", "low": 10, "high": 100, "dist": "normal"}})
    p, cond = ranges.apply(rs, {"a": 3.0, "b": -0.1e5, "c": 0.9, "d": 33.0}, plant)
    assert p.driveline.J_1 == pytest.approx(3 * plant.driveline.J_1)
    assert p.hydraulics.p_prestress == pytest.approx(plant.hydraulics.p_prestress - 0.1e5)
    assert p.driveline.ratio == 0.9 and cond == {"oil_temp_C": 33.0}
    v = np.array([rs[3].draw(np.random.default_rng(i)) for i in range(2000)])
    assert v.min() >= 10 and v.max() <= 100 and abs(v.mean() - 55) < 1.5 and 20 < v.std() < 23  # truncated at 2 sigma


@pytest.mark.parametrize(("data", "fragment"), [
    ({"x": {"target": "driveline.warp", "low": 0, "high": 1}}, "[x].target"),
    ({"x": {"target": "driveline.ratio", "low": 2, "high": 1}}, "[x].low"),
    ({"x": {"target": "driveline.ratio", "low": 0.4}}, "missing key 'high'"),
    ({"x": {"target": "driveline.ratio", "how": "times", "low": 0, "high": 1}}, "[x].how"),
    ({"x": {"target": "oil_temp_C", "how": "rel", "low": 0, "high": 1}}, "absolute values only"),
    ({"x": {"target": "driveline.ratio", "low": 0, "high": 1, "colour": "red"}}, "unknown key 'colour'"),
    ({"x": {"target": "driveline.ratio", "low": 0.4, "high": 1, "dist": "cauchy"}}, "[x].dist"),
    ({"x": {"target": "driveline.ratio", "low": 0.4, "high": 1, "corner": "yes"}}, "[x].corner"),
    ({"x": {"target": "driveline.ratio", "low": 0.4, "high": 1},
      "y": {"target": "driveline.ratio", "low": 0.5, "high": 1}}, "varied by two ranges"),
    ({"x": 3}, "[x]"),
    ({}, "no ranges"),
])
def test_bad_ranges_are_one_line_errors_naming_the_range(data, fragment):
    with pytest.raises(ranges.RangesError) as e:
        ranges.parse(data, "r.toml")
    assert fragment in str(e.value) and "\n" not in str(e.value)


def test_ranges_relative_to_the_plant_are_limited_to_its_physical_range():
    # a prestress 1 bar lower on a clutch whose prestress is 0.5 bar stops at zero; entrained air 200 times the
    # plant's 0.005 stops below a volume fraction of 0.5; what stays within is left as it is
    rs = ranges.parse({"kiss": {"target": "hydraulics.p_prestress", "how": "offset", "low": -1e5, "high": 0.2e5},
                       "air": {"target": "hydraulics.air_fraction", "how": "rel", "low": 0.5, "high": 200.0},
                       "ratio": {"target": "driveline.ratio", "low": 0.4, "high": 1.0}})
    fitted, notes = ranges.fit(rs, Params())
    by = {r.name: r for r in fitted}
    assert by["kiss"].low == pytest.approx(-0.5e5, abs=1.0) and by["kiss"].high == 0.2e5
    assert by["air"].low == 0.5 and by["air"].high == pytest.approx(100.0, abs=1e-3)
    # the ratio range, within the physical range, is not limited
    assert len(notes) == 2 and notes[0].startswith("kiss") and notes[1].startswith("air")
    for r in fitted:
        for end in (r.low, r.high):
            ranges.apply([r], {r.name: end}, Params())  # raises if out of the physical range


@pytest.mark.parametrize("data, fragment", [
    # an absolute range does not depend on the plant: an end out of the physical range is the file's error
    ({"x": {"target": "hydraulics.air_fraction", "low": 0.0, "high": 0.7}}, r"\[x\] at 0.7"),
    # no value of the range is within it
    ({"kiss": {"target": "hydraulics.p_prestress", "how": "offset", "low": -2e5, "high": -1e5}}, r"\[kiss\] at -200000"),
])
def test_ranges_that_leave_the_physical_range_are_refused_up_front(data, fragment):
    with pytest.raises(ranges.RangesError, match=fragment) as e:
        ranges.fit(ranges.parse(data), Params())
    assert "\n" not in str(e.value)


_value = st.one_of(st.floats(allow_nan=True), st.integers(-5, 5), st.text(max_size=5), st.booleans(),
                   st.lists(st.integers(), max_size=2))


_entry = st.dictionaries(
    st.sampled_from(["target", "how", "dist", "low", "high", "corner", "unit", "zz"]),
    st.one_of(_value, st.sampled_from(["driveline.ratio", "oil_temp_C", "rel", "abs", "normal", "uniform"])))


@settings(max_examples=150, deadline=None)
@given(st.dictionaries(st.text(min_size=1, max_size=8), st.one_of(_value, _entry), max_size=3))
def test_any_ranges_table_parses_or_gives_one_line(data):
    try:
        out = ranges.parse(data, "r.toml")
    except WetclutchError as e:
        assert "\n" not in str(e)
    else:
        assert all(r.low <= r.high for r in out)


def _without(text: str, name: str) -> str:
    data = tomllib.loads(text)
    del data["settings"][name]
    return tomli_w.dumps(data)


def test_a_controller_file_without_a_later_setting_takes_its_default():
    """A file written before a setting existed: a controller default fills in, saying so, and a setting the design
    takes from the plant comes from the file's [plant] (the reset spring's stroke span, k_reset x_contact / A_p);
    a controller kind's setting that is neither is an error naming it."""
    p = Params()
    design = designs.cached(p, "launch")
    text = files.to_toml(design)
    back = files.loads(_without(_without(text, "dither_hz_high"), "stroke_span"), "c.toml")
    # the design that wrote the file ran the default and took the stroke span from the same plant: the file
    # without either runs the same controller
    np.testing.assert_array_equal(designs.record(back), designs.record(design))
    assert back.sources["dither_hz_high"] == "controller default (not in the file)"
    base = files.to_toml(designs.cached(p, "baseline"))
    with pytest.raises(files.ControllerFileError, match=r"c\.toml: settings\.kp: missing"):
        files.loads(_without(base, "kp"), "c.toml")


def test_the_torque_dither_is_as_much_wider_as_the_magnets_play():
    """The dither must be wider than the play (input volts: I_hyst / g_current); a wider play than the default rig's
    widens it by the same factor, a narrower one keeps the default."""
    base = designs.LAUNCH_DEFAULTS["dither_amp_torque"]
    ref = Params().valve.I_hyst / Params().valve.g_current
    for over, factor in (({}, 1.0), ({"valve.I_hyst": 0.03}, 1.0), ({"valve.I_hyst": 0.08}, 0.08 / 0.2 / ref),
                         ({"valve.I_hyst": 0.06, "valve.g_current": 0.15}, 0.06 / 0.15 / ref)):
        d = designs.design(load(overrides=over))
        assert d.settings["dither_amp_torque"] == pytest.approx(base * factor, rel=1e-12)
        assert ("play" in d.sources["dither_amp_torque"]) == (factor > 1.0)
