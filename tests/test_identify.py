"""Identification: round trip on virtual-rig data with known parameters, file robustness, channel maps, CLI."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy import io as sio
from scipy import signal

from inprocess import invoke
from wetclutch import ident, params
from wetclutch.ident import dynamics, onset
from wetclutch.ident.friction import measured_ratio
from wetclutch.ident import recordings as channels
from wetclutch.errors import WetclutchError
from wetclutch.physics import actuator
from wetclutch.plant import driveline
from wetclutch.report.identify import measured_cell
from wetclutch.report import identify as identify_report
from wetclutch.report import rig as rig_report
from wetclutch.rig import experiments as rig
from wetclutch.rig.onset import TORQUE_ONSET, first_crossing

#: the rig's true parameters: not the defaults, so that recovering them means something
TRUE = {"friction.mu_slip_poly": [-1.2e-6, 2.2e-4, 3.0e-2], "driveline.ratio": 0.6}
RUNS = {
    # 1.8 V: about 1.6 bar at 41 C (the valve settles lower in cooler oil, as the study measured)
    "step41": dict(experiment="step", level=1.8, oil_temp_C=41.0, seed=1),
    "step85": dict(experiment="step", level=2.5, oil_temp_C=85.0, seed=2),
    "stair": dict(experiment="staircase", config="valve-only", input_mode="pwm", level=0.15, from_=0.0, seed=3),
    "noise": dict(experiment="noise", config="valve-only", input_mode="pwm", level=0.15, from_=0.0, seed=4),
}


@pytest.fixture(scope="module")
def rig_data(tmp_path_factory):
    """The virtual rig's runs with the true parameters, written like a real rig (once per module)."""
    p = params.load(overrides=TRUE)
    root = tmp_path_factory.mktemp("rig_runs")
    results = {}
    for name, kw in RUNS.items():
        kw = dict(kw)
        res = rig.run(kw.pop("experiment"), p, **kw)
        rig_report.write(res, root / name)
        results[name] = res
    return p, root, results


@pytest.fixture(scope="module")
def identified(rig_data):
    _, root, _ = rig_data
    recs = [channels.load(root / n / f"measured.{ext}") for n, ext in zip(RUNS, ("mf4", "csv", "mat", "mf4"))]
    return ident.identify(recs)


def true_dead_time(res: rig.RigResult) -> float:
    tr = res.truth
    t_on = first_crossing(tr.time.to_numpy(), np.abs(tr.T_c.to_numpy()), TORQUE_ONSET)[0]
    return t_on - rig.T_STEP


@pytest.mark.parametrize("i_hyst", [0.03, 0.08])
def test_the_magnets_play_is_found_from_the_valves_up_and_down_staircases(i_hyst, tmp_path):
    """A valve whose play differs from the prior's: the PWM staircase's up and down plateaus give its half-width."""
    from wetclutch.ident.play import play_half_width
    from wetclutch.ident.static import plateaus

    p = params.load(overrides={"valve.I_hyst": i_hyst})
    kw = dict(RUNS["stair"])
    rig_report.write(rig.run(kw.pop("experiment"), p, **kw), tmp_path / "stair")
    rec = channels.load(tmp_path / "stair" / "measured.csv")
    est = play_half_width(plateaus(rec), params.Params())
    assert est is not None and est.value == pytest.approx(i_hyst, rel=0.03)
    assert est.extra["pairs"] >= 5 and 0.0 < est.se < 0.1 * i_hyst
    # the chain takes it into the identified parameters
    assert ident.identify([rec]).identified.valve.I_hyst == pytest.approx(est.value, rel=1e-12)


# ---------------------------------------------------------------- round trip


def test_files_are_read_as_the_experiments_they_are(identified):
    kinds = [(r.experiment, r.config, r.input_mode) for r in identified.recordings]
    assert kinds == [("step", "clutch", "dc"), ("step", "clutch", "dc"), ("staircase", "valve-only", "pwm"),
                     ("noise", "valve-only", "pwm")]


def test_friction_polynomial_is_recovered(identified):
    est = identified.estimates["mu_slip_poly"]
    true = np.array(TRUE["friction.mu_slip_poly"])
    np.testing.assert_allclose(est.value, true, rtol=0.05)
    w = np.linspace(10.0, 150.0, 50)
    assert np.max(np.abs(np.polyval(est.value, w) / np.polyval(true, w) - 1.0)) < 0.02
    assert all(s > 0 for s in est.se)
    # the standard errors are honest: the truth lies within a few of them
    assert np.all(np.abs(np.array(est.value) - true) < 6.0 * np.array(est.se) + 0.01 * np.abs(true))


def test_dead_time_and_contact_pressure_are_recovered(identified, rig_data):
    p, _, results = rig_data
    assert len(identified.onsets) == 2
    for o, name in zip(identified.onsets, ("step41", "step85")):
        assert abs(o.dead_time - true_dead_time(results[name])) < 0.015, name
        assert abs(o.rec.oil_temp_C - RUNS[name]["oil_temp_C"]) < 0.5
    est = identified.estimates["contact_pressure_Pa"]
    assert abs(est.value - actuator.contact_pressure(p)) < 0.05e5
    start = identified.estimates["stroke_start_Pa"]
    assert abs(start.value - p.hydraulics.p_prestress) < max(4.0 * start.se, 0.015e5)
    dts = {round(o.rec.oil_temp_C): o.dead_time for o in identified.onsets}
    assert dts[41] > dts[85]  # cold oil fills slower (the study's dead times)


def test_ratio_and_resonance_are_recovered(identified, rig_data):
    _, _, results = rig_data
    assert abs(identified.estimates["ratio"].value / TRUE["driveline.ratio"] - 1.0) < 0.005
    for rg in identified.ringings:
        tr = results["step41" if "step41" in str(rg.rec.path) else "step85"]
        after = tr.truth[tr.truth.time > tr.meta["t_sync"] + 0.2]
        f_true = driveline.ring_frequency(after.time.to_numpy(), after.T_r.to_numpy())
        assert abs(rg.freq / f_true - 1.0) < 0.02
        assert 0.0 < rg.zeta < 0.2
    assert len(identified.ringings) == 2


