"""Kiss-point finding within a launch and adaptation across launches, on clutches whose kiss point drifted."""

import numpy as np
import pytest

from wetclutch.errors import WetclutchError
from wetclutch.launch import adaptation, design, loop, metrics, verify
from wetclutch.launch import controller as control
from wetclutch.params import Params, load
from wetclutch.physics import actuator


@pytest.mark.parametrize("shift", [-0.3e5, 0.3e5])
@pytest.mark.parametrize("temp", [20.0, 85.0])
def test_a_drifted_kiss_point_is_found_and_learnt(shift, temp):
    # the controller is designed on the defaults; the clutch's kiss point lies 0.3 bar lower or higher
    plant = load(overrides={"hydraulics.p_prestress": Params().hydraulics.p_prestress + shift})
    true = actuator.contact_pressure(plant)
    d = design.cached(Params(), "launch")
    runs = loop.sequence(plant, d, loop.Conditions(t_ref=100.0, oil_temp_C=temp), 3)
    for r in runs:
        assert r.kiss_found_Pa == pytest.approx(true, abs=0.12e5)
    # from the second launch on it starts where the first found it and does not slam; a kiss point so low that a dip
    # from the hold there would not lower the magnet's force is set aside, and the launch starts from the design's
    expected = runs[0].kiss_found_Pa if shift > 0.0 else d.settings["p_kiss"]
    assert runs[1].summary["kiss_start_Pa"] == pytest.approx(expected)
    for r in runs[1:]:
        assert r.summary["overshoot_pct"] < 25.0, r.summary
    assert runs[-1].adaptation.launches[adaptation.band(temp)] == 3


def test_a_first_launch_fills_to_a_drifted_kiss_point_from_where_the_stroke_starts():
    # nothing learnt yet; the reset spring's prestress, and with it the whole stroke and the kiss point, lies 0.3 bar
    # lower or higher than the design's. The fill's steep rise ends where the piston starts to move, the kiss point
    # lies the design's stroke span above that: the plates touch about as long before the request as on the
    # design's own clutch (judged by the pressure from the design's kiss point, the fill of the stiffer spring would
    # end at once, and the slow approach of the hold would leave the plates touching some 0.3 s later)
    d = design.cached(Params(), "launch")
    cond = loop.Conditions(t_ref=50.0, oil_temp_C=40.0, t_max=2.5)
    contact = {}
    for shift in (-0.3e5, 0.0, 0.3e5):
        plant = load(overrides={"hydraulics.p_prestress": Params().hydraulics.p_prestress + shift})
        contact[shift] = loop.simulate(plant, d, cond).summary["contact_s"]
    assert contact[-0.3e5] == pytest.approx(contact[0.0], abs=0.1)
    assert contact[0.3e5] == pytest.approx(contact[0.0], abs=0.1)


def test_a_kiss_point_found_in_a_pressure_slam_is_placed_before_the_jump():
    # hot oil; the clutch's kiss point lies 0.15 bar below the design's and its stroke is shorter, and the kiss point
    # learnt earlier lies 0.1 bar above it (learnt before the plates wore): the full-input fill, ended by the learnt
    # point, reaches the plates and slams the pressure; the torque onset comes only once the pressure is some 0.2 bar
    # above the contact. The kiss point is placed no higher than the pressure before the jump, so the hold neither
    # creeps nor needs the creep watch to find it (a creep limit no clutch reaches switches the watch off)
    p = Params().hydraulics
    plant = load(overrides={"hydraulics.p_prestress": p.p_prestress - 0.11e5, "hydraulics.x_contact": 0.825 * p.x_contact})
    true = actuator.contact_pressure(plant)
    d = design.cached(Params(), "launch")
    learnt = adaptation.Adaptation().learn(97.0, true + 0.1e5)
    cond = loop.Conditions(t_ref=100.0, oil_temp_C=97.0)
    for ctrl in (d, design.with_settings(d, creep_limit=1e3)):
        r = loop.simulate(plant, ctrl, cond, adaptation=learnt)
        assert r.summary["standby_peak_Nm"] > 50.0  # the slam
        assert r.kiss_found_Pa == pytest.approx(true, abs=0.05e5)
        assert r.summary["creep_Nm"] <= metrics.REQ_CREEP_NM


