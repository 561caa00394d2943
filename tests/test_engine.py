"""The hybrid engine against closed-form solutions and exact event instants."""

from __future__ import annotations

import numpy as np
import pytest

import wetclutch as wc
from wetclutch.plant import scenarios
from wetclutch.sim import integrator
from wetclutch.sim import workspace as engine
from wetclutch.sim.network import GROUND, Network, integrate
from wetclutch.sim.signals import Const, Ramp, Sine, Step
from wetclutch.sim.workspace import new_workspace


def test_two_inertias_constant_capacity_sync_time():
    # relative deceleration T (1/Ja + 1/Jb) takes the slip from dw to zero
    Ja, Jb, T, wa = 0.7, 2.3, 13.0, 120.0
    net = Network()
    a = net.body("a", Ja, w0=wa)
    b = net.body("b", Jb, w0=-5.0)
    net.clutch("c", a, b, T)
    tr = integrate(net, 10.0)
    expected = (wa + 5.0) / (T * (1 / Ja + 1 / Jb))
    assert tr.first_lock("c") == pytest.approx(expected, rel=1e-9)
    # after lock both turn at the momentum-conserving common speed
    w_common = (Ja * wa - Jb * 5.0) / (Ja + Jb)
    assert tr.speed("a")[-1] == pytest.approx(w_common, rel=1e-9)
    assert tr.speed("b")[-1] == pytest.approx(w_common, rel=1e-9)



def test_absolute_tolerance_per_state_is_checked_and_one_value_means_every_state():
    net = Network()
    a = net.body("a", 0.7, w0=120.0)
    b = net.body("b", 2.3, w0=-5.0)
    net.clutch("c", a, b, 13.0)
    one = integrate(net, 2.0, atol=1e-10)
    each = integrate(net, 2.0, atol=np.full(net.n_state, 1e-10))
    assert np.array_equal(one.x, each.x)
    for bad in (np.full(net.n_state + 1, 1e-10), np.zeros(net.n_state), -1e-10):
        with pytest.raises(ValueError, match="atol"):
            integrate(net, 2.0, atol=bad)


@pytest.mark.parametrize("eta", [1.0, 0.9])
def test_clutch_into_lossy_gear_sync_time(eta):
    # forward power flow: the output inertia is seen through the gear as J_s r^2 / eta
    Jp, J1, Js, r, T, w0 = 1.2, 0.01, 6.5, 0.5, 40.0, 150.0
    net = Network()
    p = net.body("p", Jp, w0=w0)
    one = net.body("1", J1)
    s = net.body("s", Js)
    net.clutch("c", p, one, T)
    net.gear("g", one, s, r, eta)
    tr = integrate(net, 10.0)
    expected = w0 / (T / Jp + T / (J1 + r * r * Js / eta))
    assert tr.first_lock("c") == pytest.approx(expected, rel=1e-9)
    assert np.all(np.diff(tr.energies()["dissipated_gear"]) >= -1e-9)


def test_breakaway_at_the_right_instant():
    # locked pair driven by a constant torque; capacity falls linearly until it
    # can no longer carry the constraint torque T_src * Jb / (Ja + Jb)
    Ja, Jb, T_src, C0, rate = 1.0, 3.0, 8.0, 20.0, 4.0
    net = Network()
    a = net.body("a", Ja)
    b = net.body("b", Jb)
    net.source("drive", a, T_src)
    net.clutch("c", a, b, Ramp(0.0, C0 / rate, C0, 0.0))
    tr = integrate(net, 4.0)
    lam = T_src * Jb / (Ja + Jb)
    t_break = (C0 - lam) / rate
    ev = tr.events[tr.events[:, 2] != engine.LOCKED]
    assert ev[0, 0] == pytest.approx(t_break, abs=1e-9)
    assert ev[0, 2] == 1  # slides forward: a is driven
    # before breakaway the pair turns together; after, a outruns b
    i_before = np.searchsorted(tr.t, t_break) - 1
    assert abs(tr.speed("a")[i_before] - tr.speed("b")[i_before]) < 1e-9
    assert tr.speed("a")[-1] > tr.speed("b")[-1]