def test_inertias_of_the_default_driveline_are_recovered(identified):
    # the rig of the round trip keeps the default inertias; the clutch output's is too small to show
    assert identified.estimates["J_p"].value == pytest.approx(params.Driveline().J_p, rel=0.02)
    assert identified.estimates["J_s"].value == pytest.approx(params.Driveline().J_s, rel=0.02)
    assert "J_1" not in identified.estimates
    assert identified.identified.driveline.J_1 == identified.prior.driveline.J_1
    status, why = identified.sources()["driveline.J_1"]
    assert status == "prior" and why.startswith("not excited by the data")


def _rig_runs(root: Path, overrides: dict, runs: dict) -> list[channels.Recording]:
    """Rig runs of a clutch with ``overrides``, written like a real rig, read back."""
    p = params.load(overrides=overrides)
    recs = []
    for name, kw in runs.items():
        kw = dict(kw)
        rig_report.write(rig.run(kw.pop("experiment"), p, **kw), root / name)
        recs.append(channels.load(root / name / "measured.csv"))
    return recs


CLUTCH_STEPS = {k: RUNS[k] for k in ("step41", "step85")}


@pytest.mark.parametrize("overrides, identified_within, kept", [
    # heavier primary, lighter secondary, a clutch output 5 times the default: too light to be excited
    ({"driveline.J_p": 1.8, "driveline.J_s": 4.0, "driveline.J_1": 5e-3}, {"J_p": 0.02, "J_s": 0.02}, ["J_1"]),
    # a clutch output 50 times the default: its acceleration in the slip phase shows
    ({"driveline.J_1": 5e-2}, {"J_p": 0.02, "J_s": 0.02, "J_1": 0.15}, []),
])
def test_inertias_are_identified_where_the_data_excite_them(tmp_path, overrides, identified_within, kept):
    recs = _rig_runs(tmp_path, overrides, {"step85": RUNS["step85"]})
    res = ident.identify(recs)
    true = params.load(overrides=overrides).driveline
    for name, rel in identified_within.items():
        est = res.estimates[name]
        assert est.value == pytest.approx(getattr(true, name), rel=rel), name
        assert 0 < est.se < 0.1 * est.value
        assert getattr(res.identified.driveline, name) == est.value
        assert res.sources()[f"driveline.{name}"][0] == "identified"
    for name in kept:
        assert name not in res.estimates
        assert getattr(res.identified.driveline, name) == getattr(params.Driveline(), name)
        assert res.sources()[f"driveline.{name}"][1].startswith("not excited by the data")
        assert res.as_json()["parameters"][f"driveline.{name}"] == "prior"
    # the report tells the user what an inertia it could not identify means for the launch, and only then
    assert (identify_report.J1_FROM_PRIOR in identify_report._report(res, [])) == ("J_1" in kept)
    # the ring-out frequency gives the axle stiffness through the identified inertias
    assert res.identified.driveline.k_a == pytest.approx(true.k_a, rel=0.03)


@pytest.mark.parametrize("p0, slope, stroke", [(0.5e5, 1.1e5, 0.25), (0.8e5, 2.0e5, 0.09), (0.3e5, 0.4e5, 0.6)])
def test_the_stroke_start_is_where_the_first_rise_meets_the_stroke_line(p0, slope, stroke):
    """A synthetic fill with a known prestress: a rise within 3 ms from 0.1 bar to ``p0``, a linear stroke, the
    sensor's noise (0.02 bar)."""
    t = np.arange(0.0, 2.0, 1e-3)
    t_cmd = 1.0
    rise = np.clip((t - t_cmd) / 0.003, 0.0, 1.0)
    p = 0.1e5 + (p0 - 0.1e5) * rise + slope * np.clip(t - t_cmd - 0.003, 0.0, None)
    p += np.random.default_rng(1).normal(0.0, 0.02e5, t.size)
    k_cmd = int(np.argmax(t >= t_cmd))
    value, se = onset.stroke_start(t, p, k_cmd, t_cmd + stroke, p0 + slope * stroke)
    assert 200.0 < se < 0.02e5  # the sensor's 2 kPa of noise over a few hundred samples, extrapolated
    assert abs(value - p0) < 4.0 * se + 0.002e5


def test_a_stroke_too_short_to_show_gives_no_start():
    t = np.arange(0.0, 2.0, 1e-3)
    p = np.where(t >= 1.0, 0.8e5, 0.1e5)
    value, se = onset.stroke_start(t, p, 1000, 1.0 + onset.MIN_STROKE_SAMPLES * 1e-3 / 2, 0.9e5)
    assert np.isnan(value) and np.isnan(se)
    # the report's per-run table shows a dash for it, not "nan ± nan"
    assert measured_cell(value / 1e5, se / 1e5, 3) == "–"
    assert measured_cell(0.3481, 0.0021, 3) == "0.348 ± 0.002"
    assert measured_cell(0.3481, float("nan"), 3) == "0.348"


def test_a_prestress_unlike_the_prior_is_identified_and_the_stroke_follows(tmp_path):
    """Prestress 0.8 bar (prior 0.5) and a stroke of 1.2 mm: the contact pressure alone, read with the prior's
    prestress, would put the stroke at 3.2 mm, and the fill's volume with it."""
    true = {**TRUE, "hydraulics.p_prestress": 0.8e5, "hydraulics.x_contact": 1.2e-3}
    res = ident.identify(_rig_runs(tmp_path, true, CLUTCH_STEPS))
    h = params.load(overrides=true).hydraulics
    start = res.estimates["stroke_start_Pa"]
    assert start.value == pytest.approx(h.p_prestress, abs=max(4.0 * start.se, 0.03e5))
    assert res.identified.hydraulics.p_prestress == start.value
    assert res.identified.hydraulics.x_contact == pytest.approx(h.x_contact, rel=0.15)
    assert res.sources()["hydraulics.p_prestress"][0] == "identified"


@pytest.fixture(scope="module")
def slow_cvt_input(tmp_path_factory):
    """Runs at a CVT ratio of 1.25: the CVT input turns too slowly for the speed sensors to give the ratio."""
    root = tmp_path_factory.mktemp("ratio125")
    return root, _rig_runs(root, {**TRUE, "driveline.ratio": 1.25}, CLUTCH_STEPS)