def test_a_hold_that_presses_the_plates_is_pulled_down_by_the_creep_it_causes():
    # a hold set 0.1 bar above the kiss point presses the plates: the waiting vehicle creeps with 11 N m unless the
    # hold watches the creep and lowers its belief of the kiss point to the one the torque shows
    d = design.with_settings(design.cached(Params(), "launch"), hold_offset=0.1e5)
    cond = loop.Conditions(t_ref=100.0, oil_temp_C=85.0)
    watched = loop.simulate(Params(), d, cond)
    blind = loop.simulate(Params(), design.with_settings(d, creep_limit=1e3), cond)
    assert blind.summary["creep_Nm"] > metrics.REQ_CREEP_NM
    assert watched.summary["creep_Nm"] <= metrics.REQ_CREEP_NM
    assert watched.kiss_found_Pa < blind.kiss_found_Pa - 0.02e5


def test_a_cold_clutch_with_a_late_kiss_point_neither_takes_the_drag_for_contact_nor_slams():
    # cold oil, a kiss point 0.18 bar above the design's and a longer stroke: right after the start the axle torque
    # settles on the open plates' drag (3-4 N m), a rise that must not count as the plates' contact (it put the
    # kiss point at 0.5 bar, and the request then wound the torque loop up against open plates: 7x the request)
    p = Params()
    h, v, dl = p.hydraulics, p.valve, p.driveline
    plant = load(overrides={
        "hydraulics.p_prestress": h.p_prestress + 0.18e5, "hydraulics.x_contact": 1.23 * h.x_contact,
        "friction.mu_scale": 1.17, "friction.mu_slope": 1.4, "hydraulics.p_supply": 0.9 * h.p_supply,
        "valve.d_stem": 1.84 * v.d_stem, "driveline.J_1": 4.8 * dl.J_1, "driveline.ratio": 0.57,
        "driveline.k_a": 0.71 * dl.k_a, "engage.T_load": 5.0})
    true = actuator.contact_pressure(plant)
    runs = loop.sequence(plant, design.cached(Params(), "launch"),
                         loop.Conditions(t_ref=80.0, oil_temp_C=19.0, seed=3, noise_scale=1.3), 3)
    for r in runs:
        assert r.kiss_found_Pa == pytest.approx(true, abs=0.05e5)
        assert r.summary["overshoot_pct"] < 100.0 * (verify.SLAM_FACTOR - 1.0)
    assert runs[-1].summary["all_pass"]


def test_an_early_kiss_point_is_held_where_the_pressure_shows_it_not_where_the_axle_rang():
    # a kiss point 0.26 bar below the design's: the plates touch in the full-input fill and the axle rings after
    # the jolt, down to -48 N m. That swing is no drag (the open plates push the waiting vehicle forward); taken
    # for one, the torque above it looked like 13 N m of creep, the kiss point was pulled down to 0.26 bar while
    # the hold's pressure sat at 0.47 bar with 1 N m on the axle, and the request overshot by 79 %
    p = Params()
    h, dl = p.hydraulics, p.driveline
    plant = load(overrides={
        "hydraulics.p_prestress": h.p_prestress - 0.26e5, "hydraulics.x_contact": 1.18 * h.x_contact,
        "hydraulics.leak_85C": 1.73 * h.leak_85C, "hydraulics.air_fraction": 0.0021, "hydraulics.p_supply": 0.9 * h.p_supply,
        "friction.mu_scale": 1.16, "friction.mu_slope": 1.39, "driveline.J_1": 9.5 * dl.J_1, "driveline.ratio": 0.414,
        "driveline.eta": 0.963, "driveline.k_a": 0.89 * dl.k_a, "engage.T_load": 5.66, "valve.d_stem": 63.0})
    true = actuator.contact_pressure(plant)
    first = loop.simulate(plant, design.cached(Params(), "launch"),
                          loop.Conditions(t_ref=36.2, oil_temp_C=59.2, seed=722266545))
    assert first.kiss_found_Pa == pytest.approx(true, abs=0.05e5)
    assert first.summary["overshoot_pct"] < metrics.ROBUST_OVERSHOOT


def test_a_learnt_kiss_point_is_not_searched_above_while_a_cold_stroke_is_still_short_of_it():
    # oil at 10 C and a CVT ratio of 0.42 (the axle feels the clutch's torque 2.2 times): the piston strokes slowly
    # after the fill. The later launches start from the kiss point the first one learnt (0.51 bar: high enough that a
    # dip from the hold there crosses the magnet's play, so it is kept); raising that belief as if the plates were
    # open while the stroke was still short of it led the valve open, and the plates' contact jolted the waiting
    # vehicle with 20-23 N m (the largest 0.1 s mean before the request) instead of some 15.5 N m
    plant = load(overrides={
        "hydraulics.p_supply": 7.94e5, "hydraulics.line_length": 1.72, "hydraulics.p_prestress": 0.32e5,
        "hydraulics.x_contact": 1.3045e-3, "hydraulics.leak_85C": 1.92e-12, "hydraulics.air_fraction": 0.0042,
        "valve.d_stem": 79.2, "friction.mu_scale": 1.126, "friction.mu_slope": 0.89, "driveline.J_1": 1.96e-3,
        "driveline.ratio": 0.4205, "driveline.eta": 0.938, "driveline.k_a": 399.4, "engage.T_load": 13.6})
    runs = loop.sequence(plant, design.cached(Params(), "launch"),
                         loop.Conditions(t_ref=192.8, oil_temp_C=10.16, seed=132356420, noise_scale=0.62), 3)
    assert runs[1].summary["kiss_start_Pa"] == pytest.approx(runs[0].kiss_found_Pa)
    assert [r.summary["standby_peak_Nm"] < 20.0 for r in runs[1:]] == [True, True]
    assert runs[2].summary["creep_Nm"] <= metrics.REQ_CREEP_NM


