"""A CVT whose ratio moves: the engine against conservation laws and an independent ODE, and the post-sync hold."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from wetclutch.cli import main
from wetclutch.launch import Conditions, simulate
from wetclutch.launch.loop import HOLD_T_MAX
from wetclutch.params import Params
from wetclutch.plant import driveline
from wetclutch.sim.network import Network, integrate
from wetclutch.sim.signals import Const, Ramp, Step


@pytest.mark.parametrize("command", [0.4, 3.0])
def test_ratio_ramp_keeps_kinetic_energy_and_stops_at_its_limit(command):
    # two inertias coupled by an ideal gear (eta = 1), no other element: the gear does no work, so
    # (J_in + J_out r^2) w_in^2 / 2 stays E0 while r ramps at 0.4 /s (a command of 3 /s is cut to the
    # rate limit 0.4 /s), until it reaches its greatest value 1.5 at t = 2.5 s exactly
    Ji, Jo, w0, r0, rate = 0.8, 2.0, 100.0, 0.5, 0.4
    net = Network()
    a = net.body("in", Ji, w0=w0)
    b = net.body("out", Jo, w0=r0 * w0)
    net.gear("cvt", a, b, r0, rate=command, ratio_range=(0.4, 1.5), rate_max=rate)
    tr = integrate(net, 4.0, dt_out=0.01)
    r = np.minimum(r0 + rate * tr.t, 1.5)
    w_in = np.sqrt(2.0 * 0.5 * (Ji + Jo * r0**2) * w0**2 / (Ji + Jo * r**2))
    np.testing.assert_allclose(tr.ratio("cvt"), r, rtol=0, atol=1e-12)
    np.testing.assert_allclose(tr.speed("in"), w_in, rtol=1e-7)
    np.testing.assert_allclose(tr.speed("out"), r * w_in, rtol=1e-7)
    assert tr.energy_residual() < 1e-6
    assert tr.stats["events"] == 1  # the ratio limit, located
    assert tr.ratio("cvt")[-1] == 1.5


def test_ratio_limit_is_met_at_the_exact_instant():
    # down at -0.5 /s from t = 1 s, the ratio reaches its least value 0.6 at 1.8 s, an event, and is held there
    # while the command still pushes down
    net = Network()
    a = net.body("in", 1.0, w0=50.0)
    b = net.body("out", 3.0, w0=50.0)
    net.gear("cvt", a, b, 1.0, rate=Step(1.0, 0.0, -0.5), ratio_range=(0.6, 2.0), rate_max=1.0)
    tr = integrate(net, 3.0, dt_out=1e-3)
    i = np.searchsorted(tr.t, [1.0, 1.8])
    ratio = tr.ratio("cvt")
    assert np.all(ratio[: i[0] + 1] == 1.0)
    np.testing.assert_allclose(ratio[i[0]:i[1]], 1.0 - 0.5 * (tr.t[i[0]:i[1]] - 1.0), atol=1e-12)
    np.testing.assert_allclose(ratio[i[1]:], 0.6, rtol=0, atol=1e-12)
    # held there: the speeds stay, at the energy-conserving value (J_in + J_out r^2) w_in^2 = (1 + 3) 50^2
    w = tr.speed("in")[i[1] + 1:]
    assert np.ptp(w) < 1e-12 * w[-1]
    assert w[-1] == pytest.approx(np.sqrt(4.0 * 50.0**2 / (1.0 + 3.0 * 0.6**2)), rel=1e-7)


def _lock_by_ode(Jp, J1, Js, T, w0, r0, rate):
    """Lock time of a clutch (constant torque T) from a primary into a CVT whose ratio ramps, from the one-degree-of-
    freedom equation of the output side, written here from Newton's law: with w_s = r w_1 and J_s w_s' = lam,
    J_1 w_1' = T - r lam, hence (J_1 + r^2 J_s) w_1' = T - r r' J_s w_1."""
    def f(t, y):
        r = r0 + rate * t
        return [-T / Jp, (T - r * rate * Js * y[1]) / (J1 + r * r * Js)]

    def slip(t, y):
        return y[0] - y[1]

    slip.terminal = True
    sol = solve_ivp(f, (0.0, 10.0), [w0, 0.0], method="DOP853", rtol=1e-12, atol=1e-12, events=slip)
    return float(sol.t_events[0][0])


def test_clutch_locks_at_the_instant_an_independent_ode_gives_while_the_ratio_moves():
    Jp, J1, Js, T, w0, r0, rate = 1.2, 0.01, 6.5, 40.0, 150.0, 0.5, 0.2
    net = Network()
    p = net.body("p", Jp, w0=w0)
    one = net.body("1", J1)
    s = net.body("s", Js)
    net.clutch("c", p, one, T)
    net.gear("cvt", one, s, r0, rate=rate, ratio_range=(0.4, 2.5), rate_max=1.0)
    tr = integrate(net, 4.0)
    assert tr.first_lock("c") == pytest.approx(_lock_by_ode(Jp, J1, Js, T, w0, r0, rate), rel=1e-8)
    assert tr.energy_residual() < 1e-6