def test_friction_is_identified_with_the_commanded_ratio_when_the_speeds_cannot_give_it(slow_cvt_input, tmp_path):
    _, recs = slow_cvt_input
    assert all(np.isnan(measured_ratio(r)[0]) for r in recs)
    res = ident.identify(recs)
    assert "ratio" not in res.estimates
    assert res.identified.driveline.ratio == 1.25  # the rig's setting in meta.json, not the prior's 0.5
    w = np.linspace(20.0, 120.0, 30)
    true = np.polyval(TRUE["friction.mu_slip_poly"], w)
    assert np.max(np.abs(np.polyval(res.estimates["mu_slip_poly"].value, w) / true - 1.0)) < 0.03
    data = res.as_json()
    assert data["parameters"]["driveline.ratio"] == "prior"
    assert "commanded ratio 1.25" in data["parameter_reasons"]["driveline.ratio"]
    assert data["parameters"]["friction.mu_slip_poly"] == "identified"
    identify_report.write(res, tmp_path / "out")
    report = (tmp_path / "out" / "report.md").read_text()
    assert "| driveline.ratio | prior | not measured, the commanded ratio 1.25 (meta.json of the runs) is used" in report
    assert "commanded ratio 1.25" in (tmp_path / "out" / "report.html").read_text()


def test_a_ringing_that_dies_early_in_a_long_quiet_window_gives_the_axle(tmp_path):
    # a clutch at a CVT ratio of 1.25 with a 2 bar prestress and a stickier valve: after the lock-up the driveline
    # rings at 4.8 Hz and is quiet after half a second of a 2.3 s window, whose noise crosses the mean far more often
    # than the ringing did. Started from the zero crossings alone the fit settled on 30 Hz, undamped, and made the
    # axle 38 times too stiff; the periodogram's peak starts it on the ringing
    overrides = {"driveline.ratio": 1.25, "driveline.J_p": 0.9, "driveline.J_s": 5.0, "driveline.J_1": 0.002,
                 "hydraulics.p_prestress": 2e5, "hydraulics.x_contact": 0.0014, "hydraulics.A_p": 0.0105,
                 "hydraulics.p_supply": 1e6, "hydraulics.p_relief": 1e6, "friction.mu_scale": 1.15,
                 "friction.drag_20C": 0.02, "valve.F_friction": 0.15, "valve.I_hyst": 0.06}
    res = ident.identify(_rig_runs(tmp_path, overrides, {"step85": RUNS["step85"]}))
    true = params.load(overrides=overrides).driveline
    (rg,) = res.ringings
    assert rg.freq == pytest.approx(4.8, rel=0.02) and 0.1 < rg.zeta < 0.25
    assert res.identified.driveline.k_a == pytest.approx(true.k_a, rel=0.05)
    assert res.identified.driveline.d_a == pytest.approx(true.d_a, rel=0.1)


def test_without_the_secondary_speed_its_inertia_is_the_prior_and_said(slow_cvt_input):
    _, recs = slow_cvt_input
    bare = [channels.Recording(r.path, {k: v for k, v in r.data.items() if k != "omega_s"}, r.experiment, r.config,
                               r.input_mode, r.meta) for r in recs]
    res = ident.identify(bare)
    assert "J_s" not in res.estimates and "J_p" in res.estimates
    assert res.sources()["driveline.J_s"] == ("prior", "no omega_s channel")


def test_without_a_commanded_ratio_the_prior_ratio_is_used_and_said(slow_cvt_input, tmp_path):
    root, _ = slow_cvt_input
    for name in CLUTCH_STEPS:  # the files alone, as a rig without meta.json would write them
        shutil.copy(root / name / "measured.csv", tmp_path / f"{name}.csv")
    recs = [channels.load(tmp_path / f"{name}.csv") for name in CLUTCH_STEPS]
    prior = params.load(overrides={"driveline.ratio": 1.25})
    res = ident.identify(recs, prior)
    assert res.identified.driveline.ratio == 1.25
    assert "mu_slip_poly" in res.estimates
    assert "prior ratio 1.25" in res.sources()["driveline.ratio"][1]
    # with a wrong prior ratio, mu is wrong by that factor: the ratio scales the clutch torque from T_r
    wrong = ident.identify(recs, params.load(overrides={"driveline.ratio": 1.0}))
    assert np.polyval(wrong.estimates["mu_slip_poly"].value, 60.0) == pytest.approx(
        np.polyval(res.estimates["mu_slip_poly"].value, 60.0) * 1.0 / 1.25, rel=0.01)


def test_valve_gain_matches_the_true_static_pressures(identified, rig_data):
    _, _, results = rig_data
    est = identified.estimates["valve_gain"]
    truth = results["stair"].truth
    fit = identified.estimates["valve_gain_poly"]
    us, ps = [], []
    for u, _ in fit.extra["points"]:
        # the noise-free pressure at the end of each dwell at this duty
        at = truth[(np.abs(truth.u - u) < 1e-9)]
        ends = at.time.to_numpy()[np.flatnonzero(np.diff(at.time.to_numpy(), append=np.inf) > 0.01)]
        for t_end in ends:
            us.append(u)
            ps.append(truth.p_clutch.to_numpy()[np.searchsorted(truth.time, t_end - 0.05)] / 1e5)
    # the line through the measured dwells is the line through the true ones (the valve's
    # curvature and hysteresis are the model's; the estimator must not add to them)
    slope, offset = np.polyfit(us, ps, 1)
    assert est.value["slope_bar_per_duty"] == pytest.approx(slope, rel=0.05)
    assert est.value["offset_bar"] == pytest.approx(offset, abs=0.05)
    assert est.value["slope_bar_per_duty"] > 0 and est.se["slope_bar_per_duty"] > 0


def test_pressure_models_and_frequency_response_are_lti(identified):
    import control

    assert {m.order for m in identified.steps} == {1, 2}
    for m in identified.steps:
        sys_ = m.lti()
        # as many stable poles as the model's order, and its gain at DC
        assert len(control.poles(sys_)) == m.order and np.all(np.real(control.poles(sys_)) < 0.0)
        assert np.isclose(control.dcgain(sys_), m.gain, rtol=1e-6)
    (fr,) = identified.responses
    # the FRD holds the measured response at the measured frequencies, in rad/s
    frd = fr.frd()
    assert np.allclose(frd.omega, 2 * np.pi * fr.freq)
    assert np.isclose(frd.eval(frd.omega[1]), fr.H[1])
    assert fr.freq.min() >= 0.2 and np.all(fr.coherence > 0.5)


# ---------------------------------------------------------------- estimators on signals of known form


def _recording(t: np.ndarray, u: np.ndarray, p: np.ndarray, experiment: str) -> channels.Recording:
    data = {"time": t, "u": u, "p_clutch": p, "oil_temp": np.full(t.size, 60.0)}
    return channels.Recording(Path("synthetic.csv"), data, experiment, "valve-only", "pwm")


