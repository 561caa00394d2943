"""Closed-loop launches: the controller against the requirements, the loop's plumbing, the baseline."""

import numpy as np
import pandas as pd
import pytest

from wetclutch.launch import controller as control
from wetclutch.launch import design as designs
from wetclutch.launch import loop as launch
from wetclutch.launch import metrics, ranges, verify
from wetclutch.launch.adaptation import Adaptation
from wetclutch.errors import WetclutchError
from wetclutch.params import Params
from wetclutch.plant import clutch
from wetclutch.params import load as params_load
from wetclutch.physics import friction, oil


@pytest.fixture(scope="module")
def nominal():
    return launch.simulate(Params(), "launch", launch.Conditions(t_ref=100.0, oil_temp_C=85.0))


@pytest.mark.parametrize("temp", [41.0, 85.0])
@pytest.mark.parametrize("t_ref", [50.0, 150.0])
def test_nominal_launches_reach_the_request(temp, t_ref):
    res = launch.simulate(Params(), "launch", launch.Conditions(t_ref=t_ref, oil_temp_C=temp))
    s = res.summary
    assert s["requirements"]["steady_state_error"], s
    assert s["t95_s"] < metrics.REQ_T95_S, s
    assert s["creep_Nm"] <= metrics.REQ_CREEP_NM, s
    assert s["t_sync_s"] is not None and s["t_sync_s"] > 1.5


def test_the_fair_baseline_fills_holds_and_meets_its_tuning_target():
    base = launch.simulate(Params(), "baseline", launch.Conditions(t_ref=100.0, oil_temp_C=85.0))
    s = base.summary
    assert s["controller"] == "baseline"
    # the SIMC rule aims at a 95 % time of 0.15 s; a plain PI without fill would need the dead time of the fill on top
    assert s["t95_settled_s"] < metrics.REQ_T95_S and s["overshoot_pct"] < 10.0, s
    assert s["creep_Nm"] <= metrics.REQ_CREEP_NM
    sig = base.signals
    # the timed fill pulse: full input from the start, for the design's fill time at 85 C
    d = designs.cached(Params(), "baseline")
    pulse = sig.time[(sig.u >= 4.999) & (sig.time < 1.0)].max()
    assert pulse == pytest.approx(float(np.interp(85.0, d.temps_C, d.fill_s)), abs=2e-3)


def test_lock_up_is_found_for_a_small_request_that_locks_late():
    # 25 N m against the road load: synchronisation some 9 s after the request
    res = launch.simulate(Params(), "launch", launch.Conditions(t_ref=25.0, oil_temp_C=85.0))
    tr = res.truth
    locked = tr.locked.to_numpy().astype(bool)
    first_locked_for_good = tr.time[np.flatnonzero(~locked)[-1] + 1]
    assert res.summary["t_sync_s"] is not None
    assert res.summary["t_sync_s"] == pytest.approx(first_locked_for_good, abs=1.5e-3)


def test_signals_carry_the_rig_channels_request_and_input(nominal):
    sig = nominal.signals
    assert list(sig.columns) == ["time", *control.MEASURED, "t_ref", "u"]
    # the fill starts at the top of the rig's DC input range; the hold waits far below it
    assert np.all(sig.u[sig.time < 0.02] == 5.0)
    hold = sig.u[(sig.time > 0.5) & (sig.time < 1.0)]
    assert 0.2 < hold.min() and hold.max() < 2.0
    assert np.all(sig.t_ref[sig.time < 1.0] == 0.0) and np.all(sig.t_ref[sig.time >= 1.0] == 100.0)
    # the run stops t_after after the final lock
    assert sig.time.iloc[-1] == pytest.approx(nominal.summary["t_sync_s"] + 0.5, abs=5e-3)


def test_without_noise_the_loop_measures_the_truth():
    res = launch.simulate(Params(), "launch", launch.Conditions(t_ref=80.0, noise=False, t_max=2.0))
    np.testing.assert_allclose(res.signals.T_r, res.truth.T_r, atol=1e-5)
    np.testing.assert_allclose(res.signals.p_clutch, res.truth.p_clutch, atol=1e-6)


@pytest.mark.parametrize("scale", [1.0, 2.0])
def test_the_noise_the_ripple_discounts_is_the_one_the_loop_reads(scale):
    # the waiting clutch's reading less the truth is the sensor's white noise and, small beside it, what the
    # sensor's filter takes off the hold's dither (some 0.13 N m RMS): the noise's deviation is what the metrics take
    # out of the ripple
    c = launch.Conditions(t_ref=60.0, t_max=1.6, noise_scale=scale)
    res = launch.simulate(Params(), "launch", c, nominal=metrics.Response.empty())
    wait = (res.signals.time > 0.6) & (res.signals.time < 1.0)
    err = (res.signals.T_r - res.truth.T_r)[wait]
    assert launch.torque_noise(c) == pytest.approx(0.5 * scale)
    assert err.std() == pytest.approx(launch.torque_noise(c), rel=0.1)
    assert launch.torque_noise(launch.Conditions(noise=False)) == 0.0


def test_slip_energy_is_the_integral_of_clutch_power(nominal):
    tr = nominal.truth
    power = tr.T_c * tr.slip
    energy = float(np.sum(0.5 * (power[1:].to_numpy() + power[:-1].to_numpy()) * np.diff(tr.time)))
    assert nominal.summary["slip_energy_J"] == pytest.approx(energy, rel=0.01)


def test_same_seed_same_launch_other_seed_other_noise():
    c = launch.Conditions(t_ref=60.0, t_max=1.6, seed=3)
    a = launch.simulate(Params(), "launch", c, nominal=metrics.Response.empty())
    b = launch.simulate(Params(), "launch", c, nominal=metrics.Response.empty())
    d = launch.simulate(Params(), "launch", launch.Conditions(t_ref=60.0, t_max=1.6, seed=4), nominal=metrics.Response.empty())
    pd.testing.assert_frame_equal(a.signals, b.signals)
    assert not np.allclose(a.signals.T_r, d.signals.T_r)


def test_ramp_and_file_profiles(tmp_path):
    t = np.arange(0.0, 2.0, 1e-3)
    ramp = launch.reference(launch.Conditions(t_ref=90.0, profile="ramp"), t)
    assert ramp[t < 1.0].max() == 0.0
    assert ramp[np.searchsorted(t, 1.0 + launch.RAMP_TIME / 2)] == pytest.approx(45.0, rel=0.01)
    f = tmp_path / "profile.csv"
    f.write_text("time,t_ref\n0,0\n0.5,120\n")
    ref = launch.reference(launch.Conditions(profile=str(f)), t)
    assert ref[np.searchsorted(t, 1.25)] == pytest.approx(60.0, rel=0.01)


