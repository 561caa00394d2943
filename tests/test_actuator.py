"""Actuator physics on the virtual rig: fill phases, static gain, oil volume balance, PWM, relief, temperature."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

import wetclutch as wc
from wetclutch.physics import actuator as A
from wetclutch.physics import oil
from wetclutch.plant import clutch
from wetclutch.rig import calibration
from wetclutch.rig import experiments as rig
from wetclutch.sim.network import integrate
from wetclutch.sim.signals import Sine, Step, Table


@pytest.fixture(scope="module")
def pwm_step():
    return rig.run("step", input_mode="pwm", level=0.2, noise=False, t_end=3.0)


def test_fill_phases_in_order(pwm_step):
    t = pwm_step.truth
    h = wc.Params().hydraulics
    # the first second settles the start from an all-zero state (its inrush may just touch the
    # prestress); at the step the piston must be back at its stop
    assert t.x_piston[t.time < rig.T_STEP].iloc[-1] == 0.0
    moving = t.time[(t.time >= rig.T_STEP) & (t.x_piston > 0)].iloc[0]
    contact = t.time[t.x_piston >= h.x_contact * (1 - 1e-9)].iloc[0]
    torque = t.time[t.T_c.abs() > 0.2].iloc[0]
    assert rig.T_STEP < moving < contact <= torque
    # the piston starts at the prestress and the plates touch at 0.7 bar (the study's figure)
    assert t.p_clutch[t.time == moving].iloc[0] == pytest.approx(h.p_prestress, rel=0.05)
    # (the last sample before contact: after it the small oil volume lets the pressure jump)
    assert t.p_clutch[t.time < contact].iloc[-1] / 1e5 == pytest.approx(0.7, abs=0.02)
    # stroke: the pressure creeps (a plateau) while the piston moves, far slower than before and after
    stroke = t[(t.time > moving) & (t.time < contact)]
    assert np.ptp(stroke.p_clutch) < 0.3e5 and (contact - moving) > 0.02


def test_a_fast_fill_through_a_narrow_stroke_takes_the_strokes_oil():
    # a 1.64 bar prestress and a 0.65 mm stroke: the piston strokes between 1.64 and 1.74 bar, where its compliance is
    # a thousand times the oil's. The full input fills the chamber in 5 ms; by the plates' contact the clutch must
    # have taken the stroke's volume A_p x_contact (a step that crosses the 0.1 bar band unseen takes 4 % of it)
    params = wc.params.load(overrides={"hydraulics.p_prestress": 1.64e5, "hydraulics.x_contact": 0.65e-3})
    rn = clutch.build(params, Step(0.005, 0.0, 5.0), temp_C=30.0)
    tr = integrate(rn.network, 0.2, rtol=1e-5, atol=rn.atol(1e-9))  # a launch's tolerances
    rec = A.pack(params, 30.0)
    i0 = rn.network.actuator_state
    at = np.argmax(tr.x[:, rn.i_pressure] >= rec[A.P_CONTACT])
    assert at > 0
    taken = tr.x[at, i0 + A.VOLUME_IN] - tr.x[at, i0 + A.VOLUME_OUT]
    assert taken >= rec[A.A_P] * rec[A.X_CONTACT]


def test_static_gain_is_monotone_in_the_input():
    p = wc.Params()
    v = [0.5, 1.0, 1.5, 2.0, 3.0, 4.0]
    stat = [clutch.static_pressure(p, Step(1.0, 0.2, x), temp_C=85.0, t_end=4.0) for x in v]
    assert np.all(np.diff(stat) > 0)


def test_oil_volume_is_conserved(pwm_step):
    """Flow in - flow out (drain, leakage, relief) = piston displacement + compression of the oil."""
    t = pwm_step.truth
    rec = A.pack(wc.Params(), 85.0)

    def volume(p):
        return rec[A.V0] + rec[A.A_P] * t_piston(p)

    def t_piston(p):
        if p <= rec[A.P_PRE]:
            return 0.0
        if p >= rec[A.P_CONTACT]:
            return rec[A.X_CONTACT]
        return rec[A.A_P] * (p - rec[A.P_PRE]) / rec[A.K_RESET]

    def compliance(p):
        return volume(p) / oil.bulk_modulus(85.0, max(p, 0.0), air_fraction=rec[A.AIR])

    p0, p1 = t.p_clutch.iloc[0], t.p_clutch.iloc[-1]
    pts = sorted({p0, p1, rec[A.P_PRE], rec[A.P_CONTACT]})
    compression = sum(quad(compliance, a, b, limit=200)[0] for a, b in zip(pts[:-1], pts[1:]))
    stored = volume(p1) - volume(p0) + compression * np.sign(p1 - p0)
    net_in = (t.V_in.iloc[-1] - t.V_in.iloc[0]) - (t.V_out.iloc[-1] - t.V_out.iloc[0])
    assert net_in == pytest.approx(stored, rel=1e-4)


def test_pwm_ripple_is_small_at_the_default_frequency(pwm_step):
    t = pwm_step.truth
    settled = t.p_clutch[t.time > 2.5]
    assert np.std(settled) < 0.01e5  # well below the 0.2 bar sensor threshold


def test_relief_holds_8_bar():
    res = rig.run("step", level=5.0, noise=False, t_end=3.0)
    assert res.truth.p_clutch.max() <= wc.Params().hydraulics.p_relief * 1.01


def test_colder_oil_fills_slower():
    p = wc.Params()
    cold, _ = calibration.onset(p, 0.2, 20.0)
    warm, _ = calibration.onset(p, 0.2, 85.0)
    assert cold > 1.5 * warm


def test_study_figures_that_the_default_meets():
    """The study's dead times, contact pressure, DC static curve, valve test and hysteresis (the study's figures)."""
    figs = {f.name: f for f in calibration.run()}
    for name, f in figs.items():
        if name.startswith(("dead time", "contact pressure", "whole clutch static p vs DC", "driveline resonance",
                            "valve alone", "valve hysteresis")):
            assert f.passed, (name, f.simulated, f.error)


def test_pwm_duty_sets_the_mean_coil_current():
    rn = clutch.build(wc.Params(), Step(1.0, 0.0, 0.1), pwm=True)
    tr = integrate(rn.network, 2.0, dt_out=1e-4)
    v = wc.Params().valve
    mean_i = np.mean(tr.x[tr.t > 1.5, rn.i_current])
    assert mean_i == pytest.approx(0.1 * v.V_supply / v.R_coil, rel=0.02)


def test_feed_restriction_and_port_act_as_orifices_in_series():
    """Two equal turbulent orifices in series pass 1/sqrt(2) of one (no laminar line)."""
    p = wc.load_params(overrides={"hydraulics.line_length": 0.0})
    rec = A.pack(p, 85.0)
    nx = 13  # the actuator's five states (I, p, V_in, V_out, I_m) at 8..12
    rec[A.STATE], rec[A.STEM_SPRING] = 8, 0
    x = np.zeros(nx)
    x[0] = 1.0  # stem far open: the port is fully uncovered
    ext = np.zeros(1)
    dx_one, dx_two = np.zeros(nx), np.zeros(nx)
    rec[A.A_FEED] = 0.0  # the port alone first
    A.evaluate(x, rec, 0.0, ext, dx_one)
    rec[A.A_FEED] = rec[A.CDW] * rec[A.X_PORT] * np.sqrt(2.0 / rec[A.RHO])  # the same area as the port
    A.evaluate(x, rec, 0.0, ext, dx_two)
    assert dx_two[10] == pytest.approx(dx_one[10] / np.sqrt(2.0), rel=1e-12)


def test_flow_force_lowers_the_valve_test_pressure():
    base = calibration.staircase(wc.Params(), np.array([0.1]))[0][0]
    ff = calibration.staircase(wc.load_params(overrides={"valve.flow_force": 1.0}), np.array([0.1]))[0][0]
    assert ff < base - 0.1e5


def test_magnet_force_continues_linearly_above_saturation():
    """Quadratic below ``I_sat``; above it a straight line with the slope it had there (C1)."""
    rec = A.pack(wc.load_params(overrides={"valve.I_sat": 0.5}), 85.0)

    def f(i):
        return A.magnet_force(i, rec)

    assert f(0.3) == pytest.approx(rec[A.K_F1] * 0.3 + rec[A.K_F2] * 0.09, rel=1e-12)
    h = 1e-6
    assert (f(0.5 + h) - f(0.5)) == pytest.approx(f(0.5) - f(0.5 - h), rel=1e-4)
    assert f(1.2) - f(1.0) == pytest.approx(f(1.0) - f(0.8), rel=1e-9)
    # below the quadratic by exactly k_F2 (I - I_sat)^2
    assert rec[A.K_F1] * 1.4 + rec[A.K_F2] * 1.4**2 - f(1.4) == pytest.approx(rec[A.K_F2] * 0.9**2, rel=1e-9)


def test_magnetising_current_lags_by_the_play():
    """DC ramp up then down: I_m trails I by +I_hyst rising, -I_hyst falling, and stays put in between."""
    p = wc.load_params(overrides={"valve.I_hyst": 0.05})
    u = Table([0.0, 0.5, 2.5, 3.0, 5.0, 6.0], [0.0, 0.0, 4.0, 4.0, 1.0, 1.0], kinks_are_breakpoints=True)
    rn = clutch.build(p, u, config="valve-only")
    tr = integrate(rn.network, 6.0, dt_out=1e-3)
    cur, i_m = tr.x[:, rn.i_current], tr.x[:, rn.i_current + 4]
    rising, falling = (tr.t > 1.5) & (tr.t < 2.4), (tr.t > 4.0) & (tr.t < 4.9)
    assert np.allclose(cur[rising] - i_m[rising], 0.05, rtol=0.05)
    assert np.allclose(cur[falling] - i_m[falling], -0.05, rtol=0.05)
    hold = tr.t > 5.5  # the current has settled: the iron keeps its (down-branch) magnetisation
    assert np.ptp(i_m[hold]) < 1e-6 and np.mean(i_m[hold] - cur[hold]) == pytest.approx(0.05, rel=0.05)


@pytest.mark.parametrize("n", [2, 5, 8, 32])
def test_the_smoothed_play_follows_its_closed_form_on_a_rising_current(n):
    """On a current that only rises, the play is rate-independent: the lag ``z = (I - I_m) / I_hyst`` obeys
    ``dz/dxi = 1 - z^n`` in ``xi = (I - I_0) / I_hyst``, so ``xi(z) = integral_0^z dv / (1 - v^n)``."""
    r = 0.05
    p = wc.load_params(overrides={"valve.I_hyst": r, "valve.play_exponent": n})
    u = Table([0.0, 0.5, 2.5, 3.0], [0.0, 0.0, 4.0, 4.0], kinks_are_breakpoints=True)
    rn = clutch.build(p, u, config="valve-only")
    tr = integrate(rn.network, 2.5, dt_out=1e-3)
    cur, i_m = tr.x[:, rn.i_current], tr.x[:, rn.i_current + A.MAGNETISATION]
    assert np.all(np.diff(cur[tr.t > 0.5]) > 0.0)  # the closed form holds for a current that only rises
    z, xi = (cur - i_m) / r, cur / r
    pick = (z > 0.2) & (z < 0.97)
    assert pick.sum() > 20
    want = np.array([quad(lambda v: 1.0 / (1.0 - v**n), 0.0, zi)[0] for zi in z[pick]])
    assert np.allclose(xi[pick], want, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("n", [8, 32])
def test_the_iron_stays_put_after_the_current_turns_until_the_play_is_crossed(n):
    """The engine maps the magnetisation along a monotone current and locates the current's turns. After a turn the
    lag is negative until the current has moved back by it, and ``dI_m/dt`` is exactly 0 there: ``I_m`` holds its
    value (a map carried through the turn would run back down the curve with the current)."""
    p = wc.load_params(overrides={"valve.I_hyst": 0.045, "valve.play_exponent": n})
    rn = clutch.build(p, Sine(0.6, 7.0, offset=2.5), config="valve-only")  # +-0.12 A on the coil: the play crossed
    tr = integrate(rn.network, 1.0, dt_out=1e-4)
    cur, i_m = tr.x[:, rn.i_current], tr.x[:, rn.i_current + A.MAGNETISATION]
    assert tr.stats["turns"] == 14  # every half period of the 7 Hz input
    d = np.sign(np.diff(cur))
    turns = np.flatnonzero(d[1:] != d[:-1]) + 1  # the extreme sample; the next lies past the turn
    checked = 0
    for k in turns[turns < cur.size - 2]:
        lag = abs(cur[k] - i_m[k])
        inside = np.flatnonzero(np.abs(cur[k + 1:] - cur[k]) > 0.9 * lag)
        end = k + 1 + (inside[0] if inside.size else cur.size - k - 1)
        assert np.max(np.abs(i_m[k + 1:end] - i_m[k + 1])) < 1e-12
        checked += end - k - 1
    assert checked > 1000


def test_valve_staircase_shows_the_magnetic_hysteresis_under_pwm():
    """Up and down staircases differ visibly (the PWM ripple does not dither the play out); none without it."""
    d = np.array([0.1, 0.2, 0.3])  # the top step is the turning point: compare the two below it
    up, down = calibration.staircase(wc.Params(), d)
    assert np.all(down[:2] - up[:2] > 0.05e5)
    up0, down0 = calibration.staircase(wc.load_params(overrides={"valve.I_hyst": 0.0}), d)
    assert np.all(np.abs(down0 - up0) < 0.01e5)


def test_valve_staircase_under_dc_runs_down_its_steps_and_shows_the_hysteresis():
    # the staircase's 1 ms falling steps, where a DC amplifier's controller asks for less than 0 V
    r = rig.run("staircase", config="valve-only", input_mode="dc", level=1.0, seed=3)
    m = r.truth
    ends = 1.0 + 1.5 * np.arange(1, 13) - 0.01  # the end of each of the 12 steps (6 up, 6 down)
    i = np.searchsorted(m.time.to_numpy(), ends)
    cur, p = m.coil_current.to_numpy()[i], m.p_clutch.to_numpy()[i]
    u = np.concatenate([np.linspace(0.2, 1.0, 7)[1:], np.linspace(1.0, 0.2, 7)[1:]])
    assert cur == pytest.approx(0.2 * u, abs=1e-6)  # the current controller settles on every step
    up, down = p[:5], p[6:11][::-1]  # at the same inputs, 0.33-0.87 V
    assert np.all(down > up + 0.01e5)


def test_seal_leak_is_a_gap_in_series_with_an_orifice():
    rec = A.pack(wc.Params(), 85.0)
    p = 4e5
    rec[A.G_LEAK], rec[A.K_SEAL] = 1e-10, 3e-8
    q = A.seal_leak(p, rec)
    assert q / rec[A.G_LEAK] + (q / rec[A.K_SEAL]) ** 2 == pytest.approx(p, rel=1e-12)
    rec[A.K_SEAL] = 1e-3  # orifice wide open: the laminar gap alone
    assert A.seal_leak(p, rec) == pytest.approx(1e-10 * p, rel=1e-6)
    rec[A.G_LEAK], rec[A.K_SEAL] = 1e-3, 3e-8  # gap wide open: the orifice alone
    assert A.seal_leak(p, rec) == pytest.approx(3e-8 * np.sqrt(p), rel=1e-4)
    rec[A.K_SEAL] = 0.0  # no orifice given: laminar only, as before
    assert A.seal_leak(p, rec) == 1e-3 * p


def test_turbulent_seal_leak_makes_the_static_pressure_rise_with_temperature():
    """With the seal rings' orifice the leak, lost in the viscous feed line, lowers the cold pressure most."""
    # without the feedback chamber, whose own trend would hide this one; a force balance near 5 bar
    base = {"valve.fb_orifice": 0.0, "valve.F_preload": 2.0}
    p = wc.load_params(overrides={**base, "hydraulics.leak_85C": 8e-10, "hydraulics.seal_orifice": 6.3e-8})
    cold, warm = (clutch.static_pressure(p, Step(1.0, 0.0, 0.2), pwm=True, temp_C=temp, t_end=4.0) for temp in (20.0, 85.0))
    assert warm - cold > 0.5e5
    # laminar seal gap only, no feedback chamber: the force balance, whatever the viscosity
    d = wc.load_params(overrides=base)
    cold0, warm0 = (clutch.static_pressure(d, Step(1.0, 0.0, 0.2), pwm=True, temp_C=temp, t_end=4.0) for temp in (20.0, 85.0))
    assert abs(warm0 - cold0) < 0.2e5