def test_step_model_recovers_first_order_plus_dead_time():
    t = np.arange(0.0, 5.0, 1e-3)
    tau, theta, gain = 0.08, 0.12, 20e5
    u = np.where(t >= 1.0, 0.3, 0.1)
    s = np.clip(t - 1.0 - theta, 0.0, None)
    p = 0.1 * gain + 0.2 * gain * (1 - np.exp(-s / tau)) + np.random.default_rng(0).normal(0, 2e3, t.size)
    (m1,) = dynamics.step_models(_recording(t, u, p, "step"), orders=(1,))
    assert abs(m1.params["tau_s"] / tau - 1) < 0.03 and abs(m1.theta - theta) < 0.003
    assert abs(m1.gain / gain - 1) < 0.01 and m1.vaf > 99


def test_a_step_model_puts_no_dead_time_before_the_command():
    # a response with an instant part (a third of it at the command, as a chamber's fill spike) and a lag for the
    # rest: a first-order lag's best fit with a free dead time starts before the command (about -0.1 s here)
    t = np.arange(0.0, 5.0, 1e-3)
    u = np.where(t >= 1.0, 0.3, 0.1)
    s = np.clip(t - 1.0, 0.0, None)
    p = 2e5 + np.where(t >= 1.0, 1e5 + 2e5 * (1 - np.exp(-s / 0.2)), 0.0) + np.random.default_rng(3).normal(0, 2e3, t.size)
    for m in dynamics.step_models(_recording(t, u, p, "step"), orders=(1, 2)):
        assert m.theta == 0.0 and m.se["dead_time_s"] == 0.0, (m.order, m.theta)
        assert m.vaf > 80.0 and abs(m.gain / (3e5 / 0.2) - 1) < 0.1


