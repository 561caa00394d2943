"""Bad input through the Python API: one line, an exception of wetclutch's own, naming the argument as a Python caller
spells it (the command line's option names are for the command line), before any simulation."""

import pickle

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import wetclutch as wc
from wetclutch import ident, launch
from wetclutch.errors import WetclutchError
from wetclutch.launch import design as designs
from wetclutch.launch import verify
from wetclutch.launch.adaptation import Adaptation
from wetclutch.rig import experiments as rig


def refused(call, *fragments):
    """The one-line WetclutchError that ``call()`` raises; each of ``fragments`` is in it."""
    with pytest.raises(WetclutchError) as e:
        call()
    msg = str(e.value)
    assert "\n" not in msg
    for f in fragments:
        assert f in msg, msg
    return msg


@given(text=st.text(max_size=12))
def test_an_error_quoting_any_name_is_one_line_that_names_it(text):
    # a name read from the user's file (a column, a key) may hold any line break str.splitlines knows
    msg = str(WetclutchError(f"column '{text}' is unknown"))
    assert len(msg.splitlines()) == 1 and msg.startswith("column '") and msg.endswith("' is unknown")
    # every character of the name that is not a line break is shown, in its order
    kept = (c for c in text if len(f"a{c}b".splitlines()) == 1)
    rest = iter(msg[len("column '"):])
    assert all(c in rest for c in kept)


@pytest.fixture(scope="module")
def d():
    return designs.cached(wc.Params(), "launch")


# --- the parameter record ---------------------------------------------------------------------------------------------

def test_assigning_a_refused_value_is_one_line_naming_the_parameter():
    p = wc.Params()
    refused(lambda: setattr(p.driveline, "ratio", -1), "driveline.ratio")
    refused(lambda: setattr(p.driveline, "ratio", "x"), "driveline.ratio", "must be a number")
    refused(lambda: setattr(p.driveline, "foo", 1), "unknown parameter 'driveline.foo'")
    refused(lambda: setattr(p, "driveline", 5), "'driveline'")
    assert p.driveline.ratio == 0.5
    with pytest.raises(wc.ParameterError):
        p.driveline.ratio = -1


def test_an_assignment_is_checked_with_the_rest_of_its_record():
    # mu(slip) must stay positive up to omega_p0: a check across two sections
    p = wc.Params()
    refused(lambda: setattr(p.friction, "mu_slip_poly", [-0.02]), "friction.mu_slip_poly")
    refused(lambda: setattr(p.driveline, "omega_p0", 500.0), "friction.mu_slip_poly", "omega_p0")
    assert p == wc.Params()
    # the copies of a record are checked so too
    for q in (pickle.loads(pickle.dumps(p)), p.model_copy()):
        refused(lambda: setattr(q.friction, "mu_slip_poly", [-0.02]), "friction.mu_slip_poly")


def test_a_copy_shares_nothing_with_the_original():
    p = wc.Params()
    q = p.model_copy()
    q.driveline.ratio = 0.7
    r = wc.Params(driveline=p.driveline)
    r.driveline.ratio = 0.8
    assert p.driveline.ratio == 0.5
    refused(lambda: p.model_copy(update={"driveline": 5}), "'driveline'")
    refused(lambda: p.driveline.model_copy(update={"ratio": -1.0}), "driveline.ratio")
    assert p.model_copy(update={"driveline": {"ratio": 0.6}}).driveline.ratio == 0.6


def test_building_a_record_is_one_line():
    refused(lambda: wc.Params(driveline={"ratio": -1}), "driveline.ratio")
    refused(lambda: wc.Params(foo=1), "unknown parameter 'foo'")
    refused(lambda: wc.Params.model_validate("x"), "parameter set")
    refused(lambda: wc.Params.model_validate_json('{"driveline": {"ratio": -1}}'), "driveline.ratio")


@pytest.mark.parametrize("kwargs, fragment", [
    ({"overrides": [("driveline.ratio", 1)]}, "overrides"), ({"overrides": "driveline.ratio=1"}, "overrides"),
    ({"overrides": {1: 2}}, "parameter path"), ({"param_file": 5}, "param_file"), ({"base": {}}, "base")])