def test_a_low_kiss_point_learnt_in_cold_oil_is_set_aside_so_that_the_waiting_vehicle_is_not_pushed():
    # the default design on a clutch whose kiss point is 0.39 bar (the design's 0.70), at 11 C: the hold's input
    # there is near the bottom of its range, and the lowest input does not cross the magnet's play from there. Held
    # at the kiss point the first launch learnt, the later launches' plates touched in the hold, and no input could
    # bring the trapped pressure down: 11.0-11.2 N m of creep on the second launches and 15.1-16.6 N m on the third
    # (seeds 1-4). Placing the kiss point as a first launch does (its search has the input high when the plates
    # touch, and the dip then drains the pressure) keeps them within 7.3-8.8 N m
    plant = load(overrides={
        "hydraulics.p_prestress": 0.226e5, "hydraulics.x_contact": 1.11e-3, "hydraulics.leak_85C": 3.7e-12,
        "hydraulics.line_length": 1.68, "hydraulics.air_fraction": 0.0086, "hydraulics.p_supply": 7.78e5,
        "driveline.J_1": 7.5e-3, "driveline.ratio": 0.47})
    d = design.cached(Params(), "launch")
    # the map's input at the kiss point (its coldest row, 20 C, holds below it) within the play of the lowest input
    hold_input = np.interp(actuator.contact_pressure(plant), d.pressures_Pa, d.input_V[0])
    assert hold_input < design.record(d, 1e-3)[control.U_MIN] + 2.0 * d.settings["valve_play"]
    for seed in (1, 3):
        runs = loop.sequence(plant, d, loop.Conditions(t_ref=150.0, oil_temp_C=11.0, seed=seed), 3)
        assert runs[0].kiss_found_Pa < 0.45e5  # learnt, and set aside: the later launches start from the design's
        assert [r.summary["kiss_start_Pa"] for r in runs[1:]] == [d.settings["p_kiss"]] * 2
        creep = [r.summary["creep_Nm"] for r in runs]
        assert max(creep) < 0.9 * metrics.REQ_CREEP_NM and all(r.summary["all_pass"] for r in runs), creep


def test_a_request_on_a_hold_a_little_below_the_kiss_point_neither_jumps_the_set_point_nor_winds_up():
    # a controller designed on a plant with a 0.8 bar prestress and a short stroke, run cold (16 C) on a clutch whose
    # kiss point lies 0.2 bar lower, with a small request. From the second launch on the hold
    # starts from the learnt kiss point, but its pressure sits 0.01 to 0.03 bar below it (the hold's integrator
    # waits for the kiss point, since a stroking piston's flow makes the pressure droop). A request judged to wait
    # for the fill there lifted the set point 0.3 bar above plates that already touch, and an integrator that wound
    # up against the last of the stroke opened the valve as wide: the pressure slammed to 1.7-1.9 bar, the torque
    # overshot by 20-60 % and the plates bounced open (0 of the 8 later launches within 10 % and 0.2 s)
    base = load(overrides={
        "driveline.J_p": 1.0, "driveline.J_s": 7.5, "driveline.ratio": 0.65, "hydraulics.p_prestress": 0.8e5,
        "hydraulics.x_contact": 1.04e-3, "friction.mu_slip_poly": [-2.16e-06, 3.13e-4, 0.0239], "rig.oil_temp_C": 63.0})
    plant = load(base=base, overrides={
        "driveline.J_1": 0.002, "driveline.ratio": 0.83, "driveline.k_a": 527.0, "engage.T_load": 20.0,
        "valve.d_stem": 66.5, "hydraulics.p_supply": 7.2e5, "hydraulics.line_length": 1.18,
        "hydraulics.p_prestress": 0.58e5, "hydraulics.leak_85C": 2.9e-12, "hydraulics.air_fraction": 0.0063,
        "friction.mu_scale": 1.21, "friction.mu_slope": 1.39})
    d = design.cached(base, "launch")
    later = []
    for seed in range(1, 5):
        runs = loop.sequence(plant, d, loop.Conditions(t_ref=26.5, oil_temp_C=16.1, seed=seed, t_max=2.45), 3)
        later += [r.summary for r in runs[1:]]
    good = [s["overshoot_pct"] < metrics.ROBUST_OVERSHOOT and s["t95_settled_s"] < metrics.REQ_T95_S for s in later]
    # 7 of 8 on the host this was written on (22 of 24 over noise seeds 1-12); a closed loop with stick/slip carries
    # a CPU's rounding into different launches, hence the margin
    assert sum(good) >= 5, [(round(s["overshoot_pct"], 1), round(s["t95_settled_s"], 3)) for s in later]