@pytest.mark.parametrize("content", ["time,torque\n0,1\n1,2\n", "time,t_ref\n0,1\n0,2\n", "time,t_ref\n0,nan\n1,2\n",
                                     "time,t_ref\n0,1\n1,5000\n", "\x00\x01garbage"])
def test_bad_profile_files_are_one_line_errors(tmp_path, content):
    f = tmp_path / "bad.csv"
    f.write_text(content)
    with pytest.raises(WetclutchError) as e:
        launch.reference(launch.Conditions(profile=str(f)), np.arange(0.0, 2.0, 1e-3))
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("kwargs, field", [({"t_ref": -5.0}, "t_ref"), ({"oil_temp_C": 400.0}, "oil_temp_C"),
                                           ({"profile": "zigzag"}, "profile"), ({"noise_scale": -1.0}, "noise_scale"),
                                           ({"rtol": 0.0}, "rtol"), ({"rtol": 0.1}, "rtol")])
def test_bad_conditions_name_the_field(kwargs, field):
    # from Python the field's name (the command line names its options: test_cli)
    with pytest.raises(WetclutchError, match=f"^{field} "):
        launch.Conditions(**kwargs).checked()


def test_inverse_map_inverts_a_known_curve():
    v = designs.MAP_VOLTS
    p = (0.41 * v**2 + 0.29 * v + 0.20) * 1e5  # the study's static curve, bar -> Pa
    table = designs.inverse_map(p[None, :])[0]
    target = designs.MAP_PRESSURES
    inside = (target >= p[0]) & (target <= p[-1])
    exact = (-0.29 + np.sqrt(0.29**2 - 4 * 0.41 * (0.20 - target[inside] / 1e5))) / (2 * 0.41)
    np.testing.assert_allclose(table[inside], exact, atol=0.02)  # linear interpolation between 0.3 V points
    # pressures the curve cannot reach map to the input range's ends
    assert np.all(table[target < p[0]] == v[0]) and np.all(table[target > p[-1]] == v[-1])


def test_inverse_map_takes_the_lowest_input_of_a_flat_stretch():
    # below the piston's prestress the static pressure does not move with the input: any input there holds
    # that pressure, and the map must answer with the lowest (the fill's exit from full input relies on it)
    v = designs.MAP_VOLTS
    p = (0.41 * v**2 + 0.29 * v + 0.20) * 1e5
    stretch = (v > 1.0) & (v < 2.1)  # 1.1 to 2.0 V hold the pressure of 1.1 V
    p[stretch] = p[stretch][0]
    table = designs.inverse_map(p[None, :], v, np.array([p[stretch][0]]))[0]
    assert np.count_nonzero(stretch) == 4 and table[0] == pytest.approx(v[stretch][0], abs=1e-6)


def test_unknown_controller_is_refused():
    with pytest.raises(WetclutchError, match="unknown controller"):
        launch.simulate(Params(), "bang-bang", launch.Conditions(t_max=1.6))


def test_controller_refuses_a_friction_law_it_would_truncate():
    # an identified mu(slip) of higher order as the design: refused by name, not cut to a quadratic
    design = Params()
    design.friction.mu_slip_poly = [1e-9, -1.7e-6, 2.7e-4, 2.6e-2]
    with pytest.raises(WetclutchError, match="friction.mu_slip_poly"):
        designs.design(design, "launch")



def test_a_valve_stem_creeping_to_rest_at_its_friction_limit_does_not_stop_the_launch():
    """After lock-up the input stays at its maximum without dither and the stem creeps to rest with its force
    at the friction's limit: the force grazes the capacity, and a breakaway at once turned back into a lock
    at one instant, over and over (the run stopped as Zeno behaviour). The lock must hold instead."""
    p = params_load(overrides={
        "driveline.J_1": 0.0036197424443680823, "driveline.ratio": 0.44802753667105555,
        "driveline.eta": 0.9044077383554725, "driveline.k_a": 386.167897411133, "engage.T_load": 4.501597587588851,
        "valve.d_stem": 38.07519596421963, "hydraulics.p_supply": 709730.9372482491,
        "hydraulics.line_length": 1.0358335514366366, "hydraulics.p_prestress": 69849.8073766649,
        "hydraulics.x_contact": 0.0014987316512260955, "hydraulics.leak_85C": 3.276693878525695e-12,
        "hydraulics.air_fraction": 0.002562585228628782, "friction.mu_scale": 0.9819387434290435,
        "friction.mu_slope": 0.9083925014979395})
    cond = launch.Conditions(t_ref=177.16465154380592, oil_temp_C=71.21364455810087, seed=1854455492,
                             noise_scale=1.3066909372644664)
    res = launch.simulate(p, designs.cached(Params()), cond)
    truth = res.truth
    assert res.summary["t_sync_s"] is not None
    # locked to the end: the clutch holds once synchronised
    assert truth["locked"].iloc[-1]


def test_a_valve_stem_whose_drive_peaks_beyond_its_friction_limit_does_not_stop_the_launch():
    """In the slip phase of a cold launch the stem's drive rises to its friction's limit and turns back there,
    beyond the limit by more than the grip margin of a grazing breakaway: the stem let go and stuck again at
    one instant, over and over, and the run stopped as Zeno behaviour (a verification sample of a clutch unlike
    the built-in rig, designed on its identified parameters). The margin grows until the lock holds."""
    common = {"driveline.J_p": 1.4176964794310094, "driveline.J_s": 4.787710813881632,
              "driveline.d_a": 5.101855422739873, "valve.I_hyst": 0.049101166946017794,
              "friction.mu_slip_poly": [-1.714050214972977e-06, 0.0002720115704447912, 0.02132359188809977],
              "rig.oil_temp_C": 62.997894725}
    identified = params_load(overrides=common | {
        "driveline.ratio": 1.1711508177826708, "driveline.k_a": 474.6465399022698,
        "hydraulics.p_prestress": 112904.74621123199, "hydraulics.x_contact": 0.001111955541363847})
    plant = params_load(overrides=common | {
        "driveline.J_1": 0.003662531342585125, "driveline.ratio": 0.9439912143414949,
        "driveline.eta": 0.9672057018585315, "driveline.k_a": 472.65121809230476, "engage.T_load": 13.961703777744622,
        "valve.d_stem": 75.3321014995196, "hydraulics.p_supply": 744808.1901511743,
        "hydraulics.line_length": 1.5864221019658946, "hydraulics.p_prestress": 108631.53600226423,
        "hydraulics.x_contact": 0.0012188814792207377, "hydraulics.leak_85C": 2.5733192850438974e-12,
        "hydraulics.air_fraction": 0.0033846892433715913, "friction.mu_scale": 0.8144374214394441,
        "friction.mu_slope": 0.7526537265012098})
    cond = launch.Conditions(t_ref=175.4329235211535, oil_temp_C=11.650252413351478, seed=122296662,
                             noise_scale=0.934756696366509, t_max=2.45)
    res = launch.simulate(plant, designs.design(identified, "launch"), cond)
    # the launch runs to its end
    assert res.truth["time"].iloc[-1] == pytest.approx(cond.t_max, abs=2e-3)