def test_brake_holds_until_torque_exceeds_capacity():
    net = Network()
    a = net.body("a", 2.0)
    net.source("drive", a, Ramp(0.0, 1.0, 0.0, 10.0))
    net.brake("brake", a, 4.0)
    tr = integrate(net, 2.0)
    assert tr.events[0, 0] == pytest.approx(0.4, abs=1e-9)
    w = tr.speed("a")
    assert np.all(w[tr.t < 0.4] == 0.0)
    # after breakaway: J w' = 10 t - 4 on [0.4, 1], then 6 N m
    assert w[-1] == pytest.approx((5 * (1 - 0.16) - 4 * 0.6 + 6.0 * 1.0) / 2.0, rel=1e-8)


def test_slow_approach_to_lock_does_not_chatter():
    # a damper pulls the speeds together exponentially, a weak clutch helps:
    # slip reaches zero once and stays there
    net = Network()
    a = net.body("a", 1.0, w0=1.0)
    b = net.body("b", 1.0)
    net.spring("visc", a, b, k=0.0, d=5.0)
    net.clutch("c", a, b, 1e-3)
    tr = integrate(net, 10.0)
    assert tr.stats["mode_switches"] == 1
    assert tr.first_lock("c") is not None


def test_lock_against_oscillating_load_switches_boundedly():
    # a sinusoidal torque near the static capacity: every period at most one
    # unlock and one relock, never a burst of switches
    net = Network()
    a = net.body("a", 1.0)
    b = net.body("b", 1.0)
    net.source("drive", a, Sine(10.0, 1.0))
    net.clutch("c", a, b, 4.9)
    tr = integrate(net, 5.0)
    assert 0 < tr.stats["mode_switches"] <= 4 * 5 + 2
    assert tr.energy_residual() < 1e-6


def test_several_locked_clutches_are_solved_together():
    # a chain held by a brake at the end: all locked, torques passed through
    net = Network()
    b1 = net.body("b1", 1.0)
    b2 = net.body("b2", 2.0)
    b3 = net.body("b3", 3.0)
    net.source("drive", b1, 5.0)
    net.clutch("c12", b1, b2, 100.0)
    net.clutch("c23", b2, b3, 100.0)
    net.brake("brake", b3, 100.0)
    tr = integrate(net, 0.5)
    assert np.all(tr.locked("c12") == 1) and np.all(tr.locked("brake") == 1)
    assert tr.clutch_torque("c12")[-1] == pytest.approx(5.0)
    assert tr.clutch_torque("c23")[-1] == pytest.approx(5.0)
    assert tr.clutch_torque("brake")[-1] == pytest.approx(5.0)


def test_massless_body_without_rigid_tie_is_an_error():
    from wetclutch.errors import SimulationError

    net = Network()
    a = net.body("a", 1.0, w0=1.0)
    b = net.body("b", 0.0)
    net.clutch("c", a, b, Step(0.5, 0.0, 1.0))
    net.spring("s", b, GROUND, 1.0, 1.0)
    # the error names the body and the cause
    with pytest.raises(SimulationError, match="body 'b' has no inertia and no lock"):
        integrate(net, 1.0)


def test_rerun_does_not_recompile():
    net = Network()
    a = net.body("a", 1.0, w0=3.0)
    b = net.body("b", 1.0)
    net.clutch("c", a, b, Const(1.0))
    integrate(net, 1.0)
    n_sig = len(integrator.advance.signatures)
    integrate(net, 2.0)
    assert len(integrator.advance.signatures) == n_sig