@pytest.mark.parametrize("scale", [0.8, 1.2])
def test_a_friction_level_off_the_design_is_learnt_and_the_next_launch_starts_from_it(scale):
    # the controller is designed on the defaults; the clutch's friction is 20 % lower or higher. The estimate is the
    # measured axle torque over the nominal law's at the measured pressure, so it must come out near the scale
    plant = load(overrides={"friction.mu_scale": scale})
    d = design.cached(Params(), "launch")
    runs = loop.sequence(plant, d, loop.Conditions(t_ref=100.0, oil_temp_C=60.0), 3)
    assert runs[0].summary["friction_factor_start"] is None
    assert runs[0].summary["friction_factor_found"] == pytest.approx(scale, rel=0.1)
    assert runs[1].summary["friction_factor_start"] == pytest.approx(runs[0].summary["friction_factor_found"])
    learnt = runs[-1].adaptation.friction_factor(60.0)
    assert learnt == pytest.approx(scale, rel=0.1)
    # started from what was learnt, the response meets the requirement and stays within the robustness tolerance
    # of the first launch (on the stronger clutch the first is the quicker one: its nominal friction law asks for
    # 20 % more pressure than needed until the estimate has converged, and the learnt factor takes that push away)
    assert runs[-1].summary["t95_settled_s"] < metrics.REQ_T95_S
    assert runs[-1].summary["t95_settled_s"] <= runs[0].summary["t95_settled_s"] + metrics.ROBUST_DT95
    assert runs[-1].summary["overshoot_pct"] <= runs[0].summary["overshoot_pct"] + metrics.ROBUST_OVERSHOOT


def test_adaptation_state_round_trips_and_bad_files_name_the_field(tmp_path):
    a = adaptation.Adaptation().learn(41.0, 0.9e5).learn(41.0, 1.0e5, 1.2, 0.002).learn(85.0, 0.7e5, inertia=0.02)
    assert a.kiss(45.0) == pytest.approx(0.95e5) and a.kiss(85.0) == 0.7e5 and a.kiss(10.0) is None
    assert a.inertia == 0.02 and a.learn(41.0, 1e5, inertia=0.01).inertia == pytest.approx(0.015)
    assert a.friction_factor(45.0) == 1.2 and a.friction_factor(85.0) is None
    assert a.friction_slope(45.0) == 0.002 and a.friction_slope(85.0) is None
    back = adaptation.loads(a.to_toml())
    assert back == a
    with pytest.raises(WetclutchError, match=r"band\[0\].friction_factor"):
        adaptation.loads(a.to_toml().replace("friction_factor = 1.2", "friction_factor = 7.0"))
    with pytest.raises(WetclutchError, match=r"band\[0\].friction_slope_per_rad_s"):
        adaptation.loads(a.to_toml().replace("friction_slope_per_rad_s = 0.002", "friction_slope_per_rad_s = 0.5"))
    with pytest.raises(WetclutchError, match=r"band\[0\].friction_slope_per_rad_s"):
        adaptation.loads(a.to_toml().replace("friction_slope_per_rad_s = 0.002", 'friction_slope_per_rad_s = "x"'))
    with pytest.raises(WetclutchError, match=r"band\[0\].frictoin_factor: unknown field"):
        adaptation.loads(a.to_toml().replace("friction_factor = 1.2", "frictoin_factor = 1.2"))
    with pytest.raises(WetclutchError, match=r"output_inertia_kg_m2: must be a number in 0\.\.1"):
        adaptation.loads(a.to_toml().replace("output_inertia_kg_m2 = 0.02", "output_inertia_kg_m2 = -0.02"))
    with pytest.raises(WetclutchError, match=r"bandC: unknown field"):
        adaptation.loads("bandC = 20.0\n" + a.to_toml())
    bad = a.to_toml().replace("launches = 2", "launches = -2")
    with pytest.raises(WetclutchError, match=r"band\[0\].launches"):
        adaptation.loads(bad)
    with pytest.raises(WetclutchError, match="kiss_Pa"):
        adaptation.loads(a.to_toml().replace("kiss_Pa = 95000.0", "kiss_Pa = nan"))
    with pytest.raises(WetclutchError, match="cannot read adaptation file"):
        adaptation.load(tmp_path / "missing.toml")
    # a launch that crept moves its band's hold further below the kiss point, step by step up to the cap
    held = a.learn(41.0, 1e5, crept=True)
    assert held.hold_margin(45.0) == adaptation.MARGIN_STEP and held.hold_margin(85.0) == 0.0
    for _ in range(int(adaptation.MARGIN_MAX / adaptation.MARGIN_STEP) + 2):
        held = held.learn(41.0, 1e5, crept=True)
    assert held.hold_margin(45.0) == adaptation.MARGIN_MAX and held.learn(41.0, 1e5).hold_margin(45.0) == 0.1e5
    assert adaptation.loads(held.to_toml()) == held
    with pytest.raises(WetclutchError, match=r"band\[0\].hold_margin_Pa: must be a number in 0\.\.10000"):
        adaptation.loads(held.to_toml().replace("hold_margin_Pa = 10000.0", "hold_margin_Pa = 20000.0"))