@pytest.mark.parametrize("oil_temp_C, t_ref, load_Nm, seed", [(86.0, 189.0, 3.5, 1442223462), (29.0, 183.0, 9.0, 950881900)])
def test_a_heavy_clutch_output_ringing_at_a_low_ratio_does_not_keep_ringing(oil_temp_C, t_ref, load_Nm, seed):
    """A clutch output 30 times the default's at a CVT ratio of 0.41 rings against the axle at some 8 Hz (the
    default design is not told). With the friction-factor estimate's time constant fixed, the estimate follows
    the axle torque's swing and keeps the ringing up (a ripple of 22-24 % through the slip phase, measured);
    slowed while the clutch output swings back, the ringing dies out."""
    plant = params_load(overrides={"driveline.J_1": 0.03, "driveline.ratio": 0.41, "engage.T_load": load_Nm})
    cond = launch.Conditions(t_ref=t_ref, oil_temp_C=oil_temp_C, seed=seed)
    res = launch.simulate(plant, designs.cached(Params()), cond)
    assert res.summary["ripple_pct"] < metrics.REQ_RIPPLE_PCT


def test_the_requests_s_curve_is_the_raised_cosine_of_a_step():
    # a step through the moving average of ref_weights(n) is (1 - cos(pi k / n)) / 2 after k samples, 1 from n on
    n = 180
    w = control.ref_weights(n)
    assert w.sum() == pytest.approx(1.0, abs=1e-12) and np.all(w >= 0.0)
    k = np.arange(1, n + 1)
    assert np.cumsum(w) == pytest.approx((1.0 - np.cos(np.pi * k / n)) / 2.0, abs=1e-12)
    # the controller's ring buffer gives the same moving average, for a step and past the ring's length
    ctrl = designs.record(designs.cached(Params()), 1e-3)
    cs = np.zeros(control.N_CS)
    out = [control._shaped(ctrl, cs, 50.0) for _ in range(int(ctrl[control.REF_N]) + 20)]
    m = int(ctrl[control.REF_N])
    assert m == round(designs.cached(Params()).settings["ref_rise"] / 1e-3)
    assert out[:m] == pytest.approx(50.0 * np.cumsum(control.ref_weights(m)), rel=1e-12)
    assert out[m:] == pytest.approx([50.0] * 20, rel=1e-12)
    # at the shortest sample time the whole curve fits (not cut short)
    assert designs.record(designs.cached(Params()), 1e-4)[control.REF_N] == 10 * m


@pytest.mark.parametrize("j_1, ratio", [(0.001, 0.4), (0.001, 1.0), (0.02, 0.45), (0.004, 0.5), (0.004, 0.65),
                                        (0.004, 0.7)])
def test_the_request_takes_the_s_curve_where_the_clutch_output_rings(j_1, ratio):
    # the output's mode on the axle's side, J_1 / i^2 on k_a with d_a, has the damping ratio d_a i / (2 sqrt(k_a J_1));
    # the request is shaped below 1.2 of it: never for the built-in rig's output (1 g m^2) over the ratios 0.4-1
    # (below 0.33 only), for one 4 times heavier below a ratio of 0.665, for one 20 times heavier below 1.49
    d = designs.cached(Params())
    ctrl = designs.record(d, 1e-3)
    cs = np.zeros(control.N_CS)
    cs[control.CS_J1] = j_1
    meas = np.zeros(len(control.MEASURED))
    meas[control.M_RATIO] = ratio
    k_a, d_a = Params().driveline.k_a, Params().driveline.d_a
    zeta = d_a * ratio / (2.0 * np.sqrt(k_a * j_1))
    assert control._rings(ctrl, cs, meas) == (zeta < 1.2)


def test_a_heavy_clutch_output_measured_on_an_earlier_launch_settles_in_time_with_the_s_curve():
    # a clutch output 30 times the built-in rig's at a ratio of 0.45, known to the design and measured on an earlier
    # launch: through the two stages the request rings it (settled t95 0.24 s, measured); through the S-curve it
    # settles in time (0.16 s)
    plant = params_load(overrides={"driveline.J_1": 0.03, "driveline.ratio": 0.45})
    d = designs.design(plant)
    cond = launch.Conditions(t_ref=200.0, oil_temp_C=90.0, seed=2)
    known = Adaptation(inertia=0.03)
    shaped, stages = (launch.simulate(plant, dd, cond, nominal=metrics.Response.empty(), adaptation=known).summary
                      for dd in (d, designs.with_settings(d, d_a=1e5)))  # an axle damped so that nothing rings
    assert shaped["request_shaped"] and not stages["request_shaped"]
    assert shaped["t95_settled_s"] < metrics.REQ_T95_S < stages["t95_settled_s"]
    assert shaped["overshoot_pct"] < 10.0


def test_a_first_launch_takes_the_s_curve_until_a_launch_has_measured_the_clutch_output():
    # the design's J_1 is the prior's where the rig's runs do not show it, and the clutch's may be ten times as heavy:
    # until a launch has measured it the request goes through the S-curve. Measured and light (the built-in rig's
    # 1 g m^2 at its ratio of 0.7 does not ring), it goes through the two stages.
    plant = Params()
    cond = launch.Conditions(t_ref=100.0, oil_temp_C=60.0, seed=3)
    first, later = (launch.simulate(plant, designs.cached(plant), cond, adaptation=a).summary
                    for a in (None, Adaptation(inertia=plant.driveline.J_1)))
    assert first["request_shaped"] and not later["request_shaped"]
    for s in (first, later):
        assert s["all_pass"], s