def test_feedback_chamber_is_an_orifice_in_series_with_a_laminar_gap():
    """The stem feels the outlet pressure less the damping orifice's drop at the guide's leak."""
    rec = A.pack(wc.Params(), 85.0)
    p = 7e5
    q = A.feedback_flow(p, rec)
    p_fb = A.feedback_pressure(p, q, rec)
    assert q == pytest.approx(rec[A.FB_GAP] * p_fb, rel=1e-12)  # no vent: the gap carries p_fb to the tank
    assert p - p_fb == pytest.approx((q / rec[A.FB_DAMP]) ** 2, rel=1e-12)
    # the leak is laminar: cold oil leaks less, so the stem feels nearly all of the outlet pressure
    cold = A.pack(wc.Params(), 20.0)
    assert p - A.feedback_pressure(p, A.feedback_flow(p, cold), cold) < 0.2 * (p - p_fb)
    # small pressures feel it less (the drop grows with the square of the leak)
    assert (1e5 - A.feedback_pressure(1e5, A.feedback_flow(1e5, rec), rec)) / 1e5 < 0.5 * (p - p_fb) / p


def test_static_pressure_follows_the_studys_temperature_curve_linear_in_fluidity():
    """The study: p = 4.8e-4 T^2 + 4.1e-4 T + 4.2 bar at pdc 0.2, a straight line in 1/viscosity."""
    temps = np.array([20.0, 41.0, 60.0, 85.0])
    study = 4.8e-4 * temps**2 + 4.1e-4 * temps + 4.2
    fluidity = 1.0 / oil.dynamic_viscosity(temps)
    line = np.polyval(np.polyfit(fluidity, study, 1), fluidity)
    assert np.max(np.abs(line / study - 1.0)) < 0.003
    sim = np.array([clutch.static_pressure(wc.Params(), Step(1.0, 0.0, 0.2), pwm=True, temp_C=t, t_end=4.0)
                    for t in temps]) / 1e5
    assert np.max(np.abs(sim / study - 1.0)) < 0.1
    # without the chamber the force balance gives the same pressure cold and warm, far from the study's 7.7 bar
    flat = wc.load_params(overrides={"valve.fb_orifice": 0.0})
    cold, warm = (clutch.static_pressure(flat, Step(1.0, 0.0, 0.2), pwm=True, temp_C=t, t_end=4.0) / 1e5
                  for t in (20.0, 85.0))
    assert abs(warm - cold) < 0.2 and study[-1] - warm > 2.0


