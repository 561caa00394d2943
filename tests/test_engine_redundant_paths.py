"""Redundant paths between the same bodies (over-determined constraints), against closed forms.

Two gears in parallel, a gear beside a locked clutch, a gear chain locked through a clutch to a
braked body: the motion is unique even where the constraint torques are not. An ideal gear has no
modes (its constraint is the same whichever way power flows, and it has no friction to stick
with); a lossy gear whose constraint the locks beside it already hold carries no torque (of the
distributions within every element's limits, the one without loss in it) until they cannot hold
the load, and then carries what their sliding torque does not, with its loss.
"""

from __future__ import annotations

import numpy as np
import pytest

from wetclutch.sim import workspace as engine
from wetclutch.sim.network import GROUND, Network, integrate
from wetclutch.sim.signals import Ramp, Sine, Step


def _mode_changes(tr, clutch: str) -> np.ndarray:
    j = [c.name for c in tr.network.clutches].index(clutch)
    return tr.events[tr.events[:, 1] == j]


def _parallel_gears(r: float, eta1: float, eta2: float, drive) -> Network:
    net = Network()
    b1 = net.body("b1", 1.0)
    b2 = net.body("b2", 1.0)
    net.gear("g1", b1, b2, r, eta1)
    net.gear("g2", b1, b2, r, eta2)
    net.source("d", b1, drive)
    return net


def _gear_beside_clutch(eta: float, drive, w0: float = 0.0, cap: float = 5.0) -> Network:
    net = Network()
    b1 = net.body("b1", 1.0, w0=w0)
    b2 = net.body("b2", 1.0, w0=w0)
    net.gear("g", b1, b2, 1.0, eta)
    net.clutch("c", b1, b2, cap)
    net.source("d", b1, drive)
    return net


# ---------------------------------------------------------------------------- ideal gears