@pytest.mark.parametrize(("T_in", "moves"), [(10.0, False), (12.0, True)])
def test_lossy_gear_at_standstill_sticks_within_its_friction(T_in, moves):
    # ratio 1, eta 0.8, output loaded with -9 N m: the gear's losses can hold an input
    # torque between 0.8 * 9 = 7.2 and 9 / 0.8 = 11.25 N m without moving
    net = Network()
    i = net.body("in", 1.0)
    o = net.body("out", 2.0)
    net.gear("g", i, o, 1.0, 0.8)
    net.source("drive", i, T_in)
    net.source("load", o, -9.0)
    tr = integrate(net, 1.0)
    w = tr.speed("out")
    if moves:
        # forward power flow (torque on the input -lam / eta): (eta J_in + J_out) a = eta T_in - 9
        assert w[-1] == pytest.approx((0.8 * T_in - 9.0) / (0.8 * 1.0 + 2.0), rel=1e-9)
    else:
        assert np.all(w == 0.0) and np.all(tr.speed("in") == 0.0)
    assert tr.energy_residual() < 1e-6


def _chunked_run(network, refactor_always: bool) -> np.ndarray:
    """States after advancing 1 ms at a time with a restart before each call, as a closed loop does;
    ``refactor_always``: the constraint factors and the cache of solutions forgotten before each call."""
    net, x0, ext = network.compile()
    ws = new_workspace(net, x0)
    n = 2001
    out = (np.zeros(n), np.zeros((n, x0.size)), np.zeros((n, ws.aux.size)), np.zeros((n, ws.clm.size), dtype=np.int64))
    cache = engine.FACTOR_CACHE * (ws.A.shape[1] + 1)
    for k in range(n - 1):
        ws.istate[0] = 1
        if refactor_always:
            ws.fact[:] = engine.NO_MODE
            ws.A[-cache:] = 0.0
        assert integrator.advance(net, ext, ws, (k + 1) * 1e-3, 1e-3, 0.0, 1e-8, np.full(x0.size, 1e-10), np.inf,
                                          *out) == engine.OK
    return out[1][: ws.istate[1]]


def _stick_slip() -> Network:
    # a sinusoidal torque beyond a clutch's capacity: it slips and sticks again twice a period, and its two modes'
    # constraint solutions come from the cache after the first of each
    net = Network()
    a = net.body("a", 1.0)
    b = net.body("b", 1.0)
    net.source("drive", a, Sine(10.0, 2.0))
    net.clutch("c", a, b, 4.9)
    return net


@pytest.mark.parametrize("case", ["engage", "stick-slip"])
def test_restarts_that_keep_the_modes_reuse_the_constraint_factors(case):
    # the engage driveline through slip, lock-up and the road load's release, and a clutch that sticks and slips by
    # turns; their constraint matrices change with the modes, and reusing the factors of the current modes or the
    # solutions cached for earlier ones must change no result at all
    net = scenarios._engage(wc.Params()) if case == "engage" else _stick_slip()
    x_cached = _chunked_run(net, refactor_always=False)
    x_fresh = _chunked_run(net, refactor_always=True)
    assert x_cached.shape[0] == 2001
    np.testing.assert_array_equal(x_cached, x_fresh)
    # and the modes did change on the way (so the factors had to be remade in between), the clutch's back and forth
    tr = integrate(net, 2.0)
    assert np.unique(tr.modes[:, 0]).size >= 2
    if case == "stick-slip":
        assert tr.stats["mode_switches"] >= 6