def test_output_rows_carry_the_torques_of_their_states():
    # output rows take a reduced evaluation (no accelerations, no pressure derivative): the
    # torques they report must still follow from the row's own state
    params = wc.Params()
    rn = clutch.build(params, Step(1.0, 0.2, 1.5), temp_C=85.0)
    tr = integrate(rn.network, 3.0)
    rec = A.pack(params, 85.0)
    p = tr.x[:, rn.i_pressure]
    f_n = np.where(p > rec[A.P_CONTACT], rec[A.A_P] * (p - rec[A.P_CONTACT]), 0.0)
    cap = f_n * f_n / (f_n + rec[A.F_KNEE])
    assert np.allclose(tr.capacity("clutch"), cap, rtol=1e-12, atol=1e-9)
    slip = tr.speed("p") - tr.speed("1")
    mode = tr.modes[:, 0]
    sliding = np.abs(mode) == 1
    assert sliding.sum() > 1000
    mu = np.polyval([c * params.friction.mu_scale for c in params.friction.mu_slip_poly], np.abs(slip))
    assert np.allclose(tr.clutch_torque("clutch")[sliding], (mode * cap * np.maximum(mu, 0.0))[sliding], rtol=1e-12)
    d = params.driveline
    twist = tr.x[:, len(rn.network.bodies) + [s.name for s in rn.network.springs].index("axle")]
    axle = d.k_a * twist + d.d_a * (tr.speed("r") - tr.speed("s"))
    assert np.allclose(tr.spring_torque("axle"), axle, rtol=1e-12, atol=1e-9)
    # the CVT output body is massless: the gear's output torque (a constraint torque) carries the axle
    assert np.abs(tr.gear_torque("cvt")).max() > 10.0
    assert np.allclose(tr.gear_torque("cvt"), tr.spring_torque("axle"), rtol=1e-9, atol=1e-7)