def test_cli_sequence_writes_the_state_and_resumes_from_it(tmp_path):
    from wetclutch.cli import main

    out = tmp_path / "seq"
    args = ["--set", "hydraulics.p_prestress=70000", "--oil-temp", "60", "--t-ref", "80"]
    assert main(["launch", "--out", str(out), "--sequence", "2", *args]) == 0
    state = adaptation.load(out / "adaptation.toml")
    assert state.launches[adaptation.band(60.0)] == 2
    assert (out / "sequence.csv").read_text().count("\n") == 3
    assert main(["launch", "--out", str(tmp_path / "next"), "--adaptation", str(out / "adaptation.toml"), *args]) == 0
    nxt = adaptation.load(tmp_path / "next" / "adaptation.toml")
    assert nxt.launches[adaptation.band(60.0)] == 3


def test_where_cold_drag_takes_most_of_the_creep_allowed_the_hold_keeps_the_plates_apart():
    # the default design on a clutch at 14.7 C and a short CVT ratio (0.4): the open plates' drag alone pushes the
    # waiting vehicle with some 6-7 N m of the 10 allowed. Held at the kiss point, the hold's pressure wandered
    # 0.05-0.1 bar above it (the magnet's play; a valve whose static map differs from the design's) and the
    # creep came out at 11-12.5 N m on the launches after the first (0 of 9 within the limit, mean 11.8 N m; now 8 of
    # 9, mean 8.0 N m, on the host this was written on)
    plant = load(overrides={
        "driveline.J_1": 0.00885, "driveline.ratio": 0.40, "driveline.eta": 0.924, "driveline.k_a": 557.0,
        "engage.T_load": 20.6, "valve.d_stem": 69.9, "hydraulics.p_supply": 7.42e5, "hydraulics.line_length": 1.51,
        "hydraulics.p_prestress": 0.385e5, "hydraulics.x_contact": 1.265e-3, "hydraulics.leak_85C": 1.78e-12,
        "hydraulics.air_fraction": 0.0097, "friction.mu_scale": 1.11})
    d = design.cached(Params(), "launch")
    later = []
    for seed in range(1, 4):
        cond = loop.Conditions(t_ref=123.0, oil_temp_C=14.7, seed=seed, noise_scale=1.5, t_max=2.45)
        later += [r.summary for r in loop.sequence(plant, d, cond, 4)[1:]]
    creep = [s["creep_Nm"] for s in later]
    assert sum(creep) / len(creep) < 0.9 * metrics.REQ_CREEP_NM, creep
    assert sum(c <= metrics.REQ_CREEP_NM for c in creep) >= 6, creep
    # the plates a little apart cost the response little: the request's lead closes them (settled t95 0.164-0.180 s
    # before, 0.130-0.176 s now)
    assert all(s["t95_settled_s"] < metrics.REQ_T95_S for s in later), [s["t95_settled_s"] for s in later]