@pytest.mark.parametrize("eps", [1e-5, 1e-7])
def test_a_slip_that_only_touches_zero_within_a_step_stops_the_body(eps):
    # a body (J = 1) sliding forward against a brake of 1 N m, driven by 1 - sin(10 t) N m: sliding, its speed
    # is w0 - (1 - cos 10t) / 10, which from w0 = 0.2 - eps falls to zero at cos(10 t*) = 1 - 10 w0, just
    # before its least value (-eps at t = pi/10), and would rise again. Touching zero it stops: the drive
    # (1 - sin(10 t*), below the brake's 1 N m) cannot move it, until sin(10 t) turns negative at pi/10, where
    # the drive exceeds the brake and it slides on. The dip below zero lasts 0.3 to 3 ms, less than a step.
    net = Network()
    a = net.body("a", 1.0, w0=0.2 - eps)
    net.source("drive", a, Sine(-1.0, 10.0 / (2.0 * np.pi), offset=1.0))
    net.brake("brake", a, 1.0)
    tr = integrate(net, 0.5)
    t_stop = np.arccos(1.0 - 10.0 * (0.2 - eps)) / 10.0
    assert tr.stats["mode_switches"] == 2
    assert tr.events[0, 2] == engine.LOCKED and tr.events[0, 0] == pytest.approx(t_stop, abs=1e-7)
    assert tr.events[1, 2] == 1 and tr.events[1, 0] == pytest.approx(np.pi / 10.0, abs=1e-9)
    assert tr.energy_residual() < 1e-6


def test_a_network_without_clutches_or_gears_moves():
    # nothing to switch: the constraint factors (the inverse inertias alone) must still be made once
    net = Network()
    a = net.body("a", 2.0)
    net.source("drive", a, 3.0)
    tr = integrate(net, 1.0)
    np.testing.assert_allclose(tr.speed("a"), 1.5 * tr.t, atol=1e-12)  # J w' = T
    # two masses on a spring, one kicked: the twist rings at w_n = sqrt(k (J1 + J2) / (J1 J2))
    J1, J2, k, w0 = 1.0, 3.0, 40.0, 2.0
    net = Network()
    b1, b2 = net.body("b1", J1, w0=w0), net.body("b2", J2)
    net.spring("s", b1, b2, k)
    tr = integrate(net, 2.0, dt_out=1e-3, rtol=1e-10, atol=1e-12)
    wn = np.sqrt(k * (J1 + J2) / (J1 * J2))
    # phi' = w1 - w2, the relative speed w0 cos(wn t): phi = (w0 / wn) sin(wn t)
    np.testing.assert_allclose(tr.spring_deflection("s"), w0 / wn * np.sin(wn * tr.t), atol=1e-8)
    np.testing.assert_allclose(J1 * tr.speed("b1") + J2 * tr.speed("b2"), J1 * w0, atol=1e-9)  # momentum
    assert tr.energy_residual() < 1e-8


def test_a_sine_load_beyond_a_brakes_capacity_breaks_it_away_each_period_by_default():
    # 6 sin(2 pi t) on a body held by a 5 N m brake: beyond the capacity from asin(5/6) / (2 pi) = 0.1568 s to
    # 0.3432 s of each half period; with no step limit the locked body's steps grew past that window unseen
    net = Network()
    a = net.body("a", 1.0)
    net.brake("brake", a, 5.0)
    net.source("drive", a, Sine(6.0, 1.0))
    tr = integrate(net, 3.0)
    t_break = np.arcsin(5.0 / 6.0) / (2.0 * np.pi)
    starts = tr.events[tr.events[:, 2] != 2, 0]  # breakaways, forward (1) and backward (-1)
    np.testing.assert_allclose(starts, t_break + 0.5 * np.arange(6), atol=1e-9)
    assert tr.stats["events"] == 12 and np.max(np.abs(tr.speed("a"))) > 0.1


@pytest.mark.parametrize(("option", "value", "named"), [("rtol", -1.0, "rtol"), ("rtol", 0.0, "rtol"),
                                                         ("h_max", 0.0, "h_max")])
def test_integrate_refuses_a_tolerance_or_step_limit_that_checks_nothing(option, value, named):
    net = Network()
    net.body("a", 1.0, w0=1.0)
    with pytest.raises(ValueError, match=named):
        integrate(net, 1.0, **{option: value})