def test_load_params_refuses_arguments_of_the_wrong_kind(kwargs, fragment):
    refused(lambda: wc.load_params(**kwargs), fragment)


# --- wetclutch.simulate -----------------------------------------------------------------------------------------------

def test_simulate_refuses_a_scenario_that_is_no_name():
    refused(lambda: wc.simulate(["engage"]), "scenario")


# --- a launch -----------------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs, fragment", [
    ({"t_ref": -5.0}, "t_ref must be"), ({"oil_temp_C": 400.0}, "oil_temp_C"), ({"profile": "zigzag"}, "profile must"),
    ({"noise_scale": -1.0}, "noise_scale must"), ({"seed": -1}, "seed must"), ({"hold_time": 0.0}, "hold_time must"),
])
def test_conditions_name_the_field_not_the_option(kwargs, fragment):
    msg = refused(lambda: launch.Conditions(**kwargs).checked(), fragment)
    assert "--" not in msg


@pytest.mark.parametrize("kwargs, fragment", [
    ({"t_ref": "100"}, "t_ref"), ({"t_ref": None}, "t_ref"), ({"t_ref": True}, "t_ref"), ({"t_ref": np.ones(2)}, "t_ref"),
    ({"profile": None}, "profile"), ({"profile": 5}, "profile"), ({"oil_temp_C": "41"}, "oil_temp_C"),
    ({"t_request": "1"}, "t_request"), ({"t_request": -1.0}, "t_request"), ({"t_after": -1.0}, "t_after"),
    ({"t_after": float("nan")}, "t_after"), ({"t_max": "5"}, "t_max"), ({"dt": "0.001"}, "dt"),
    ({"seed": 1.5}, "seed"), ({"seed": "1"}, "seed"), ({"seed": None}, "seed"), ({"noise": "no"}, "noise"),
    ({"noise_scale": "1"}, "noise_scale"), ({"post_sync_hold": "yes"}, "post_sync_hold"),
    ({"hold_time": "1"}, "hold_time"), ({"rtol": "1e-5"}, "rtol"), ({"hold_time": 2.0}, "post_sync_hold"),
])
def test_conditions_of_the_wrong_kind_are_one_line(kwargs, fragment):
    refused(lambda: launch.Conditions(**kwargs).checked(), fragment)


@given(st.one_of(st.text(max_size=5), st.none(), st.booleans(), st.lists(st.floats(), max_size=2),
                 st.dictionaries(st.text(max_size=2), st.integers(), max_size=2)))
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_any_non_number_for_a_number_is_one_line(value):
    for name in ("t_ref", "t_request", "t_after", "dt", "noise_scale", "rtol"):
        refused(lambda: launch.Conditions(**{name: value}).checked(), name)


def test_checked_conditions_hold_python_numbers():
    c = launch.Conditions(t_ref=np.float32(80.0), seed=np.int64(3), noise=np.bool_(True)).checked()
    assert type(c.t_ref) is float and type(c.seed) is int and type(c.noise) is bool


def test_launch_refuses_arguments_of_the_wrong_kind(d):
    p, c = wc.Params(), launch.Conditions(t_max=2.0)
    refused(lambda: launch.simulate(d, d, c), "params")
    refused(lambda: launch.simulate({}, d, c), "params")
    refused(lambda: launch.simulate(p, p, c), "controller")
    refused(lambda: launch.simulate(p, None, c), "controller")
    refused(lambda: launch.simulate(p, d, {"t_ref": 50}), "conditions")
    refused(lambda: launch.simulate(p, d, c, nominal=5), "nominal")
    refused(lambda: launch.simulate(p, d, c, adaptation={}), "adaptation")
    learnt = Adaptation().learn(85.0, 0.7e5)
    refused(lambda: launch.simulate(p, designs.cached(p, "baseline"), c, adaptation=learnt), "baseline")


@pytest.mark.parametrize("n", [0, "2", 1.5, None, True])
def test_a_sequence_names_its_length(d, n):
    msg = refused(lambda: launch.loop.sequence(wc.Params(), d, launch.Conditions(t_max=2.0), n), "n must")
    assert "--sequence" not in msg