def test_the_plates_touch_no_sooner_than_the_full_input_fill_allows():
    # The valve's full input from t = 0 is the fastest fill there is: ``design.fill_times`` strokes the piston
    # through 60 % of its travel that way (an open-loop run), so the plates' first contact (the true clutch torque)
    # comes later in any launch. Warm oil fills within 0.1 s, long before the request at 1 s; cold oil through a
    # feed line 1.5 times as long into a volume 1.3 times as large is still stroking at the request, and the
    # response, which cannot start before the contact, counts the rest of the fill.
    # ``fastest_contact`` is that open-loop run to the plates' contact: before the launch's own, or, in the cold,
    # none before the request (no controller fills that clutch in time).
    p = Params()
    slow = params_load(overrides={"hydraulics.x_contact": 1.3 * p.hydraulics.x_contact,
                                  "hydraulics.line_length": 1.5 * p.hydraulics.line_length})
    warm, cold = launch.Conditions(t_ref=50.0, oil_temp_C=85.0), launch.Conditions(t_ref=50.0, oil_temp_C=10.0)
    fills = [float(designs.fill_times(plant, np.array([c.oil_temp_C]))[0]) for plant, c in ((p, warm), (slow, cold))]
    w, c = (launch.simulate(plant, "launch", cond, nominal=metrics.Response.empty()).summary
            for plant, cond in ((p, warm), (slow, cold)))
    assert warm.t_request + w["contact_s"] > fills[0] and cold.t_request + c["contact_s"] > fills[1]
    assert w["contact_s"] < 0.0 < c["contact_s"]  # the cold fill takes 0.67 s to 60 % of the stroke
    assert c["t95_settled_s"] > c["contact_s"]
    fastest = launch.fastest_contact(p, warm)
    assert fastest is not None and fastest < w["contact_s"]
    assert launch.fastest_contact(slow, cold) is None
    # wide open from the start, the cold plates touch after the request but within the response time (0.12 s): a
    # launch could still answer in time, and this one, touching later, is the controller's; with a feed line twice
    # as long they touch only 0.49 s after it, and no launch answers in time
    late = launch.fastest_contact(slow, cold, metrics.REQ_T95_S)
    assert late is not None and 0.0 < late < c["contact_s"]
    slower = params_load(base=slow, overrides={"hydraulics.line_length": 2.0 * p.hydraulics.line_length})
    assert launch.fastest_contact(slower, cold, metrics.REQ_T95_S) is None
    assert launch.fastest_contact(slower, cold, 1.0) > metrics.REQ_T95_S


def test_a_request_beyond_the_clutchs_capacity_shows_the_valve_input_at_its_top():
    # The axle torque of a sliding clutch is at most eta / i (mu_max A_p (p_supply - p_contact) + drag): the
    # pressure cannot exceed the supply's. At a reduced supply pressure, a CVT ratio of 1 and a low friction level
    # that bound is 145 N m: a 200 N m request finds the valve input at the top of its range through the judged
    # window (half the samples: the dither reaches it on its upper half) and falls short; 100 N m never needs it.
    p = params_load(overrides={"driveline.ratio": 1.0, "friction.mu_scale": 0.79, "hydraulics.p_supply": 5.0e5})
    f, h, d = p.friction, p.hydraulics, p.driveline
    curve = f.curve()
    mu_max = max(friction.mu(curve, s) for s in np.linspace(0.0, d.omega_p0, 301))
    drag = f.drag_20C * oil.dynamic_viscosity(85.0) / oil.dynamic_viscosity(20.0) * d.omega_p0
    bound = d.eta / d.ratio * (mu_max * h.A_p * (h.p_supply - (h.p_prestress + h.k_reset * h.x_contact / h.A_p)) + drag)
    # Checked against the plates' capacity at the valve's highest static pressure, no torque under it meets the
    # 200 N m request within the steady-state error (no controller passes it); the 100 N m one is within reach.
    for t_ref in (200.0, 100.0):
        res = launch.simulate(p, "launch", launch.Conditions(t_ref=t_ref, oil_temp_C=85.0, t_max=3.0),
                              nominal=metrics.Response.empty())
        s = res.summary
        assert s["T_ss"] <= bound
        if t_ref > bound:
            assert s["input_at_max_pct"] > 40.0 and s["steady_state_error_pct"] > 10.0
            assert not launch.capacity_allows(p, res)
        else:
            assert s["input_at_max_pct"] == 0.0 and s["requirements"]["steady_state_error"]
            assert launch.capacity_allows(p, res)


def test_where_the_capacity_sags_the_torque_holds_flat_a_little_below_the_request():
    # A clutch of low friction (x0.85) with a steep curve (x1.4) at a CVT ratio near 1 and a reduced supply: over the
    # judged window of a 192 N m request its capacity at the valve's top pressure falls as the slip falls. Asking
    # for the request throughout, the torque followed that sag (a ripple of 6.6 % over the window, the input at the
    # top of its range in a quarter of it); held flat below the request, within the steady-state error allowed, it
    # meets every requirement.
    p = params_load(overrides={
        "hydraulics.p_prestress": 50690.461455475524, "hydraulics.x_contact": 0.0016249913922471236,
        "friction.mu_scale": 0.8494180483609682, "friction.mu_slope": 1.395541293157506,
        "hydraulics.p_supply": 785200.3200306768, "hydraulics.leak_85C": 2.3549824955200503e-12,
        "valve.d_stem": 86.18882696561033, "driveline.J_1": 0.008619341768094289,
        "hydraulics.line_length": 1.6338805302791166, "hydraulics.air_fraction": 0.006959431519975047,
        "driveline.ratio": 0.9823881710702717, "driveline.eta": 0.906159768146992,
        "driveline.k_a": 365.3746403894325, "engage.T_load": 16.547409202562047})
    t_ref = 192.07077145815015
    cond = launch.Conditions(t_ref=t_ref, oil_temp_C=49.279423511308806, seed=2062938959,
                             noise_scale=1.5297162462421805, t_max=2.45)
    last = launch.sequence(p, "launch", cond, 3)[-1]
    s = last.summary
    assert s["input_at_max_pct"] > 0.0 and launch.capacity_allows(p, last)
    assert (1.0 - metrics.REQ_ESS_PCT / 100.0) * t_ref < s["T_ss"] < 0.97 * t_ref
    assert s["ripple_pct"] <= metrics.REQ_RIPPLE_PCT and s["all_pass"]