def _independent_model():
    """``benchmarks/scipy_actuator.py``: the same equations written out by hand for solve_ivp."""
    bench = Path(__file__).resolve().parents[1] / "benchmarks"
    sys.path.insert(0, str(bench))  # it imports its sibling _timing
    try:
        spec = importlib.util.spec_from_file_location("scipy_actuator", bench / "scipy_actuator.py")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
    finally:
        sys.path.remove(str(bench))
    return mod


def test_engine_agrees_with_an_independent_implementation_of_the_same_equations():
    # A clutch step (0.2 -> 1 V at 1 s, 85 C) through fill, contact, the road load's release and
    # 19 stem stick/slip switches, written a second time as a plain solve_ivp model (BDF, rtol 1e-6)
    # with its own event logic: pressure, onset, event sequence and every energy term must agree.
    sp_mod = _independent_model()
    sp = sp_mod.actuator_step_scipy(5.0)
    rn = clutch.build(wc.Params(), Step(1.0, 0.2, 1.0), temp_C=85.0)
    tr = integrate(rn.network, 5.0)
    # the engine's turns of the coil current (where it follows the magnet's play anew) are its own, not the model's:
    # here the current's settling, which overshoots its set point by a few nA at the step's tolerance
    assert sp["n_events"] == tr.stats["events"] - tr.stats["turns"]
    stem = np.flatnonzero(np.array([name.startswith("stem") for _, name in sp["log"]]))
    assert stem.size == np.count_nonzero(tr.events[:, 1] == 2)
    p_eng = tr.x[:, rn.i_pressure]
    assert np.max(np.abs(np.interp(tr.t, sp["t"], sp["p_clutch"]) - p_eng)) < 200.0  # Pa, of up to 1.6 bar
    T_c = np.abs(tr.clutch_torque("clutch"))
    onset = tr.t[np.argmax(T_c > 0.2)]
    assert sp["onset_time"] <= onset < sp["onset_time"] + 1e-3  # the first 1 ms sample after it
    e = tr.energies()
    for name, value in zip(sp_mod.ENERGY_TERMS, sp["y_end"][sp_mod.E_CL : sp_mod.V_IN], strict=True):
        assert value == pytest.approx(e[name][-1], rel=1e-3), name
    i0 = rn.network.actuator_state
    assert sp["y_end"][sp_mod.V_IN] == pytest.approx(tr.x[-1, i0 + 2], rel=1e-3)
    assert sp["y_end"][sp_mod.V_OUT] == pytest.approx(tr.x[-1, i0 + 3], rel=1e-3)
    assert sp_mod.energy_residual(sp_mod.Rig(), sp["y"]) < 1e-6