def test_a_clutch_whose_hold_pushes_the_waiting_vehicle_too_hard_is_held_further_apart_on_the_next_launches():
    # the default design on a cold clutch (15.8 C, CVT ratio 0.48, a stiffly damped stem, J_1 x2.6): the hold's
    # pressure jumps past the plates' contact (the stem creeps into the supply port) and the waiting vehicle is
    # pushed by 13.5-14.0 N m on the first launch. Each launch beyond the limit moves the hold a step further below
    # the kiss point: by the second, 0.02 bar, and the third launches wait within 9.8-9.9 N m (the margin stops
    # growing once the creep is within the limit)
    plant = load(overrides={
        "hydraulics.p_prestress": 79687.33104791325, "hydraulics.x_contact": 0.0016452917997275848,
        "friction.mu_scale": 1.161949344641164, "friction.mu_slope": 0.5850790391916972,
        "hydraulics.p_supply": 735563.1743817655, "hydraulics.leak_85C": 2.6624263316106387e-12,
        "valve.d_stem": 111.63189414728596, "driveline.J_1": 0.0026427959483580708,
        "hydraulics.line_length": 1.8756802503030086, "hydraulics.air_fraction": 0.009195816250854732,
        "driveline.ratio": 0.4755098635991616, "driveline.eta": 0.9193063096034653, "driveline.k_a": 621.6918429643888,
        "engage.T_load": 15.893686726351167})
    d = design.cached(Params(), "launch")
    first, third = [], []
    for seed in (1320871885, 1, 2):
        cond = loop.Conditions(t_ref=36.73130825581094, oil_temp_C=15.795923181128927, seed=seed,
                               noise_scale=0.7886551015751946, t_max=2.45)
        runs = loop.sequence(plant, d, cond, 3)
        first.append(runs[0].summary)
        third.append(runs[-1].summary)
        assert runs[-1].summary["hold_margin_Pa"] >= adaptation.MARGIN_STEP
    before = [s["creep_Nm"] for s in first]
    assert min(before) > 1.3 * metrics.REQ_CREEP_NM, before
    creep = [s["creep_Nm"] for s in third]
    assert sum(creep) < 0.75 * sum(before) and sum(creep) / len(creep) < metrics.REQ_CREEP_NM + 0.5, creep
    # the plates further apart cost the response little (settled t95 0.136-0.183 s on the third launches)
    t95 = [s["t95_settled_s"] for s in third]
    assert max(t95) < metrics.REQ_T95_S and sum(t95) / len(t95) < 0.9 * metrics.REQ_T95_S, t95


def test_the_friction_factors_slope_with_slip_is_learnt_and_speeds_the_next_launches():
    # a clutch whose mu falls with slip along a quadratic curve, designed on it, with a heavy clutch output (nine
    # times the design's) at a CVT ratio of 0.5. The friction factor's slope found from its estimate early in the slip
    # phase must order as the curves do: a curve half as steep as the design's leaves mu rising less than the design
    # expects as the slip falls (the factor falls with it: a larger slope), one half as steep again more. With the
    # slope learnt, the flatter clutch's next launches settle within the requirement (0.167-0.182 s on the host this
    # was written on; 0.214-0.233 s with the estimate's low-pass alone following the drift, its first 0.236 s)
    curve = {"friction.mu_slip_poly": [-2.2e-6, 3.2e-4, 0.024], "driveline.J_p": 1.0, "driveline.J_s": 7.5,
             "hydraulics.p_prestress": 0.8e5, "hydraulics.x_contact": 1.1e-3}
    d = design.cached(load(overrides=curve | {"driveline.ratio": 0.65, "driveline.J_1": 0.0015}), "launch")
    cond = loop.Conditions(t_ref=180.0, oil_temp_C=60.0, seed=1, t_max=2.45)
    found, runs = {}, {}
    for steepness in (0.55, 1.0, 1.45):
        plant = load(overrides=curve | {"friction.mu_slope": steepness, "driveline.ratio": 0.5,
                                        "driveline.J_1": 0.0135})
        runs[steepness] = loop.sequence(plant, d, cond, 4)
        found[steepness] = runs[steepness][0].summary["friction_slope_found"]
    assert found[0.55] > found[1.0] > found[1.45], found
    flat = runs[0.55]
    assert flat[0].summary["friction_slope_start"] is None
    assert flat[1].summary["friction_slope_start"] == pytest.approx(found[0.55])
    t95 = [r.summary["t95_settled_s"] for r in flat[1:]]
    assert max(t95) < metrics.REQ_T95_S, t95


@pytest.mark.parametrize("j_1", [0.001, 0.01, 0.03])
def test_a_launch_measures_the_clutch_output_inertia(j_1):
    # the controller is designed on the defaults (J_1 = 0.001 kg m^2) and not told the clutch's. Its slip phase must
    # show it: within 0.005 kg m^2 of the simulated plant's (the size of J_1 that changes a launch, see below)
    plant = load(overrides={"driveline.J_1": j_1, "driveline.ratio": 0.45})
    r = loop.simulate(plant, design.cached(Params(), "launch"), loop.Conditions(t_ref=60.0, oil_temp_C=60.0, seed=2))
    assert r.summary["output_inertia_start_kg_m2"] == Params().driveline.J_1
    assert r.summary["output_inertia_found_kg_m2"] == pytest.approx(j_1, abs=0.005)
    assert r.adaptation.inertia == r.summary["output_inertia_found_kg_m2"]