def test_a_torque_above_the_flat_it_holds_at_the_capacity_winds_the_torque_integrator_down():
    # The request has risen (two stages, 150 N m); the valve's top, as the launch found it, gives the plates far less
    # than the request at the slip the judged window ends with, so the launch aims at a flat FLAT_FLOOR of the
    # request. An axle torque above that flat is no transient of the rising request: the torque integrator must wind
    # down against it (judged against the request itself, the flat's lowered request counted as still rising and
    # held the integrator, and the torque stayed above the flat until the capacity's sag pulled it down)
    d = designs.cached(Params())
    rec = designs.record(d, 1e-3)
    ratio, t_ref = d.settings["ratio"], 150.0
    cs = control.initial_state(d.settings["p_kiss"])
    # in the torque phase 0.3 s after the request, the plates answered, the input at the top seen (the valve's top
    # 0.5 bar above the kiss point), the slip falling at 100 rad/s^2, the axle torque at 98 % of the request
    state = {"PHASE": control.TORQUE, "FILLED": 1.0, "ANSWERED": 1.0, "FOUND": 1.0, "THETA": 1.0, "SAT": 1.0,
             "U": 3.0, "N": 500.0, "NREQ": 200.0, "REF": t_ref, "REF1": t_ref, "SLIPP": 100.0, "DSLIP": -100.0,
             "PTOP": d.settings["p_kiss"] + 0.5e5, "PF": 3e5, "PF5": 3e5, "PPREV": 3e5, "TF": 0.98 * t_ref}
    for name, v in state.items():
        cs[getattr(control, "CS_" + name)] = v
    meas = np.zeros(len(control.MEASURED))
    meas[control.M_P], meas[control.M_TR], meas[control.M_TEMP] = 3e5, 0.98 * t_ref, 60.0
    meas[control.M_WP], meas[control.M_W1], meas[control.M_RATIO] = 150.0, 50.0, ratio
    for k in range(100):
        slip = 100.0 - 0.1 * k  # falling at 100 rad/s^2
        meas[control.M_WS] = (meas[control.M_WP] - slip) * ratio
        control.step(rec, cs, meas, t_ref)
    assert cs[control.CS_ZT] < 0.0, cs[control.CS_ZT]


@pytest.mark.parametrize("found", [False, True])
def test_a_request_before_contact_starts_from_the_pressure_not_from_a_belief_the_search_raised(found):
    # In the hold the search has raised the believed kiss point 0.3 bar above the filtered pressure with no torque yet
    # (the piston still strokes behind a cold feed line); the request comes. A kiss point not yet found is believed at
    # most REQ_KISS above the pressure from then on; one that was found stays where it was found.
    d = designs.cached(Params())
    rec = designs.record(d, 1e-3)
    p0 = d.settings["p_kiss"] - 0.05e5
    kiss = p0 + 0.3e5
    cs = control.initial_state(d.settings["p_kiss"])
    state = {"PHASE": control.HOLD, "FILLED": 1.0, "FOUND": 1.0 if found else 0.0, "KISS": kiss, "N": 900.0,
             "PF": p0, "PF5": p0, "PPREV": p0, "TF": 3.0, "TREF": 3.0, "TMIN": 3.0, "PSET": kiss, "STROKE": 1.0}
    for name, v in state.items():
        cs[getattr(control, "CS_" + name)] = v
    meas = np.zeros(len(control.MEASURED))
    meas[control.M_P], meas[control.M_TR], meas[control.M_TEMP] = p0, 3.0, 15.0
    meas[control.M_WP], meas[control.M_RATIO] = 150.0, d.settings["ratio"]
    control.step(rec, cs, meas, 50.0)
    assert cs[control.CS_PHASE] == control.TORQUE
    expected = kiss if found else p0 + control.REQ_KISS
    assert cs[control.CS_KISS] == pytest.approx(expected, abs=1.0)


@pytest.mark.parametrize("sag, allowed", [(0.05, True), (0.14, True), (0.15, False)])
def test_a_capacity_that_sags_allows_a_launch_while_a_flat_top_meets_the_error_and_the_ripple(sag, allowed):
    # Over the judged window the plates, at the valve's highest pressure, carry 1.2 times the request r in its first
    # half and (1 - sag) r in its second. A torque flat at c, then at the capacity, has the mean (c + (1 - sag) r) / 2
    # and the standard deviation (c - (1 - sag) r) / 2; at the lowest mean the steady-state error allows, 0.9 r,
    # its ripple is (sag - 0.1) / 0.9 (none for a sag up to 0.1, where a flat torque fits under the capacity): within
    # 5 % up to a sag of 0.145. Whatever else a launch does, its torque stays under the capacity.
    p, r, temp = Params(), 100.0, 85.0
    p_max = clutch.static_pressure(p, designs.INPUT_RANGE["dc"][1], temp_C=temp)
    t = np.round(np.arange(0.0, 2.5, 1e-3), 9)
    cap = np.where(t < 1.8, 1.2 * r, (1.0 - sag) * r)
    d = p.driveline
    res = launch.LaunchResult({"time": t, "t_ref": np.where(t >= 1.0, r, 0.0)},
                              {"time": t, "p_clutch": np.full(t.size, p_max), "locked": np.zeros(t.size, np.int8),
                               "T_c": cap * d.ratio / d.eta},
                              {"steady_window_s": [1.3, 2.3], "oil_temp_C": temp}, launch.Conditions(), "launch")
    assert launch.capacity_allows(p, res) is allowed


def test_a_valve_stem_sliding_at_zero_speed_does_not_stall_the_launch():
    """After lock-up, with a dither of 250 Hz, the restart at a controller sample found the sliding valve stem's
    speed exactly zero, its friction's slide event came 3.4e-12 s later, and again and again (the launch hung:
    4.5 million events, time creeping by picoseconds). The stem must be held and the launch go on to its end."""
    identified = params_load(overrides={
        "driveline.J_p": 0.8999441601008118, "driveline.J_s": 6.50380621392607,
        "driveline.ratio": 0.5499861623524075, "driveline.k_a": 479.01347784747594, "driveline.d_a": 5.0376854373197,
        "hydraulics.p_prestress": 34783.36345544135, "hydraulics.x_contact": 0.00219590449143919,
        "friction.mu_slip_poly": [-2.615771398531033e-06, 0.00041488431785436264, 0.025220433975933567],
        "rig.oil_temp_C": 57.49940174993313})
    d = designs.with_settings(designs.design(identified), dither_hz_torque=250.0)
    p = params_load(base=identified, overrides={
        "hydraulics.p_prestress": 38214.50866365887, "hydraulics.x_contact": 0.002240391785848048,
        "friction.mu_scale": 0.7955111487050389, "friction.mu_slope": 1.3672943594567355,
        "hydraulics.p_supply": 784913.0084128231, "hydraulics.leak_85C": 1.8098513206514376e-12,
        "valve.d_stem": 51.31999751526842, "driveline.J_1": 0.0054665051596014345,
        "hydraulics.line_length": 1.2751207430400517, "hydraulics.air_fraction": 0.003269692825323545,
        "driveline.ratio": 0.4042623860645286, "driveline.eta": 0.9120129925041925,
        "driveline.k_a": 383.9745222237261, "engage.T_load": 15.099950816107068})
    cond = launch.Conditions(t_ref=181.34037658874436, oil_temp_C=86.00531934239307, seed=1889134229,
                             noise_scale=0.5839585692923934)
    runs = launch.sequence(p, d, cond, 3)
    assert [r.summary["t_sync_s"] is not None for r in runs] == [True, True, True]