@pytest.mark.parametrize("r", [2.0, 1.0, 0.3])
def test_two_parallel_ideal_gears_from_rest_move_as_one(r):
    # J1 = J2 = 1, 3 N m on b1: (J1 + r^2 J2) w1' = 3; the gears pass r J2 w1' together (least norm: half each)
    tr = integrate(_parallel_gears(r, 1.0, 1.0, 3.0), 1.0)
    a = 3.0 / (1.0 + r * r)
    np.testing.assert_allclose(tr.speed("b1"), a * tr.t, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(tr.speed("b2"), r * a * tr.t, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(tr.gear_torque("g1")[1:] + tr.gear_torque("g2")[1:], r * a, rtol=1e-12)
    np.testing.assert_allclose(tr.gear_torque("g1")[1:], tr.gear_torque("g2")[1:], rtol=1e-9)
    assert tr.stats["events"] == 0
    assert tr.energy_residual() < 1e-12


def test_two_parallel_ideal_gears_at_rest_start_when_the_drive_does():
    # at rest until the 3 N m drive starts at 0.5 s: w1(1) = 3 * 0.5 / (1 + r^2)
    r = 2.0
    tr = integrate(_parallel_gears(r, 1.0, 1.0, Step(0.5, 0.0, 3.0)), 1.0)
    w1 = tr.speed("b1")
    assert np.all(w1[tr.t <= 0.5] == 0.0)
    np.testing.assert_allclose(w1[tr.t > 0.5], 3.0 / (1.0 + r * r) * (tr.t[tr.t > 0.5] - 0.5), rtol=1e-12,
                               atol=1e-12)
    assert tr.energy_residual() < 1e-12


@pytest.mark.parametrize("drive", [3.0, 30.0])
def test_ideal_gear_beside_a_clutch_from_rest_moves_as_one_within_the_clutch_capacity(drive):
    # ratio 1: the pair passes drive / 2 to b2 whatever the clutch holds (5 N m); least norm loads both
    # alike, and at 30 N m (15 through the pair) the clutch gives way and carries its 5 N m, the gear the rest
    tr = integrate(_gear_beside_clutch(1.0, drive), 1.0)
    a = drive / 2.0
    np.testing.assert_allclose(tr.speed("b1"), a * tr.t, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(tr.speed("b2"), a * tr.t, rtol=1e-12, atol=1e-12)
    Tc, Tg = tr.clutch_torque("c")[1:], tr.gear_torque("g")[1:]
    np.testing.assert_allclose(Tc + Tg, a, rtol=1e-12)
    assert np.all(np.abs(Tc) <= 5.0 + 1e-9)
    np.testing.assert_allclose(Tc, min(a / 2.0, 5.0), rtol=1e-12)
    assert tr.energy_residual() < 1e-12


def test_gear_chain_on_a_spring_locked_through_a_clutch_turns_back_at_each_standstill():
    # b1 (0.5) -ideal gear 0.5- b2 (massless) -clutch 4 N m- b3 (2, 1 rad/s) on a spring k = 5 to the ground,
    # with a 0.7 N m brake; -1 N m on b1. Reduced to b3 (deflection phi, phi' = w3): J = 2 + 0.5 / 0.25 = 4,
    # J phi'' = -2 - 0.7 sign(w3) - 5 phi, a harmonic motion about -(2 + 0.7 s) / 5 at w = sqrt(5 / 4) in each
    # direction s. It first stops at t1 = atan((1 / w) / 0.54) / w with the spring beyond what the brake holds,
    # so the brake slides back at once; each half period pi / w later the same (the clutch stays locked)
    J, k, B, T3 = 4.0, 5.0, 0.7, 2.0
    om = np.sqrt(k / J)
    net = Network()
    b1 = net.body("b1", 0.5, w0=2.0)
    b2 = net.body("b2", 0.0, w0=1.0)
    b3 = net.body("b3", 2.0, w0=1.0)
    net.source("drive", b1, -1.0)
    net.gear("g", b1, b2, 0.5)
    net.clutch("c", b2, b3, 4.0)
    net.spring("s", b3, GROUND, k)
    net.brake("brk", b3, B)
    tr = integrate(net, 6.0)
    c0 = (T3 + B) / k
    t1 = np.arctan((1.0 / om) / c0) / om
    phi1 = -c0 + np.hypot(c0, 1.0 / om)
    t2 = t1 + np.pi / om
    brk = _mode_changes(tr, "brk")
    assert len(brk) == 2
    np.testing.assert_allclose(brk[:, 0], [t1, t2], atol=1e-9)
    np.testing.assert_array_equal(brk[:, 2], [-1, 1])
    t, w3 = tr.t, tr.speed("b3")
    first, back = t < t1, (t > t1) & (t < t2)
    np.testing.assert_allclose(w3[first], -c0 * om * np.sin(om * t[first]) + np.cos(om * t[first]), atol=1e-8)
    e_back = (T3 - B) / k  # the backward phase's centre is -e_back
    np.testing.assert_allclose(w3[back], -(phi1 + e_back) * om * np.sin(om * (t[back] - t1)), atol=1e-8)
    np.testing.assert_allclose(tr.speed("b1"), 2.0 * w3, rtol=1e-9, atol=1e-9)
    assert tr.locked("c").all()
    assert np.all(np.abs(tr.clutch_torque("c")) <= 4.0 + 1e-9)
    assert tr.energy_residual() < 1e-8


def _sine_chain(J2: float, brake: float) -> Network:
    # a sine-driven chain: b1 (0.5) driven by 1 + 8 sin(2 pi 0.3 t) -ideal gear 0.5- b2 -clutch 4 N m- b3 (2)
    # on a spring (k 5, d 0.3) to the ground, with a brake
    net = Network()
    b1 = net.body("b1", 0.5)
    b2 = net.body("b2", J2)
    b3 = net.body("b3", 2.0)
    net.source("drive", b1, Sine(8.0, 0.3, offset=1.0))
    net.gear("g", b1, b2, 0.5, 1.0)
    net.clutch("c", b2, b3, 4.0)
    net.spring("s", b3, GROUND, 5.0, 0.3)
    net.brake("brk", b3, brake)
    return net


@pytest.mark.parametrize("J2", [0.0, 0.1])
def test_sine_driven_gear_chain_with_a_braked_spring_load_runs_through_its_standstills(J2):
    # it comes to rest locked through the clutch at about 5.89 s, where the spring and the drive push it back
    # beyond the brake: the brake turns from sliding forward to sliding back at that instant (each lock within
    # its capacity, the gear on its ratio, the energy balance closed)
    tr = integrate(_sine_chain(J2, 0.7), 12.0)
    assert np.all(np.abs(tr.clutch_torque("c")) <= 4.0 + 1e-9)
    assert np.all(np.abs(tr.clutch_torque("brk")) <= 0.7 + 1e-9)
    np.testing.assert_allclose(tr.speed("b2"), 0.5 * tr.speed("b1"), rtol=1e-9, atol=1e-9)
    brk = _mode_changes(tr, "brk")
    turn = brk[(brk[:, 0] > 5.8) & (brk[:, 0] < 6.0)]
    assert len(turn) == 1 and turn[0, 2] == -1
    w3, t = tr.speed("b3"), tr.t
    near = np.abs(t - turn[0, 0]) < 0.02
    assert np.all(w3[near & (t < turn[0, 0])] > 0.0) and np.all(w3[near & (t > turn[0, 0])] < 0.0)
    assert tr.locked("c")[near].all()
    assert tr.energy_residual() < 1e-7


# ---------------------------------------------------------------------------- lossy gears

@pytest.mark.parametrize("w0", [0.0, 5.0])
def test_lossy_gear_beside_a_locked_clutch_carries_nothing_while_the_clutch_holds(w0):
    # ratio 1, eta 0.9, clutch 5 N m; 3 N m on b1: the clutch passes 1.5 N m, the gear none (no loss):
    # w(t) = w0 + 1.5 t
    tr = integrate(_gear_beside_clutch(0.9, 3.0, w0=w0), 1.0)
    np.testing.assert_allclose(tr.speed("b1"), w0 + 1.5 * tr.t, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(tr.speed("b2"), tr.speed("b1"), rtol=1e-12, atol=1e-12)
    assert np.all(tr.gear_torque("g")[1:] == 0.0)
    np.testing.assert_allclose(tr.clutch_torque("c")[1:], 1.5, rtol=1e-12)
    assert np.all(tr.energies()["dissipated_gear"] == 0.0)
    assert tr.energy_residual() < 1e-12


def test_lossy_gear_beside_a_clutch_takes_over_what_the_clutch_cannot_hold():
    # a ramp 10 t N m on b1: the clutch (5 N m) alone passes 5 t until t = 1 s, then slides at zero slip
    # with 5 N m and the gear (forward, c = 1/eta) carries lam = (10 t - 10) / (1 + c):
    # w(2) = 2.5 + 5 + 10 * 0.5 / (1 + c)
    eta = 0.9
    c = 1.0 / eta
    tr = integrate(_gear_beside_clutch(eta, Ramp(0.0, 2.0, 0.0, 20.0)), 2.0)
    ev = _mode_changes(tr, "c")
    assert len(ev) == 1 and ev[0, 2] == 1
    assert ev[0, 0] == pytest.approx(1.0, abs=1e-9)
    t = tr.t
    held = t < 1.0
    np.testing.assert_allclose(tr.speed("b1")[held], 2.5 * t[held] ** 2, rtol=1e-12, atol=1e-12)
    assert np.all(tr.gear_torque("g")[held] == 0.0)
    over = t > 1.0
    np.testing.assert_allclose(tr.gear_torque("g")[over], (10.0 * t[over] - 10.0) / (1.0 + c), rtol=1e-9)
    np.testing.assert_allclose(tr.speed("b1")[-1], 7.5 + 5.0 / (1.0 + c), rtol=1e-12)
    np.testing.assert_allclose(tr.speed("b2"), tr.speed("b1"), rtol=1e-12, atol=1e-12)
    assert np.all(np.abs(tr.clutch_torque("c")) <= 5.0 + 1e-9)
    # the loss: (c - 1) lam w, from 1 s on
    e_gear = tr.energies()["dissipated_gear"]
    assert np.all(np.diff(e_gear) >= 0.0) and e_gear[-1] > 0.0
    assert tr.energy_residual() < 1e-9


def test_lossy_gear_beside_a_clutch_idles_again_when_the_clutch_can_hold_once_more():
    # 12 N m: the clutch slides with 5 N m at zero slip, the gear carries lam = 2 / (1 + c), w' = 5 + lam;
    # from 1 s 3 N m: the clutch locks again (at once, the gear's torque through zero) and w' = 1.5
    eta = 0.9
    lam = 2.0 / (1.0 + 1.0 / eta)
    tr = integrate(_gear_beside_clutch(eta, Step(1.0, 12.0, 3.0)), 2.0)
    ev = _mode_changes(tr, "c")
    assert ev[-1, 2] == engine.LOCKED and ev[-1, 0] == pytest.approx(1.0, abs=1e-9)
    t = tr.t
    np.testing.assert_allclose(tr.gear_torque("g")[(t > 0.0) & (t < 1.0)], lam, rtol=1e-12)
    assert np.all(tr.gear_torque("g")[t > 1.0] == 0.0)
    np.testing.assert_allclose(tr.speed("b1")[-1], 5.0 + lam + 1.5, rtol=1e-12)
    assert tr.energy_residual() < 1e-12


def test_two_parallel_lossy_gears_from_rest_move_as_one():
    # ratio 2, eta 0.9 both; 3 N m on b1: (J1 + r^2 J2 / eta) w1' = 3, the two gears' losses alike
    r, eta = 2.0, 0.9
    tr = integrate(_parallel_gears(r, eta, eta, 3.0), 1.0)
    a = 3.0 / (1.0 + r * r / eta)
    np.testing.assert_allclose(tr.speed("b1"), a * tr.t, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(tr.gear_torque("g1")[1:] + tr.gear_torque("g2")[1:], r * a, rtol=1e-12)
    assert tr.energy_residual() < 1e-12


def test_lossy_gear_beside_an_ideal_one_carries_nothing():
    # ratio 2, eta 0.7 beside an ideal gear: the ideal one holds the constraint alone, without loss:
    # (J1 + r^2 J2) w1' = 3
    r = 2.0
    tr = integrate(_parallel_gears(r, 0.7, 1.0, 3.0), 1.0)
    a = 3.0 / (1.0 + r * r)
    np.testing.assert_allclose(tr.speed("b1"), a * tr.t, rtol=1e-12, atol=1e-12)
    assert np.all(tr.gear_torque("g1")[1:] == 0.0)
    np.testing.assert_allclose(tr.gear_torque("g2")[1:], r * a, rtol=1e-12)
    assert np.all(tr.energies()["dissipated_gear"] == 0.0)
    assert tr.energy_residual() < 1e-12