def test_a_heavy_clutch_output_launches_cleanly_first_time_and_after():
    # a clutch output 20 times the design's at a low ratio rings against the axle at some 10 Hz,
    # sqrt(k_a i^2 / J_1) / 2 pi. Taken for the clutch's torque, the axle torque's swing drove the friction-factor
    # estimate and, through the feedforward, kept the ring up (settled t95 0.31 s, overshoot 10 %, on every launch).
    # Told apart by J_1 w_1' (the first launch from its first 80 ms of slip on, the next from the start), it does not
    plant = load(overrides={"driveline.J_1": 0.02, "driveline.ratio": 0.45})
    runs = loop.sequence(plant, design.cached(Params(), "launch"), loop.Conditions(t_ref=60.0, oil_temp_C=60.0, seed=2), 2)
    first, second = (r.summary for r in runs)
    assert second["output_inertia_start_kg_m2"] == first["output_inertia_found_kg_m2"]
    for s in (first, second):
        assert s["all_pass"], s
        # the ring showed in the settled t95; the second launch, which knows the output rings, takes the request's
        # S-curve and overshoots by 6.7 % here (2.3 % with the two stages), within the robustness requirement
        assert s["t95_settled_s"] < metrics.REQ_T95_S - 0.03 and s["overshoot_pct"] < 10.0, s


def test_a_short_stroke_is_filled_without_pressing_the_plates():
    # a 0.55 mm stroke at a 1.4 bar prestress: 0.08 bar of stroke, 6.7 cm^3 of oil, a few ms of the full input:
    # the fill must end before the plates (no jolt on the waiting vehicle, no creep) and the launch meet every
    # requirement
    plant = load(overrides={"hydraulics.p_prestress": 1.4e5, "hydraulics.x_contact": 0.55e-3})
    s = loop.simulate(plant, design.cached(plant, "launch"), loop.Conditions(t_ref=100.0, oil_temp_C=60.0)).summary
    assert s["all_pass"], s
    assert s["standby_peak_Nm"] < 50.0 and s["creep_Nm"] < metrics.REQ_CREEP_NM, s


def test_sensor_noise_at_rest_is_not_taken_for_the_end_of_the_fills_rise():
    # a clutch whose reset spring's prestress (1.63 bar) lies 0.23 bar above its design's: the full-input fill must run
    # until the chamber's steep rise has ended there. A noisy pressure sensor at rest (its first readings, recorded on
    # such a launch, 0.08 to -0.02 bar) is flat too; taken for that end, it placed the kiss point at the search's
    # lower limit, the fill ended at once and the piston stroked only once torque was asked for (a slam of 180 %)
    d = design.cached(load(overrides={"hydraulics.p_prestress": 1.4e5}), "launch")
    rec = design.record(d, 1e-3)
    cs = control.initial_state(d.settings["p_kiss"])
    rest = [0.084, 0.047, -0.011, -0.019, 0.064]
    rise = [0.30, 0.62, 1.16, 1.633]
    stroke = [1.634 + 0.0007 * k for k in range(60)]
    meas = np.zeros(len(control.MEASURED))
    meas[control.M_WP], meas[control.M_TEMP] = 150.0, 30.0
    u = []
    for p in rest + rise + stroke:
        meas[control.M_P] = p * 1e5
        u.append(control.step(rec, cs, meas, 0.0))
    assert min(u) == rec[control.U_MAX]  # full input throughout: the stroke has 0.2 bar to go
    assert cs[control.CS_KISS] == pytest.approx(1.634e5 + d.settings["stroke_span"], abs=0.03e5)


def _state() -> adaptation.Adaptation:
    """A state with two bands, one with everything learnt and one with the kiss point alone."""
    return adaptation.Adaptation().learn(41.0, 1.0e5, 1.2, 0.002, inertia=0.02, crept=True).learn(85.0, 0.7e5)


@pytest.mark.parametrize("field", adaptation.BAND_REQUIRED)
def test_a_band_without_a_field_the_writer_always_writes_is_refused(field):
    text = _state().to_toml()
    row = next(ln for ln in text.splitlines() if ln.startswith(f"{field} = "))
    with pytest.raises(WetclutchError) as e:
        adaptation.loads(text.replace(row + "\n", "", 1), "a.toml")
    assert str(e.value).startswith(f"a.toml: band[0].{field}: missing") and "\n" not in str(e.value)