@pytest.mark.parametrize("t_ref, hz_setting", [(100.0, "dither_hz_high"), (25.0, "dither_hz_torque")])
def test_the_torque_dither_is_faster_high_in_the_pressure_range(t_ref, hz_setting):
    """The torque dither's half period in the steady window: ``dither_hz_high`` once the pressure is
    ``dither_high_above`` above the kiss point (100 N m at 85 C: 1.3 bar above it), ``dither_hz_torque``
    below (25 N m: 0.4 bar above it)."""
    d = designs.cached(Params())
    res = launch.simulate(Params(), d, launch.Conditions(t_ref=t_ref, oil_temp_C=85.0))
    sig = res.signals
    w0, w1 = res.summary["steady_window_s"]
    u = sig["u"].to_numpy()[(sig["time"] >= w0).to_numpy() & (sig["time"] <= w1).to_numpy()]
    # the square wave's edges: jumps of about twice its amplitude (the loop's own moves are far smaller)
    edges = np.flatnonzero(np.abs(np.diff(u)) > d.settings["dither_amp_torque"])
    half = np.median(np.diff(edges))
    assert half == round(0.5 / (d.settings[hz_setting] * 1e-3))


@pytest.mark.parametrize("mu_slope, t_ref, oil_temp_C", [(0.55, 180.0, 60.0), (0.5, 190.0, 85.0)])
def test_a_friction_curve_flatter_than_the_designs_does_not_slow_the_response(mu_slope, t_ref, oil_temp_C):
    # a clutch whose mu falls with slip along a quadratic curve (a quarter higher at 110 rad/s of slip than at 138),
    # designed on that curve, running with one half as steep at a CVT ratio of 0.5: as the slip falls, the design's
    # law expects more of the rise in mu than comes, the friction-factor estimate drifts down, and the filter that
    # smooths it lags the drift. The torque then crept into the 95 % band over 0.2-0.24 s (settled t95 0.206-0.237 s
    # on the four noise seeds on the host this was written on; 0.179-0.193 s with half of the lag added back)
    curve = {"friction.mu_slip_poly": [-2.2e-6, 3.2e-4, 0.024], "driveline.J_1": 0.0015, "driveline.J_p": 1.0,
             "driveline.J_s": 7.5, "hydraulics.p_prestress": 0.8e5, "hydraulics.x_contact": 1.1e-3}
    d = designs.cached(params_load(overrides=curve | {"driveline.ratio": 0.65}), "launch")
    plant = params_load(overrides=curve | {"friction.mu_slope": mu_slope, "driveline.ratio": 0.5})
    t95 = [launch.simulate(plant, d, launch.Conditions(t_ref=t_ref, oil_temp_C=oil_temp_C, seed=seed, t_max=2.45))
           .summary["t95_settled_s"] for seed in range(1, 5)]
    assert max(t95) < metrics.REQ_T95_S, t95


@pytest.mark.parametrize("over", [{}, {"friction.drag_20C": 0.026, "driveline.ratio": 0.42}])
def test_the_open_plates_creep_is_their_viscous_drag_through_the_cvt(over):
    """With the valve closed the waiting vehicle feels the open plates' oil drag, ``drag_20C mu(T) / mu(20 C)`` times
    the slip (the primary's speed), through the CVT to the axle: ``eta / ratio`` of it."""
    p = params_load(overrides=over)
    temp = 15.0
    creep = launch.open_plates_creep(p, launch.Conditions(oil_temp_C=temp))
    d = p.friction.drag_20C * oil.dynamic_viscosity(temp) / oil.dynamic_viscosity(20.0)
    want = d * p.driveline.omega_p0 * p.driveline.eta / p.driveline.ratio
    # the primary slows a little under the drag and its bearings before the request, and a creep above the road
    # load starts to move the vehicle (less slip): a few percent less
    assert creep == pytest.approx(want, rel=0.04)
    assert creep < want


def test_a_valve_stem_released_below_the_integrations_resolution_is_held_not_released_again():
    # A clutch of the class `identify` returns (its drawn ratio, contact, inertias and friction curve, as identified)
    # with a torque dither of 0.49 V: at 1.69 s of a 200 N m launch the stem's drive touches its friction and the
    # stem is released with a slip rate of 2.5e-4 m/s^2, whose slide the step's error (below the tolerance) turns
    # back through zero at once. Without the resolution rule the restart released it again 0.1 microseconds
    # later, some ten thousand times, and the launch ended as Zeno behaviour.
    plant = params_load(overrides={
        "driveline.J_p": 1.4176964794800762, "driveline.J_s": 4.787710813893278,
        "driveline.ratio": 1.1711508178678527, "driveline.k_a": 474.6465399113017,
        "driveline.d_a": 5.101855423613727, "hydraulics.p_prestress": 112904.74621123199,
        "hydraulics.x_contact": 0.0011119555390921364,
        "friction.mu_slip_poly": [-1.7140502139970263e-06, 0.00027201157033388093, 0.021323591889015944],
        "rig.oil_temp_C": 62.997894725})
    d = designs.with_settings(designs.design(plant, "launch"), dither_amp_torque=0.49)
    r = launch.simulate(plant, d, launch.Conditions(t_ref=200.0, seed=0), nominal=metrics.Response.empty())
    # about as many events as the same launch with the designed dither (750 at 0.35 V)
    assert r.stats["events"] < 2 * 750
    assert r.summary["steady_state_error_pct"] < 10.0