def test_the_stem_speed_tolerance_keeps_the_dithered_valve_accurate_in_fewer_steps():
    # a square dither of 0.35 V at 167 Hz around 2.5 V, as the launch controller drives the valve: the stem
    # reverses every 3 ms, where an absolute tolerance made for positions would ask for nm/s on its speed
    t, v = [0.0], [0.2]
    for k in range(120):
        t0 = 0.1 + k * 3e-3
        t += [t0, t0 + 1e-6]
        v += [v[-1], 2.5 + (0.35 if k % 2 == 0 else -0.35)]
    rn = clutch.build(wc.Params(), Table(np.array(t), np.array(v), kinks_are_breakpoints=True))
    ref = integrate(rn.network, 0.5, dt_out=1e-4, rtol=1e-9, atol=1e-12)
    flat = integrate(rn.network, 0.5, dt_out=1e-4, rtol=1e-5, atol=1e-9)
    per_state = integrate(rn.network, 0.5, dt_out=1e-4, rtol=1e-5, atol=rn.atol(1e-9))
    pos = ref.spring_deflection("stem_spring")
    hold = ref.t > 0.3
    # the stem's stroke (0.9 mm) to 0.3 %, the held pressure (4.2 bar) to 1 mbar
    err = [np.sqrt(np.mean((tr.spring_deflection("stem_spring") - pos) ** 2)) for tr in (flat, per_state)]
    assert err[1] < 3e-6
    assert abs(np.mean(per_state.x[hold, rn.i_pressure]) - np.mean(ref.x[hold, rn.i_pressure])) < 100.0
    # in fewer steps than the flat tolerance, with the reference's stick/slip history (the flat tolerance's history,
    # the stem stopping for an instant or not, may part from the reference's, and its error with it: 5.6e-6 on the
    # stroke where it did, 2.3e-8 where it did not)
    steps = [tr.stats["steps"] + tr.stats["rejected"] for tr in (flat, per_state)]
    assert steps[1] < 0.8 * steps[0]
    # the same stick/slip history: every clutch and stem event of the reference, of the same kind, within 0.1 ms
    assert np.array_equal(ref.events[:, 1:], per_state.events[:, 1:])
    assert np.max(np.abs(ref.events[:, 0] - per_state.events[:, 0])) < 1e-4