@pytest.mark.parametrize("field", ["friction_factor", "friction_slope_per_rad_s", "hold_margin_Pa"])
def test_a_band_without_what_was_not_learnt_is_read(field):
    a = _state()
    text = a.to_toml()
    row = next(ln for ln in text.splitlines() if ln.startswith(f"{field} = "))
    back = adaptation.loads(text.replace(row + "\n", "", 1))
    assert back.kiss(45.0) == a.kiss(45.0) and back.launches == a.launches
    assert {"friction_factor": back.friction, "friction_slope_per_rad_s": back.slope,
            "hold_margin_Pa": back.margin}[field] == {}


@pytest.mark.parametrize(("from_c", "to_c", "fragment"), [
    ("33.0", "50.0", "band[0].from_C: 33 C is not the lower edge of a band (-30, -10, 10, 30, 50, 70, 90, 110, 130, "
                     "150 C)"),
    ("-50.0", "-30.0", "band[0].from_C: -50 C is not the lower edge"),
    ("170.0", "190.0", "band[0].from_C: 170 C is not the lower edge"),
    ("30.0", "70.0", "band[0].to_C: must be from_C + band_C = 50 C (got 70)"),
    ("30.0", "true", "band[0].to_C: must be a finite number"),
])
def test_a_band_off_the_band_edges_is_refused(from_c, to_c, fragment):
    text = _state().to_toml().replace("from_C = 30.0", f"from_C = {from_c}", 1)
    text = text.replace("to_C = 50.0", f"to_C = {to_c}", 1)
    with pytest.raises(WetclutchError) as e:
        adaptation.loads(text, "a.toml")
    assert str(e.value).startswith(f"a.toml: {fragment}") and "\n" not in str(e.value)


def test_every_band_of_the_allowed_oil_temperatures_round_trips():
    a = adaptation.Adaptation()
    for temp in np.arange(-30.0, 151.0, 20.0):
        a = a.learn(float(temp), 1e5 + temp)
    assert sorted(a.kiss_Pa) == list(adaptation.BANDS)
    assert adaptation.loads(a.to_toml()) == a


def test_two_tables_for_one_band_are_refused_naming_the_band():
    text = _state().to_toml()
    first = text.index("[[band]]")
    second = text.index("[[band]]", first + 1)
    twice = text + "\n" + text[first:second]  # the 30..50 C band once more, after the 70..90 C band
    with pytest.raises(WetclutchError) as e:
        adaptation.loads(twice, "a.toml")
    assert str(e.value) == "a.toml: band[2]: band 30..50 C is given twice (band[0] before)"


def test_a_whole_number_of_launches_is_not_a_boolean():
    with pytest.raises(WetclutchError, match=r"band\[0\].launches: must be a whole number"):
        adaptation.loads(_state().to_toml().replace("launches = 1", "launches = true", 1))


import tomli_w  # noqa: E402
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

_number = st.one_of(st.sampled_from([-30.0, 10.0, 30.0, 33.0, 50.0, 150.0, 170.0, 1e5, 0.0]),
                    st.floats(-1e3, 1e6, allow_nan=False), st.integers(-5, 5), st.booleans(), st.text(max_size=3))
_edge = st.sampled_from([adaptation.band_from(b) for b in adaptation.BANDS])
#: a band as the writer writes it, or with any of its fields changed, left out or added
_band_row = st.one_of(
    st.builds(lambda lo, kiss, n, extra: {"from_C": lo, "to_C": lo + adaptation.BAND_C, "kiss_Pa": kiss, "launches": n}
              | extra, _edge, st.floats(0.0, 5e6), st.integers(0, 50),
              st.dictionaries(st.sampled_from([*adaptation.BAND_FIELDS, "zz"]), _number, max_size=1)),
    st.dictionaries(st.sampled_from([*adaptation.BAND_FIELDS, "zz"]), _number))


@settings(max_examples=200, deadline=None)
@given(rows=st.lists(_band_row, max_size=4))
def test_any_band_tables_load_as_the_writer_would_write_them_or_give_one_line(rows):
    text = tomli_w.dumps({"band_C": adaptation.BAND_C, "band": rows})
    try:
        a = adaptation.loads(text, "a.toml")
    except WetclutchError as e:
        assert str(e).startswith("a.toml: ") and "\n" not in str(e)
        return
    # what was read is one band per table, each on the band edges, and reads back as written
    assert len(a.kiss_Pa) == len(rows)
    for row in rows:
        b = adaptation.band(row["from_C"])
        assert b in adaptation.BANDS and row["from_C"] == adaptation.band_from(b)
        assert row["to_C"] == row["from_C"] + adaptation.BAND_C
        assert a.kiss_Pa[b] == row["kiss_Pa"] and a.launches[b] == row["launches"]
    assert adaptation.loads(a.to_toml()) == a