@pytest.mark.parametrize("shaped_share, winds_down", [(0.5, False), (1.0, True)])
def test_a_torque_ahead_of_the_rising_request_does_not_wind_the_torque_integrator_down(shaped_share, winds_down):
    # The plates' contact jolt (or a heavy clutch output ringing) puts the axle torque at 105 % of the request while
    # the shaped request is at half of it: a transient the request is on its way to. A torque integrator wound down against
    # it holds the pressure short afterwards (a cold launch's settled t95 0.249-0.295 s against 0.176-0.226 s); it
    # waits until the shaped request is within REF_RISING of the request, and winds down against a torque ahead of
    # the risen request as before.
    d = designs.cached(Params())
    rec = designs.record(d, 1e-3)
    t_ref = 150.0
    cs = control.initial_state(d.settings["p_kiss"])
    p = d.settings["p_kiss"] + 1.0e5
    state = {"PHASE": control.TORQUE, "FILLED": 1.0, "ANSWERED": 1.0, "FOUND": 1.0, "THETA": 1.0, "U": 2.5,
             "N": 1100.0, "NREQ": 1000.0, "REF": shaped_share * t_ref, "REF1": shaped_share * t_ref, "PF": p,
             "PF5": p, "PPREV": p, "TF": 1.05 * t_ref, "ZT": 0.1e5, "PTOP": 8e5}
    for name, v in state.items():
        cs[getattr(control, "CS_" + name)] = v
    meas = np.zeros(len(control.MEASURED))
    meas[control.M_P], meas[control.M_TR], meas[control.M_TEMP] = p, 1.05 * t_ref, 60.0
    meas[control.M_WP], meas[control.M_RATIO] = 150.0, d.settings["ratio"]
    meas[control.M_WS] = 100.0 * d.settings["ratio"]
    control.step(rec, cs, meas, t_ref)
    assert bool(cs[control.CS_ZT] < 0.1e5) is winds_down, cs[control.CS_ZT]


def test_a_cold_launch_whose_plates_touch_as_the_request_comes_settles_in_time():
    # cold oil, a heavy clutch output, a prestress of 0.79 bar (the built-in rig's 0.5) and a 20 % longer stroke: the
    # plates touch 0.012-0.028 s after the request. An earlier launch has measured the output (as light as the
    # design's), so that the request takes the two stages. Over five noise seeds the settled t95 is 0.14-0.18 s
    # (measured), 0.164-0.196 s before the request started from the filtered pressure rather than from the belief the
    # search had raised; one seed alone may sit near the 0.2 s limit, so the mean over the five is judged
    plant = params_load(overrides={
        "hydraulics.p_prestress": 78700.0, "hydraulics.x_contact": 1.647e-3, "friction.mu_scale": 1.03,
        "friction.mu_slope": 0.808, "hydraulics.p_supply": 7.0e5, "hydraulics.leak_85C": 3.5e-12,
        "valve.d_stem": 99.6, "driveline.J_1": 8.73e-3, "hydraulics.line_length": 1.81,
        "hydraulics.air_fraction": 0.0043, "driveline.ratio": 0.60, "driveline.eta": 0.914, "driveline.k_a": 493.0,
        "engage.T_load": 28.4})
    d = designs.design(Params())
    settled = []
    for seed in range(1, 6):
        cond = launch.Conditions(t_ref=157.6, oil_temp_C=11.6, seed=seed, noise_scale=1.155)
        s = launch.simulate(plant, d, cond, nominal=metrics.Response.empty(),
                            adaptation=Adaptation(inertia=Params().driveline.J_1)).summary
        assert 0.0 < s["contact_s"] < 0.05, s["contact_s"]
        settled.append(s["t95_settled_s"])
    assert sum(settled) / 5 < metrics.REQ_T95_S, settled


def test_a_launch_and_a_design_show_their_figures_not_their_arrays():
    d = designs.cached(Params())
    res = launch.simulate(Params(), d, launch.Conditions(t_ref=80.0, t_max=2.5, noise=False))
    text = repr(res)
    assert "\n" not in text and len(text) < 400
    assert f"overshoot {res.summary['overshoot_pct']:.1f} %" in text and "all requirements met" in text
    shown = repr(d)
    assert shown.startswith("Design(launch, ") and f"p_kiss={d.settings['p_kiss']:.4g}" in shown
    assert "[[" not in shown and len(shown) < 2000


@pytest.mark.parametrize("text, fragment", [
    ("time,t_ref\n", "needs at least two rows"),
    ("time,t_ref\n0,50\n1,1e3000\n", "'t_ref' is not finite in data row 2"),
    ("time,t_ref\n0,10\n0,20\n", "'time' must increase (data row 2)"),
    ("time,t_ref\n0,0\n1,0\n", "'t_ref' is 0 throughout"),
])
def test_a_bad_profile_file_says_what_is_wrong_with_it(tmp_path, text, fragment):
    f = tmp_path / "profile.csv"
    f.write_text(text)
    with pytest.raises(WetclutchError) as e:
        launch.reference(launch.Conditions(profile=str(f)), np.zeros(3))
    assert fragment in str(e.value) and str(e.value).startswith(f"profile {f}")


def test_the_pressure_loops_rate_gain_is_scheduled_on_the_oil_temperature():
    d = designs.with_settings(designs.cached(Params()), kd_p_cold=3.0)
    ctrl = designs.record(d, 1e-3)
    kd = d.settings["kd_p"]
    assert control.rate_gain(ctrl, 10.0) == pytest.approx(3.0 * kd, rel=1e-12)
    assert control.rate_gain(ctrl, -5.0) == pytest.approx(3.0 * kd, rel=1e-12)
    assert control.rate_gain(ctrl, 20.0) == pytest.approx(2.0 * kd, rel=1e-12)
    for temp in (30.0, 60.0, 100.0):
        assert control.rate_gain(ctrl, temp) == pytest.approx(kd, rel=1e-12)
    gains = [control.rate_gain(ctrl, t) for t in np.linspace(0.0, 40.0, 81)]
    assert np.all(np.diff(gains) <= 0.0)