def test_energy_balance_closes_with_a_moving_ratio_on_the_driveline():
    # the study's driveline (lossy CVT, drag, damped axle, heated clutch, road load) with the ratio moving up and
    # down through the engagement and after lock-up
    net = driveline.build(Params(), Ramp(0.5, 0.3, 0.0, 60.0), ratio_rate=Ramp(1.0, 2.0, 0.8, -0.8))
    tr = integrate(net, 4.0)
    ratio = tr.ratio("cvt")
    assert ratio.max() > 1.5 and np.ptp(ratio[-500:]) > 0.3  # it moved, up and down
    assert tr.first_lock("clutch") is not None
    assert tr.energies()["dissipated_gear"][-1] > 0.0
    assert tr.energy_residual() < 1e-6


def test_a_moving_ratio_needs_limits_that_hold_it():
    net = Network()
    a = net.body("a", 1.0)
    b = net.body("b", 1.0)
    with pytest.raises(ValueError, match="ratio_range"):
        net.gear("g", a, b, 0.5, rate=Const(0.1))
    with pytest.raises(ValueError, match="ratio_range"):
        net.gear("g", a, b, 0.5, rate=Const(0.1), ratio_range=(-1.0, 1.0))


# ------------------------------------------------------------------ the post-sync hold on the default rig

#: locks at 7.3 s and holds 1.1 s (seeds 0 and 1); 40 N m holds 0.98 s, 20 N m locks at 13.1 s. At 25-30 N m
#: the hold keeps the torque 1.3-1.6 s where the lock-up's jolt stays within the band, and not at all where it does
#: not (one launch of eight)
HOLD_NM = 35.0


@pytest.fixture(scope="module")
def held():
    return simulate(Params(), "launch", Conditions(t_ref=HOLD_NM, post_sync_hold=True))


@pytest.mark.slow
def test_post_sync_hold_keeps_the_axle_torque_for_a_second(held):
    s = held.summary
    p = Params().driveline
    assert s["t_sync_s"] is not None
    assert s["held_in_band_s"] >= 1.0, s
    ratio = held.signals["ratio"]
    assert p.ratio_min <= ratio.min() and ratio.max() <= p.ratio_max
    assert ratio.iloc[-1] > p.ratio + 0.2  # the ratio did the holding
    assert s["hold_T_r_err_rms_pct"] < 10.0


def test_a_small_request_that_locks_late_is_held_after_its_lock_up():
    # 20 N m locks some 13 s into the run, after the launch's own horizon: the post-sync hold's run goes on
    res = simulate(Params(), "launch", Conditions(t_ref=20.0, post_sync_hold=True))
    s = res.summary
    assert 12.0 < s["t_sync_s"] < HOLD_T_MAX
    assert s["hold_end"] != "running" and s["held_in_band_s"] >= 1.0, s
    assert res.signals["time"].iloc[-1] < s["t_sync_s"] + Conditions().t_after + Conditions().hold_time + 0.01


@pytest.mark.slow
def test_a_large_request_cannot_be_held_a_second_the_flywheel_lacks_the_energy():
    # at 100 N m the clutch locks early, but the hold draws T_ref w_s / eta from the primary flywheel: more than the
    # kinetic energy it has left at lock-up would give for one second
    res = simulate(Params(), "launch", Conditions(t_ref=100.0, post_sync_hold=True))
    s = res.summary
    d = Params().driveline
    tru = res.truth
    i = int(np.searchsorted(tru["time"], s["t_sync_s"]))
    e_primary = 0.5 * (d.J_p + d.J_1) * (tru["omega_s"].iloc[i] / d.ratio) ** 2
    need = 100.0 * tru["omega_s"].iloc[i] * 1.0 / d.eta
    assert e_primary < need
    assert s["held_in_band_s"] < 1.0
    assert s["hold_end"] == "rate limit"  # the CVT could not shift fast enough for the slowing flywheel


def test_launch_post_sync_hold_cli(tmp_path):
    out = tmp_path / "hold"
    assert main(["launch", "--out", str(out), "--t-ref", "100", "--post-sync-hold", "--hold-time", "0.5"]) == 0
    s = json.loads((out / "summary.json").read_text())
    for key in ("hold_s", "hold_end", "held_in_band_s", "hold_T_r_err_max_pct", "ratio_end"):
        assert key in s
    assert s["hold_s"] <= 0.5 + 1e-9
    head = (out / "signals.csv").read_text().splitlines()[0].split(",")
    assert "ratio" in head


@pytest.mark.parametrize("args, field", [(["--hold-time", "0"], "--hold-time"),
                                         (["--set", "driveline.ratio_max=0.45"], "driveline.ratio")])
def test_bad_hold_settings_are_one_line_errors(tmp_path, capsys, args, field):
    out = tmp_path / "bad"
    assert main(["launch", "--out", str(out), "--post-sync-hold", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert field in err and len(err.splitlines()) == 1
    assert not out.exists()