def test_step_models_of_a_rig_clutch_step_fit_without_numeric_warnings(tmp_path):
    # the refit without a dead time (the chamber's fill spike pulls a free one before the command) tries shapes
    # far out, whose poles are 0 or infinite: the solver steps back from them without a warning on stderr
    import warnings

    rig_report.write(rig.run("step", oil_temp_C=41.0, seed=1), tmp_path / "s41")
    rec = channels.load(tmp_path / "s41" / "measured.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        models = dynamics.step_models(rec)
    assert {m.order for m in models} == {1, 2}
    assert all(m.theta >= 0.0 and np.isfinite(m.gain) and m.vaf > 30.0 for m in models)


def test_step_model_recovers_a_third_order_valve():
    t = np.arange(0.0, 4.0, 1e-3)
    tau_c, wn, zeta, theta = 0.02, 2 * np.pi * 8.0, 0.5, 0.03
    u = np.where(t >= 1.0, 0.3, 0.1)
    sys_ = ([wn**2], np.polymul([tau_c, 1.0], [1.0, 2 * zeta * wn, wn**2]))
    _, y, _ = signal.lsim(sys_, np.where(t >= 1.0 + theta, 0.2, 0.0), t)
    p = 2e5 + 20e5 * y + np.random.default_rng(2).normal(0, 2e3, t.size)
    (m3,) = dynamics.step_models(_recording(t, u, p, "step"), orders=(3,))
    got = m3.params
    assert abs(got["tau_coil_s"] / tau_c - 1) < 0.1 and abs(got["omega_n_rad_s"] / wn - 1) < 0.05
    assert abs(got["zeta"] / zeta - 1) < 0.1 and abs(m3.theta - theta) < 0.003 and m3.vaf > 99


def test_frequency_response_recovers_a_second_order_system():
    rng = np.random.default_rng(1)
    t = np.arange(0.0, 40.0, 1e-3)
    sos = signal.butter(2, [0.1, 20.0], btype="band", fs=1000.0, output="sos")
    u = 0.2 + 0.05 * signal.sosfilt(sos, rng.standard_normal(t.size)) / 0.1
    wn, zeta, gain = 2 * np.pi * 6.0, 0.4, 10e5
    _, y, _ = signal.lsim(([gain * wn**2], [1, 2 * zeta * wn, wn**2]), u - 0.2, t)
    fr = dynamics.frequency_response(_recording(t, u, 2e5 + y + rng.normal(0, 2e3, t.size), "noise"))
    mp = fr.model_params
    assert abs(mp["omega_n_rad_s"] / wn - 1) < 0.05 and abs(mp["zeta"] / zeta - 1) < 0.1
    assert abs(mp["gain_bar_per_unit"] / 10.0 - 1) < 0.05 and mp["dead_time_s"] < 0.005


@pytest.mark.parametrize("experiment", rig.EXPERIMENTS)
def test_experiment_is_detected_from_the_command(experiment):
    s = rig.Settings(experiment=experiment, input_mode="pwm", level=0.3, from_=0.05).checked(params.Params())
    u_sig, duration = rig.input_signal(s)
    t = np.arange(0.0, duration, 1e-3)
    u = rig._sample(u_sig, t)
    assert channels.detect_experiment(t, u) == experiment


# ---------------------------------------------------------------- files: channel maps, dSPACE, bad input

ENGINEERING = {  # channel -> (name in the file, unit, factor from SI, offset)
    "time": ("t_ms", "ms", 1e3, 0.0),
    "u": ("cmd", None, None, None),
    "p_clutch": ("P_clutch", "bar", 1e-5, 0.0),
    "T_r": ("torque_out", "kN m", 1e-3, 0.0),
    "omega_p": ("n_prim", "rpm", 60 / (2 * np.pi), 0.0),
    "omega_1": ("n_cvt_in", "rpm", 60 / (2 * np.pi), 0.0),
    "omega_r": ("n_cvt_out", "rpm", 60 / (2 * np.pi), 0.0),
    "omega_s": ("n_sec", "rpm", 60 / (2 * np.pi), 0.0),
    "oil_temp": ("T_oil", "K", 1.0, 273.15),
}


def test_engineering_units_through_a_channel_map_give_the_same_result(identified, tmp_path):
    files = []
    for rec in identified.recordings:
        si = pd.read_csv(rec.path.parent / "measured.csv")
        eng = {}
        for ch, (name, unit, f, off) in ENGINEERING.items():
            if ch not in si:
                continue
            if ch == "u":  # a duty cycle in per cent, a voltage in mV
                eng[name] = si[ch] * (100.0 if rec.input_mode == "pwm" else 1e3)
            else:
                eng[name] = si[ch] * f + off
        d = tmp_path / rec.path.parent.name  # no meta.json here: the experiment is detected
        d.mkdir()
        pd.DataFrame(eng).to_csv(d / "data.csv", index=False, float_format="%.12g")
        files.append(d / "data.csv")
    lines = [f'{ch} = {{ name = "{n}", unit = "{u}" }}' for ch, (n, u, *_) in ENGINEERING.items() if u]
    (tmp_path / "map_mv.toml").write_text("\n".join([*lines, 'u = { name = "cmd", unit = "mV" }']) + "\n")
    # the table form of an entry
    (tmp_path / "map_pct.toml").write_text("\n".join([*lines, "[u]", 'name = "cmd"', 'unit = "%"']) + "\n")
    mv = channels.read_channel_map(tmp_path / "map_mv.toml")
    pct = channels.read_channel_map(tmp_path / "map_pct.toml")
    recs = [channels.load(f, pct if "stair" in str(f) or "noise" in str(f) else mv) for f in files]
    eng = ident.identify(recs)
    si = ident.identify([channels.load(r.path.parent / "measured.csv") for r in identified.recordings])
    assert [r.experiment for r in recs] == [r.experiment for r in identified.recordings]
    for key in ("mu_slip_poly", "contact_pressure_Pa", "ratio", "resonance_Hz", "valve_gain_poly", "damping_ratio"):
        a, b = np.array(eng.estimates[key].value), np.array(si.estimates[key].value)
        # rounding in the unit conversion may move a window edge by one sample: a tiny fraction of the SE
        assert np.all(np.abs(a - b) <= 1e-6 * np.abs(b) + 0.1 * np.array(si.estimates[key].se)), key
    np.testing.assert_allclose([o.dead_time for o in eng.onsets], [o.dead_time for o in si.onsets], atol=1e-9)


def test_dspace_mat_recording_reads_like_the_csv(rig_data, tmp_path):
    _, root, _ = rig_data
    si = pd.read_csv(root / "step85" / "measured.csv")
    units = {"u": "V", "p_clutch": "bar", "T_r": "Nm", "oil_temp": "degC"}
    scale = {"p_clutch": 1e-5}
    ys = np.array([(f"Model Root/Plant/{c}", si[c].to_numpy() * scale.get(c, 1.0), units.get(c, "rad/s"))
                   for c in si.columns if c != "time"], dtype=[("Name", object), ("Data", object), ("Unit", object)])
    rec = {"X": {"Name": "Time", "Data": si["time"].to_numpy(), "Unit": "s"}, "Y": ys}
    sio.savemat(tmp_path / "run.mat", {"rec001": rec})
    got = channels.load(tmp_path / "run.mat")
    want = channels.load(root / "step85" / "measured.csv")
    assert got.experiment == "step" and got.config == "clutch"
    for ch in channels.CHANNELS:
        np.testing.assert_allclose(got.data[ch], want.data[ch], rtol=1e-9, atol=1e-9, err_msg=ch)


@pytest.fixture(scope="module")
def small_csv(rig_data):
    _, root, _ = rig_data
    return pd.read_csv(root / "step85" / "measured.csv").iloc[800:1600].reset_index(drop=True)


@pytest.mark.parametrize(("corrupt", "fragment"), [
    (lambda f: f.drop(columns="p_clutch"), "required channel 'p_clutch' missing"),
    (lambda f: f.drop(columns="omega_1"), "channel 'omega_1' missing"),
    (lambda f: f.assign(T_r=np.where((f.index > 100) & (f.index < 140), np.nan, f.T_r)), "channel 'T_r' has 39 non-finite"),
    (lambda f: f.assign(time=np.where(f.index == 50, f.time.shift(1), f.time)), "duplicated time stamp"),
    (lambda f: f.iloc[np.r_[0:300, 310:300:-1, 311:800]], "channel 'time' is not increasing"),
])
def test_bad_files_give_one_line_naming_file_and_channel(small_csv, tmp_path, corrupt, fragment):
    path = tmp_path / "bad.csv"
    corrupt(small_csv).to_csv(path, index=False)
    with pytest.raises(WetclutchError) as info:
        channels.load(path)
    msg = str(info.value)
    assert fragment in msg and str(path) in msg and "\n" not in msg


def test_unknown_units_name_file_and_channel(small_csv, tmp_path):
    (tmp_path / "map.toml").write_text('p_clutch = { name = "p_clutch", unit = "atm" }\n')
    with pytest.raises(WetclutchError, match=r"map.toml.*channel 'p_clutch' has unknown unit 'atm'"):
        channels.read_channel_map(tmp_path / "map.toml")
    (tmp_path / "bad.toml").write_text('pressure = "p"\n')
    with pytest.raises(WetclutchError, match="unknown channel 'pressure'"):
        channels.read_channel_map(tmp_path / "bad.toml")
    small_csv.to_csv(tmp_path / "ok.csv", index=False)
    (tmp_path / "meta.json").write_text(json.dumps({"units": {"T_r": "ft lbf"}}))
    with pytest.raises(WetclutchError, match=r"ok.csv.*channel 'T_r' has unknown unit 'ft lbf'"):
        channels.load(tmp_path / "ok.csv")


def test_meta_json_beside_a_file_is_used_only_where_it_makes_sense(small_csv, tmp_path):
    small_csv.to_csv(tmp_path / "run.csv", index=False)
    (tmp_path / "meta.json").write_text(json.dumps({"experiment": "warp", "settings": {"config": "gearbox"}}))
    rec = channels.load(tmp_path / "run.csv")
    assert (rec.experiment, rec.config) == ("step", "clutch")  # detected instead
    (tmp_path / "meta.json").write_text("{not json")
    with pytest.raises(WetclutchError, match="meta.json"):
        channels.load(tmp_path / "run.csv")


def test_jittery_time_stamps_are_resampled_to_a_uniform_grid(small_csv, tmp_path):
    jitter = small_csv.assign(time=small_csv.time + np.random.default_rng(0).uniform(-2e-4, 2e-4, len(small_csv)))
    jitter.to_csv(tmp_path / "jitter.csv", index=False)
    rec = channels.load(tmp_path / "jitter.csv")
    assert np.allclose(np.diff(rec.t), rec.dt) and abs(rec.dt - 1e-3) < 1e-5
    np.testing.assert_allclose(rec.data["omega_p"], np.interp(rec.t, jitter.time, jitter.omega_p))


_CORRUPTIONS = ("nan_run", "shuffle", "duplicate", "drop", "garbage", "truncate")


@pytest.mark.filterwarnings("error::pytest.PytestUnraisableExceptionWarning")
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(ext=st.sampled_from(["csv", "mat", "mf4"]), kind=st.sampled_from(_CORRUPTIONS), where=st.floats(0.0, 1.0),
       length=st.integers(1, 400), column=st.sampled_from(list(channels.CHANNELS)), junk=st.binary(max_size=500),
       seed=st.integers(0, 2**16))
def test_random_corruptions_never_crash(small_csv, tmp_path_factory, ext, kind, where, length, column, junk, seed):
    from wetclutch.rig.files import write_measurement

    frame = small_csv.copy()
    n = len(frame)
    i = int(where * (n - 1))
    if kind == "nan_run":
        frame.loc[i:i + length, column] = np.nan
    elif kind == "shuffle":
        idx = np.arange(n)
        idx[i:i + length] = np.random.default_rng(seed).permutation(idx[i:i + length])
        frame["time"] = frame["time"].to_numpy()[idx]
    elif kind == "duplicate":
        frame = frame.iloc[np.sort(np.concatenate([np.arange(n), np.arange(i, min(n, i + length))]))]
    elif kind == "drop" and column != "time":
        frame = frame.drop(columns=column)
    d = tmp_path_factory.mktemp("corrupt")
    path = d / f"measured.{ext}"
    if ext == "csv":
        frame.to_csv(path, index=False)
    elif kind in ("nan_run", "drop") or ext == "mat":
        # MDF needs an increasing master channel: time corruptions only reach it through the bytes
        try:
            write_measurement(d, frame, {}, {})
        except WetclutchError:
            return
    else:
        write_measurement(d, small_csv, {}, {})
    if kind in ("garbage", "truncate"):
        raw = path.read_bytes()
        cut = int(where * len(raw))
        path.write_bytes(raw[:cut] + (junk if kind == "garbage" else b""))
    try:
        rec = channels.load(path)
        ident.identify([rec])
    except WetclutchError as err:
        assert str(path) in str(err) or "identif" in str(err) or "measurement" in str(err)
        assert "\n" not in str(err)


# ---------------------------------------------------------------- command line


def _cli(*args: str) -> subprocess.CompletedProcess:
    return invoke(args)


def test_cli_identify_writes_outputs_and_a_loadable_param_file(rig_data, tmp_path):
    _, root, _ = rig_data
    files = [str(root / n / "measured.mf4") for n in RUNS]
    out = tmp_path / "id"
    r = _cli("identify", *files, "--out", str(out))
    assert r.returncode == 0, r.stderr
    data = json.loads((out / "identified.json").read_text())
    for key in ("mu_slip_poly", "contact_pressure_Pa", "valve_gain", "clutch_gain_poly_bar_per_V", "resonance_Hz",
                "damping_ratio"):
        assert data[key]["sources"] and all(s["file"] in files for s in data[key]["sources"]), key
        assert data[key]["se"] is not None
    assert set(data["valve_gain"]["value"]) == {"slope_bar_per_duty", "offset_bar"}
    assert len(data["dead_time_s"]) == 2  # one per oil temperature of the step experiments
    for d in data["dead_time_s"]:
        assert {"oil_temp_C", "input", "value"} <= set(d), d
    p = params.load(out / "params.toml")
    assert abs(p.driveline.ratio - TRUE["driveline.ratio"]) < 0.005
    np.testing.assert_allclose(p.friction.mu_slip_poly, data["mu_slip_poly"]["value"])
    report = (out / "report.md").read_text()
    assert "| parameter | prior | identified |" in report and "Validation on held-out files" in report
    for v in data["validation"]:
        assert v["signal"] in ("T_r", "p_clutch") and np.isfinite(v["nrmse"])
    assert any(v["signal"] == "T_r" and v["vaf_percent"] > 80 for v in data["validation"])
    for png in ("friction.png", "onset.png", "steps.png", "bode.png", "static.png", "resonance.png", "validation.png"):
        assert (out / png).stat().st_size > 0
    sim = _cli("simulate", "engage", "--param-file", str(out / "params.toml"), "--out", str(tmp_path / "sim"))
    assert sim.returncode == 0, sim.stderr
    # what was identified and what is the prior, for the design step's account of its settings
    assert data["parameters"]["driveline.ratio"] == "identified"
    assert data["parameters"]["hydraulics.x_contact"] == "identified"
    assert data["parameters"]["valve.m_stem"] == "prior"


def test_the_chain_from_rig_files_to_a_verified_design(rig_data, tmp_path):
    """Rig files -> identify -> design -> verify on that plant, as a user with their own clutch runs it."""
    _, root, _ = rig_data
    out = tmp_path / "id"
    assert _cli("identify", *[str(root / n / "measured.mf4") for n in RUNS], "--out", str(out)).returncode == 0
    des = _cli("design", "--param-file", str(out / "params.toml"), "--out", str(tmp_path / "design"))
    assert des.returncode == 0, des.stderr
    md = (tmp_path / "design" / "design.md").read_text()
    assert "plant (identified): driveline.ratio" in md
    ctrl = tmp_path / "design" / "controller.toml"
    assert "| ratio | 0.6" in md  # the identified ratio of the true rig
    small = tmp_path / "r.toml"
    small.write_text("[request]\ntarget = 't_ref'\nlow = 60.0\nhigh = 120.0\ncorner = true\n")
    ver = _cli("verify", "--param-file", str(out / "params.toml"), "--controller-file", str(ctrl), "--ranges", str(small),
               "--samples", "0", "--workers", "1", "--quiet", "--out", str(tmp_path / "verify"))
    assert ver.returncode == 0, ver.stderr
    res = json.loads((tmp_path / "verify" / "verify.json").read_text())
    assert res["cases"] == 2 and all(r["metrics"] for r in res["results"])
    assert "--controller-file" in res["results"][0]["replay"]


#: a clutch unlike the defaults: friction curve, kiss point and fill volume (the contact travel), ratio, inertias
ODD = {"friction.mu_slip_poly": [-1.2e-6, 2.2e-4, 3.0e-2], "hydraulics.x_contact": 1.8e-3, "driveline.ratio": 1.25,
       "driveline.J_p": 1.8, "driveline.J_s": 4.0}


def test_the_chain_on_a_clutch_unlike_the_defaults(tmp_path):
    """``wetclutch rig`` runs of an odd clutch -> identify -> design -> verify on the identified plant."""
    sets = [a for k, v in ODD.items() for a in ("--set", f"{k}={v}")]
    files = []
    for name, level, temp, seed in (("cold", "1.8", "41", "1"), ("warm", "2.5", "85", "2")):
        r = _cli("rig", "step", "--level", level, "--oil-temp", temp, "--seed", seed, *sets,
                 "--out", str(tmp_path / name))
        assert r.returncode == 0, r.stderr
        files.append(str(tmp_path / name / "measured.mf4"))
    out = tmp_path / "id"
    r = _cli("identify", *files, "--out", str(out))
    assert r.returncode == 0, r.stderr
    got, true = params.load(out / "params.toml"), params.load(overrides=ODD)
    assert got.driveline.ratio == pytest.approx(1.25, rel=0.005)  # the heavier primary turns the CVT fast enough
    assert got.driveline.J_p == pytest.approx(1.8, rel=0.02) and got.driveline.J_s == pytest.approx(4.0, rel=0.02)
    assert actuator.contact_pressure(got) == pytest.approx(actuator.contact_pressure(true), abs=0.05e5)
    w = np.linspace(20.0, 120.0, 30)
    mu_true = np.polyval(ODD["friction.mu_slip_poly"], w)
    assert np.max(np.abs(np.polyval(got.friction.mu_slip_poly, w) / mu_true - 1)) < 0.03
    report = (out / "report.md").read_text()
    assert "| driveline.J_p | identified |" in report and "| driveline.J_1 | prior | not excited by the data" in report
    des = _cli("design", "--param-file", str(out / "params.toml"), "--out", str(tmp_path / "design"))
    assert des.returncode == 0, des.stderr
    row = next(ln for ln in (tmp_path / "design" / "design.md").read_text().splitlines() if ln.startswith("| ratio |"))
    assert float(row.split("|")[2]) == pytest.approx(1.25, rel=0.005) and "plant (identified)" in row
    small = tmp_path / "r.toml"
    small.write_text("[request]\ntarget = 't_ref'\nlow = 60.0\nhigh = 120.0\ncorner = true\n")
    ver = _cli("verify", "--param-file", str(out / "params.toml"), "--controller-file",
               str(tmp_path / "design" / "controller.toml"), "--ranges", str(small), "--samples", "0", "--workers", "1",
               "--quiet", "--out", str(tmp_path / "verify"))
    assert ver.returncode == 0, ver.stderr
    res = json.loads((tmp_path / "verify" / "verify.json").read_text())
    assert res["cases"] == 2 and all(r["metrics"] for r in res["results"])


def test_cli_identify_bad_input_is_one_line_and_writes_nothing(rig_data, tmp_path, cli_refuses):
    _, root, _ = rig_data
    shutil.copy(root / "stair" / "measured.csv", tmp_path / "valve.csv")
    (tmp_path / "map.toml").write_text('p_clutch = { name = "p_clutch", unit = "furlong" }\n')
    out = tmp_path / "never"
    for args in (["identify", str(tmp_path / "valve.csv"), "--channels", str(tmp_path / "map.toml")],
                 ["identify", str(tmp_path / "missing.csv")],
                 ["identify", str(tmp_path / "valve.csv"), "--mu-order", "9"]):
        cli_refuses(args, "error", out)


# ---------------------------------------------------------------- channel maps, duplicate runs, the oil temperature


@pytest.mark.parametrize(("text", "fragment"), [
    ('p_clutch = { unit = "bar" }\n', "'p_clutch' has no key 'name'"),
    ('[oil_temp]\nunit = "K"\n', "'oil_temp' has no key 'name'"),
    ('p_clutch = { name = "P", unit = "bar", scale = 2 }\n', "'p_clutch' has unknown key 'scale' (known: name, unit)"),
    ('p_clutch = { name = 5 }\n', "'p_clutch'.name must be a string (got 5)"),
    ('p_clutch = { name = "P", unit = 1 }\n', "'p_clutch'.unit must be a string (got 1)"),
    ('p_clutch = { name = " " }\n', "'p_clutch'.name must not be empty"),
    ("p_clutch = 5\n", "'p_clutch' must be a string (the channel's name) or a table"),
    ('p_clutch = "u"\n', "'p_clutch' and 'u' both read column 'u' ('u', not in the map, reads the column of its own"),
    ('T_r = "torque"\nomega_p = "torque"\n', "'T_r' and 'omega_p' both read column 'torque'"),
])
def test_a_bad_channel_map_entry_is_one_line_naming_the_entry_and_key(tmp_path, text, fragment):
    (tmp_path / "map.toml").write_text(text)
    with pytest.raises(WetclutchError) as e:
        channels.read_channel_map(tmp_path / "map.toml")
    assert str(e.value).startswith(f"channel map '{tmp_path / 'map.toml'}': {fragment}") and "\n" not in str(e.value)


def test_channel_map_entries_that_swap_column_names_are_read(tmp_path):
    # a column named like another channel is fine when that channel reads another column
    (tmp_path / "map.toml").write_text('p_clutch = "u"\nu = { name = "cmd", unit = "%" }\nT_r = "omega_p"\n'
                                       'omega_p = "n_prim"\n')
    got = channels.read_channel_map(tmp_path / "map.toml")
    assert got == {"p_clutch": {"name": "u"}, "u": {"name": "cmd", "unit": "%"}, "T_r": {"name": "omega_p"},
                   "omega_p": {"name": "n_prim"}}


_map_value = st.one_of(st.text(max_size=4), st.integers(-2, 2), st.booleans(),
                       st.dictionaries(st.sampled_from(["name", "unit", "scale"]),
                                       st.one_of(st.sampled_from(["u", "p_clutch", "bar", "rpm", "%", "x", ""]),
                                                 st.integers(0, 2)), max_size=3))


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(entries=st.dictionaries(st.sampled_from([*channels.CHANNELS, "pressure"]), _map_value, max_size=4))
def test_any_channel_map_reads_as_one_column_per_named_channel_or_gives_one_line(tmp_path, entries):
    import tomli_w

    (tmp_path / "map.toml").write_text(tomli_w.dumps(entries))
    try:
        got = channels.read_channel_map(tmp_path / "map.toml")
    except WetclutchError as e:
        assert str(e).startswith(f"channel map '{tmp_path / 'map.toml'}'") and "\n" not in str(e)
        return
    assert set(got) == set(entries) and all(e["name"].strip() and set(e) <= {"name", "unit"} for e in got.values())
    names = [got.get(ch, {}).get("name", ch) for ch in channels.CHANNELS]
    assert len(set(names)) == len(names)


def test_the_same_file_twice_is_refused(rig_data):
    _, root, _ = rig_data
    rec = channels.load(root / "step85" / "measured.mat")
    with pytest.raises(WetclutchError, match=r"^measurement file '.*step85/measured.mat' is given twice$"):
        ident.identify([rec, channels.load(root / "step41" / "measured.csv"), channels.load(rec.path)])
    # the same file by another way to it
    other = channels.load(root / "step41" / ".." / "step85" / "measured.mat")
    with pytest.raises(WetclutchError, match=r"step41/\.\./step85/measured.mat' is given twice \(as '.*step85/"):
        ident.identify([rec, other])


def test_two_files_of_one_recording_are_refused_naming_both(rig_data, tmp_path):
    _, root, _ = rig_data
    mat = channels.load(root / "step85" / "measured.mat")
    # the run exported in engineering units and printed to 7 digits: still the same recording
    si = pd.read_csv(root / "step85" / "measured.csv")
    eng = si.assign(time=si.time * 1e3, p_clutch=si.p_clutch * 1e-5)
    eng.to_csv(tmp_path / "export.csv", index=False, float_format="%.7g")
    (tmp_path / "map.toml").write_text('time = { name = "time", unit = "ms" }\np_clutch = { name = "p_clutch", '
                                       'unit = "bar" }\n')
    export = channels.load(tmp_path / "export.csv", channels.read_channel_map(tmp_path / "map.toml"))
    for a, b in ((mat, channels.load(root / "step85" / "measured.csv")), (mat, export),
                 (channels.load(root / "step85" / "measured.mf4"), mat)):
        assert channels.same_recording(a, b) and channels.same_recording(b, a)
        with pytest.raises(WetclutchError) as e:
            ident.identify([channels.load(root / "step41" / "measured.csv"), a, b])
        assert str(e.value) == (f"measurement files '{a.path}' and '{b.path}' hold the same recording (time and every "
                                "channel alike): give each run once")


def test_runs_that_differ_are_not_taken_for_one_recording(rig_data):
    _, root, _ = rig_data
    rec = channels.load(root / "step85" / "measured.csv")
    assert not channels.same_recording(rec, channels.load(root / "step41" / "measured.csv"))
    # one sample of one channel off by a thousandth of its span (a few quantisation steps of the pressure sensor)
    p = rec.data["p_clutch"].copy()
    p[3000] += 1e-3 * np.ptp(p)
    moved = channels.Recording(rec.path, rec.data | {"p_clutch": p}, rec.experiment, rec.config, rec.input_mode)
    assert not channels.same_recording(rec, moved)
    # the same samples a sample later
    late = channels.Recording(rec.path, {c: x[1:] for c, x in rec.data.items()}, rec.experiment, rec.config,
                              rec.input_mode)
    assert not channels.same_recording(rec, late)
    cut = {c: x[:-1] for c, x in rec.data.items()}
    assert not channels.same_recording(late, channels.Recording(rec.path, cut, rec.experiment, rec.config,
                                                                rec.input_mode))


def test_the_oil_temperature_is_the_median_over_the_clutch_runs_and_says_so(identified):
    est = identified.estimates["oil_temp_C"]
    clutch = [r for r in identified.recordings if r.config == "clutch"]
    assert len(clutch) == 2 and len(identified.recordings) == 4  # two valve-only runs beside them
    assert est.value == pytest.approx(np.median([r.oil_temp_C for r in clutch]))
    assert est.unit == "C (median over the clutch runs)"
    assert [s["file"] for s in est.sources] == [str(r.path) for r in clutch]
    assert identified.identified.rig.oil_temp_C == pytest.approx(est.value)


def test_without_clutch_runs_the_oil_temperature_is_the_median_over_the_runs(rig_data):
    _, root, _ = rig_data
    recs = [channels.load(root / n / "measured.csv") for n in ("stair", "noise")]
    est = ident.identify(recs).estimates["oil_temp_C"]
    assert est.unit == "C (median over the runs)" and len(est.sources) == 2
    assert est.value == pytest.approx(np.median([r.oil_temp_C for r in recs]))


def test_cli_identify_refuses_one_run_given_twice(rig_data, tmp_path, cli_refuses):
    _, root, _ = rig_data
    mat, csv = root / "step85" / "measured.mat", root / "step85" / "measured.csv"
    cli_refuses(["identify", str(mat), str(mat)], f"measurement file '{mat}' is given twice", tmp_path / "I")
    cli_refuses(["identify", str(mat), str(csv)], f"measurement files '{mat}' and '{csv}' hold the same recording",
                tmp_path / "I")


def test_an_identification_shows_what_it_found_in_one_line(identified):
    text = repr(identified)
    assert text.startswith(f"Identification({len(identified.recordings)} recordings, ") and "\n" not in text
    found = [k for k, (how, _) in identified.sources().items() if how == "identified"]
    assert found and all(k in text for k in found) and len(text) < 1000


def test_a_design_on_an_identification_names_identified_sources(identified):
    from wetclutch.launch import design as designs

    d = designs.design(identified.identified, "launch", identified.origin())
    assert identified.origin()["driveline.ratio"] == "identified"
    assert "identified" in d.sources["ratio"]


def test_clutch_runs_whose_plates_never_touch_are_named_as_the_reason(tmp_path):
    # a 1 V step on a clutch whose kiss point is 0.9 bar: the axle sees drag and noise only
    weak = params.load(overrides={"hydraulics.p_prestress": 90000.0})
    rig_report.write(rig.run("step", weak, oil_temp_C=41.0, seed=1, t_end=4.0), tmp_path / "weak")
    res = ident.identify([channels.load(tmp_path / "weak" / "measured.csv")])
    why = dict(res.sources())
    for path in ("friction.mu_slip_poly", "hydraulics.x_contact", "driveline.k_a"):
        assert why[path][0] == "prior" and "the input may never have pressed the plates" in why[path][1], path
    assert "pressed the plates" not in why["valve.I_hyst"][1]