def test_a_falling_ramp_is_followed_below_zero_volts_by_the_regulating_stage():
    # the rig's staircase steps down by 0.133 V in 1 ms. The current lags the ramp i_ref = i_0 + r t by -r / a
    # (a = (R + K) / L), so the controller asks for v = R i_ref + K (i_ref - i) of about -1.4 V: below zero, above
    # the freewheel circuit's -R_fw i, where the transistor carries part of the coil current. The current follows
    # L di/dt = (R + K) (i_ref - i): i = i_ref - (r / a) (1 - exp(-a t)) on the ramp, then exp(-a t) towards the
    # end. (An output stage that jumped to the freewheel's voltage below 0 V held the current on that edge by
    # switching at once back and forth: the run ended as Zeno behaviour.)
    v = wc.Params().valve
    R, L, K, g = v.R_coil, v.L_coil, v.amp_gain, v.g_current
    u0, u1, t0, ramp = 1.0, 1.0 - 0.8 / 6, 1.0, 1e-3
    a, r = (R + K) / L, g * (u1 - u0) / ramp
    rn = clutch.build(wc.Params(), Table(np.array([0.0, t0, t0 + ramp]), np.array([u0, u0, u1]),
                                         kinks_are_breakpoints=True), temp_C=85.0)
    tr = integrate(rn.network, t0 + 0.01, dt_out=1e-5)
    s = tr.t[tr.t >= t0] - t0
    cur = tr.x[tr.t >= t0, rn.network.actuator_state + A.CURRENT]
    on_ramp = g * u0 + r * s - r / a * (1.0 - np.exp(-a * s))
    end = g * u0 + r * ramp - r / a * (1.0 - np.exp(-a * ramp))
    after = g * u1 + (end - g * u1) * np.exp(-a * (s - ramp))
    exact = np.where(s < ramp, on_ramp, after)
    assert np.max(np.abs(cur - exact)) < 2e-8  # A, of 0.17-0.2 A
    v_ctrl = R * g * u1 + K * (g * u1 - end)  # the controller's voltage at the ramp's end
    assert -v.R_freewheel * end < v_ctrl < -1.0