def test_design_refuses_arguments_of_the_wrong_kind(d):
    refused(lambda: designs.design("x"), "plant")
    refused(lambda: designs.design(d), "plant", "Design")
    refused(lambda: designs.design(wc.Params(), ["launch"]), "kind")
    refused(lambda: designs.cached(wc.Params(), ["launch"]), "kind")
    refused(lambda: designs.cached("x"), "plant")
    refused(lambda: designs.design(wc.Params(), "launch", "x"), "origin")
    refused(lambda: designs.record(d, "0.001"), "dt")
    refused(lambda: designs.with_settings(d, kd_p=float("nan")), "kd_p")
    refused(lambda: designs.with_settings(d, kd_p="1"), "kd_p")


# --- verification -------------------------------------------------------------------------------------------------------

def test_verify_names_its_arguments(d):
    opts = {"workers": 1, "corners": False, "progress": False}
    p = wc.Params()
    refused(lambda: verify.run(p, p, n=1, **opts), "design")
    refused(lambda: verify.run(d, d, n=1, **opts), "plant")
    refused(lambda: verify.run(d, n=-1, **opts), "n must")
    refused(lambda: verify.run(d, n="2", **opts), "n must")
    refused(lambda: verify.run(d, n=1, seed=1.5, **opts), "seed")
    refused(lambda: verify.run(d, n=1, seed=-1, **opts), "seed must")
    refused(lambda: verify.run(d, n=1, **opts | {"workers": 0}), "workers must")
    refused(lambda: verify.run(d, n=1, sequence=0, **opts), "sequence must")
    refused(lambda: verify.run(d, n=1, ranges="r.toml", **opts), "ranges")
    refused(lambda: verify.run(d, n=1, ranges=[1], **opts), "ranges[0]")
    msg = refused(lambda: verify.run(d, n=1, profile="zigzag", **opts), "profile must")
    assert "--" not in msg


def test_verify_with_nothing_to_verify_is_refused_not_nan(d):
    refused(lambda: verify.run(d, n=0, workers=1, corners=False, progress=False), "nothing to verify")


# --- identification and the rig -------------------------------------------------------------------------------------

def test_identify_refuses_what_is_no_recording():
    refused(lambda: ident.identify("file.csv"), "recordings")
    refused(lambda: ident.identify(["file.csv"]), "recordings[0]", "ident.load")
    refused(lambda: ident.identify([wc.Params()]), "recordings[0]")
    refused(lambda: ident.identify([], prior="x"), "prior")


@pytest.mark.parametrize("kwargs, fragment", [
    ({"level": "1"}, "level"), ({"oil_temp_C": "41"}, "oil_temp_C"), ({"rate_hz": "1000"}, "rate_hz"),
    ({"seed": 1.5}, "seed"), ({"seed": "1"}, "seed"), ({"t_end": "2"}, "t_end"), ({"noise": "no"}, "noise"),
    ({"input_mode": ["dc"]}, "input_mode"), ({"level": -1.0}, "level"), ({"t_end": -1.0}, "t_end must"),
])
def test_rig_settings_name_the_field(kwargs, fragment):
    msg = refused(lambda: rig.run("step", **kwargs), fragment)
    assert "--" not in msg


def test_rig_refuses_arguments_of_the_wrong_kind():
    refused(lambda: rig.run(["step"]), "experiment")
    refused(lambda: rig.run("step", {}), "params")


def test_a_trajectory_asked_for_an_element_it_has_not_names_the_ones_it_has():
    tr = wc.simulate("coupled-clutches", t_end=0.2).trajectory
    refused(lambda: tr.speed("J9"), "no body named 'J9'", "J1, J2, J3, J4")
    refused(lambda: tr.clutch_torque("J1"), "no clutch named 'J1'")


@pytest.mark.parametrize("args, fragment", [((5,), "path must be"), (("x.csv", "x"), "channel_map must be")])
def test_a_recording_given_as_something_else_is_one_line(args, fragment):
    refused(lambda: ident.load(*args), fragment)