@pytest.mark.parametrize("oil_temp_C, over", [
    (12.8, {"hydraulics.p_prestress": 0.744e5, "hydraulics.x_contact": 1.636e-3, "friction.mu_scale": 0.979,
            "friction.mu_slope": 1.297, "hydraulics.p_supply": 6.94e5, "valve.d_stem": 100.3, "driveline.J_1": 2.65e-3,
            "hydraulics.line_length": 1.47, "hydraulics.air_fraction": 0.01, "driveline.ratio": 0.78,
            "driveline.k_a": 601.0}),
    (18.1, {"hydraulics.p_prestress": 0.644e5, "hydraulics.x_contact": 1.483e-3, "friction.mu_scale": 1.169,
            "hydraulics.p_supply": 6.98e5, "valve.d_stem": 115.9, "driveline.J_1": 1.71e-3,
            "hydraulics.line_length": 1.14, "hydraulics.air_fraction": 0.0025, "driveline.ratio": 0.43,
            "driveline.k_a": 408.5})])
def test_a_stiffly_damped_stem_in_cold_oil_overshoots_less_with_the_cold_rate_gain(oil_temp_C, over):
    # the stem damped 1.7-1.9 times the built-in rig's at 13-18 C (two clutches of the shipped ranges): with the warm
    # oil's rate gain the pressure rises in jumps and the torque overshoots by 12-14 % on some noise seeds, about the
    # robustness limit (the nominal's overshoot plus 10 points); with three times the gain in cold oil by 5-6 %
    plant = params_load(overrides=over)
    d = designs.cached(plant)
    runs = {k: [launch.simulate(plant, designs.with_settings(d, kd_p_cold=k),
                                launch.Conditions(t_ref=170.0, oil_temp_C=oil_temp_C, seed=seed)).summary
                for seed in range(4)] for k in (1.0, 3.0)}
    over_pct = {k: [s["overshoot_pct"] for s in v] for k, v in runs.items()}
    assert max(over_pct[3.0]) < max(over_pct[1.0]) - 3.0, over_pct
    assert all(s["requirements"]["robustness"] for s in runs[3.0]), over_pct


def _watched(p: np.ndarray, dt: float = 1e-3) -> tuple[int, float | None]:
    """The limit-cycle watch over a measured pressure ``p`` (Pa), its rate filtered as the controller filters it:
    the cycles seen and the time (s) of the first."""
    cs = np.zeros(control.N_CS)
    first = None
    control._pressure_rate(cs, p[0], True, dt)
    for k in range(1, len(p)):
        cs[control.CS_N] = k
        control._pressure_rate(cs, p[k], False, dt)
        control._watch_cycle(cs, dt)
        if first is None and cs[control.CS_LC_SEEN] > 0:
            first = k * dt
    return int(cs[control.CS_LC_SEEN]), first


def test_the_pressure_loops_limit_cycle_is_seen_and_a_launchs_rise_is_not():
    t = np.arange(0.0, 0.3, 1e-3)
    rng = np.random.default_rng(3)
    noise = 1e3 * rng.standard_normal(t.size)
    # the cycle a lightly damped stem runs into (85 Hz, +-2.5 bar about 4 bar): seen on its 4th swing beyond the
    # rate's threshold, some one and a half periods in (18 ms)
    seen, first = _watched(4e5 + 2.5e5 * np.sin(2 * np.pi * 85.0 * t) + noise)
    assert seen >= 1 and 0.012 < first < 0.03, (seen, first)
    # a swing of +-0.5 bar at the same frequency: its rate (some 27 MPa/s) stays within the threshold
    assert _watched(4e5 + 0.5e5 * np.sin(2 * np.pi * 85.0 * t) + noise)[0] == 0
    # a fast rise (0.7 to 5 bar in 50 ms) with the torque dither's ripple (+-0.3 bar at 167 Hz) and a jump that
    # rings twice: never
    rise = np.interp(t, [0.05, 0.1], [0.7e5, 5e5])
    ripple = 0.3e5 * np.sign(np.sin(2 * np.pi * 167.0 * t))
    ring = np.where(t > 0.2, 1e5 * np.exp(-(t - 0.2) / 0.01) * np.cos(2 * np.pi * 40.0 * (t - 0.2)), 0.0)
    assert _watched(rise + noise)[0] == 0
    assert _watched(rise + ring + noise)[0] == 0
    assert _watched(rise + 0.5 * ripple + noise)[0] == 0


@pytest.mark.parametrize("values, seed", [
    ({"kiss_point": 25801.641435942314, "fill_volume": 1.072077662097359, "friction_level": 0.9360390119160467,
      "friction_slope": 1.1038582135043953, "oil_temp": 19.030907557955473, "supply_pressure": 0.8974636839940358,
      "seal_leakage": 0.6023294811185451, "stem_damping": 0.5480040856070824, "output_inertia": 7.128272092515189,
      "line_length": 1.0620866671952114, "air_fraction": 0.0020613999058147333, "cvt_ratio": 0.8928311365586015,
      "efficiency": 0.9404280183718323, "axle_stiffness": 0.7361474840144535, "road_load": 4.6310706815570635,
      "request": 144.22301860433635, "sensor_noise": 0.8505729783737144}, 1664470627),
    ({"kiss_point": 16014.003514856304, "fill_volume": 1.2505575500238906, "friction_level": 1.1192882564980526,
      "friction_slope": 1.1821617234896993, "oil_temp": 11.741725576056991, "supply_pressure": 0.9340862133353546,
      "seal_leakage": 1.3538466253225114, "stem_damping": 0.5009247987977835, "output_inertia": 9.227238172776572,
      "line_length": 0.8348515270075193, "air_fraction": 0.003484413059408392, "cvt_ratio": 0.9838731733481721,
      "efficiency": 0.9296806963092672, "axle_stiffness": 0.8052181208759284, "road_load": 25.384449622725953,
      "request": 147.3522972046518, "sensor_noise": 1.3042843981909393}, 715696600)])
def test_a_lightly_damped_stem_in_cold_oil_does_not_hold_the_pressure_loop_in_a_cycle(values, seed):
    # two clutches of the shipped ranges whose stem has half the built-in rig's damping, in oil at 12-19 C: on the
    # third launch the cold oil's rate gain drove the pressure into an 85-90 Hz cycle of 1.5-6.5 bar through the slip
    # phase (a torque ripple of 24-27 %); seen, the rate gain goes, and the launch passes
    d = designs.cached(Params())
    ctx = verify.Context(d, Params(), ranges.load(), sequence=3)
    plant, cond = ctx.case(verify.Sample(0, values, seed))
    runs = launch.sequence(plant, d, cond, 3)
    last = runs[-1].summary
    assert last["limit_cycles_seen"] >= 1
    assert last["ripple_pct"] < metrics.REQ_RIPPLE_PCT, last["ripple_pct"]
    assert last["all_pass"], last["requirements"]