@pytest.mark.parametrize(("u1", "u2"), [(4.0, 1.0), (1.0, 4.0)])
def test_coil_current_through_the_amplifier_stage_limits_follows_the_closed_form(u1, u2):
    # a DC input step from u1 to u2 at 1 s, the current settled at g u1 before it. The current controller's
    # voltage v = R i_ref + K (i_ref - i) is out of the stage's range at first: going down it is below the freewheel
    # circuit's -R_fw i, the transistor blocks and the current decays through the freewheel, di/dt = -(R + R_fw) i / L,
    # until v = -R_fw i at i* = i_ref (R + K) / (K - R_fw); going up the stage saturates, di/dt = (V - R i) / L, until v = V at
    # i* = (i_ref (R + K) - V) / K. Then it regulates: i -> i_ref with the rate (R + K) / L.
    v = wc.Params().valve
    R, L, K, g = v.R_coil, v.L_coil, v.amp_gain, v.g_current
    i0, i_ref = g * u1, g * u2
    if u2 < u1:
        rate, i_inf, i_sw = (R + v.R_freewheel) / L, 0.0, i_ref * (R + K) / (K - v.R_freewheel)
    else:
        rate, i_inf, i_sw = R / L, v.V_supply / R, (i_ref * (R + K) - v.V_supply) / K
    t_sw = np.log((i0 - i_inf) / (i_sw - i_inf)) / rate  # 3.4 ms down, 2.4 ms up: 20-40 samples on the limit

    rn = clutch.build(wc.Params(), Step(1.0, u1, u2), temp_C=85.0)
    tr = integrate(rn.network, 1.03, dt_out=1e-4)
    s = tr.t[tr.t >= 1.0] - 1.0
    cur = tr.x[tr.t >= 1.0, rn.network.actuator_state + A.CURRENT]
    exact = np.where(s < t_sw, i_inf + (i0 - i_inf) * np.exp(-rate * s),
                     i_ref + (i_sw - i_ref) * np.exp(-(R + K) / L * (s - t_sw)))
    # A, of 0.2-0.8 A: rtol 1e-8 holds the RMS of the step's errors over all states, so the current alone may take a
    # few times its share (1.3e-8 since the magnet's play, the stiffest mode, no longer holds the steps short)
    assert np.max(np.abs(cur - exact)) < 2e-8
