"""Redundant locks (two locks holding one body) and the one-way clutch, against closed forms and
Modelica results.

Where two locks hold one body the constraint torques are not unique; the engine takes the
least-norm distribution and lets the set go only when no distribution keeps every lock
within its limit (the released lock carries its sliding torque, the others the rest).
"""

from __future__ import annotations

import numpy as np
import pytest

from wetclutch.errors import SimulationError
from wetclutch.sim import workspace as engine
from wetclutch.sim.network import GROUND, Network, integrate
from wetclutch.sim.signals import Ramp, Sine, Step


def _release_times(tr, clutch: str) -> np.ndarray:
    j = [c.name for c in tr.network.clutches].index(clutch)
    ev = tr.events[(tr.events[:, 1] == j) & (tr.events[:, 2] != engine.LOCKED)]
    return ev[:, 0]


@pytest.mark.parametrize("caps", [(2.0, 5.0), (1.0, 2.0, 10.0)])
def test_parallel_clutches_break_away_at_their_combined_capacity(caps):
    # a driven by k t, b free: the pair passes T Jb / (Ja + Jb); clutches of 2 and 5 N m (or three)
    # hold it until that reaches their sum (least norm would load each alike: the weakest lets go
    # first, carrying its sliding torque, and the others take the rest)
    Ja, Jb, k = 1.0, 3.0, 10.0
    net = Network()
    a = net.body("a", Ja)
    b = net.body("b", Jb)
    net.source("drive", a, Ramp(0.0, 10.0, 0.0, 10.0 * k))
    for i, c in enumerate(caps):
        net.clutch(f"c{i + 1}", a, b, c)
    C = sum(caps)
    t_end = 3.0
    tr = integrate(net, t_end, dt_out=1e-3)
    t_break = C * (Ja + Jb) / (Jb * k)
    last = f"c{len(caps)}"
    assert _release_times(tr, last)[0] == pytest.approx(t_break, abs=1e-9)
    # while held: no slip, and the torques add up to what the pair passes, each within its capacity
    held = tr.t < t_break - 1e-6
    assert np.max(np.abs(tr.speed("a")[held] - tr.speed("b")[held])) < 1e-9
    total = sum(tr.clutch_torque(f"c{i + 1}") for i in range(len(caps)))
    np.testing.assert_allclose(total[held], k * tr.t[held] * Jb / (Ja + Jb), rtol=1e-9, atol=1e-9)
    for i, c in enumerate(caps):
        assert np.all(np.abs(tr.clutch_torque(f"c{i + 1}")[held]) <= c + 1e-9)
    # after: a sees k t - C, b sees +C
    w_common = k * t_break**2 / 2.0 / (Ja + Jb)
    dt = t_end - t_break
    wa = w_common + (k * (t_end**2 - t_break**2) / 2.0 - C * dt) / Ja
    wb = w_common + C * dt / Jb
    assert tr.speed("a")[-1] == pytest.approx(wa, rel=1e-8)
    assert tr.speed("b")[-1] == pytest.approx(wb, rel=1e-8)
    assert tr.energy_residual() < 1e-9


@pytest.mark.parametrize(("T_hold", "moves"), [(4.0, False), (6.0, True)])
def test_brakes_on_both_sides_of_a_gear_stop_it_and_hold_it(T_hold, moves):
    # ordinary vehicle braking: body 1 (2 kg m^2, 10 rad/s) drives body 2 (8 kg m^2) through an
    # ideal gear of ratio 0.5, brakes of 3 and 4 N m on either side. Reduced to body 1:
    # J = 2 + 0.25 * 8 = 4, brake torque 3 + 0.5 * 4 = 5 N m: standstill at 4 * 10 / 5 = 8 s.
    # From 10 s a torque on body 1: below 5 N m both stay at rest, above they move off.
    J1, J2, r, B1, B2, w0 = 2.0, 8.0, 0.5, 3.0, 4.0, 10.0
    net = Network()
    b1 = net.body("b1", J1, w0=w0)
    b2 = net.body("b2", J2, w0=r * w0)
    net.gear("g", b1, b2, r)
    net.brake("brake1", b1, B1)
    net.brake("brake2", b2, B2)
    net.source("drive", b1, Step(10.0, 0.0, T_hold))
    tr = integrate(net, 12.0, dt_out=1e-3)
    J_eq, B_eq = J1 + r * r * J2, B1 + r * B2
    t_stop = w0 * J_eq / B_eq
    assert tr.first_lock("brake1") == pytest.approx(t_stop, abs=1e-9)
    assert tr.first_lock("brake2") == pytest.approx(t_stop, abs=1e-9)
    w1 = tr.speed("b1")
    before = tr.t < t_stop
    np.testing.assert_allclose(w1[before], w0 - B_eq / J_eq * tr.t[before], rtol=1e-9, atol=1e-9)
    at_rest = (tr.t > t_stop) & (tr.t < 10.0)
    assert np.all(w1[at_rest] == 0.0) and np.all(tr.speed("b2")[at_rest] == 0.0)
    if moves:
        assert w1[-1] == pytest.approx((T_hold - B_eq) * 2.0 / J_eq, rel=1e-9)
        assert tr.speed("b2")[-1] == pytest.approx(r * w1[-1], rel=1e-9)
    else:
        assert np.all(w1[tr.t >= 10.0] == 0.0)
        # the brakes share the load within their limits
        assert abs(tr.clutch_torque("brake1")[-1]) <= B1 + 1e-9
        assert abs(tr.clutch_torque("brake2")[-1]) <= B2 + 1e-9
    assert tr.energy_residual() < 1e-9


@pytest.mark.parametrize("eta", [1.0, 0.8])
def test_brakes_on_either_side_of_a_gear_at_rest_break_away_together(eta):
    # at rest from the start: the ramp k t on body 1 must overcome B1 + r B2 / eta (forward power
    # flow through the gear; ratio 0.3, which is no binary fraction: the constraint matrix is
    # singular only up to rounding); then (J1 + r^2 J2 / eta) w' = k t - B1 - r B2 / eta
    J1, J2, r, B1, B2, k = 1.0, 5.0, 0.3, 2.0, 10.0, 4.0
    net = Network()
    b1 = net.body("b1", J1)
    b2 = net.body("b2", J2)
    net.gear("g", b1, b2, r, eta)
    net.brake("brake1", b1, B1)
    net.brake("brake2", b2, B2)
    net.source("drive", b1, Ramp(0.0, 10.0, 0.0, 10.0 * k))
    tr = integrate(net, 2.0)
    t_break = (B1 + r * B2 / eta) / k
    assert _release_times(tr, "brake2")[0] == pytest.approx(t_break, abs=1e-9)
    assert np.all(tr.speed("b1")[tr.t < t_break] == 0.0)
    J_eq = J1 + r * r * J2 / eta
    assert tr.speed("b1")[-1] == pytest.approx(k * (2.0 - t_break) ** 2 / 2.0 / J_eq, rel=1e-8)
    assert tr.energy_residual() < 1e-9


# Modelica Standard Library, Mechanics.Rotational.Examples.LossyGearDemo2 (bearing friction and a
# stuck lossy gear hold one inertia), reference result of the Modelica Association's regression
# suite: repository modelica/MAP-LIB_ReferenceResults, file
# Modelica/Mechanics/Rotational/Examples/LossyGearDemo2/LossyGearDemo2.csv (commit 668b76cf).
# Columns time, Inertia2.w; its events: backward from the start, standstill (gear stuck) at
# 0.0635911045847122 s, forward from 0.230374015885001 s, standstill at 0.308306846100604 s,
# backward from 0.472738310500834 s (the simulator's speeds at rest are 5e-11, not zero).
LGD2_W2 = [
    (0.01, -0.00706972803501361),
    (0.03, -0.0131664626254367),
    (0.05, -0.00876990702749678),
    (0.24, 0.000118610980146235),
    (0.25, 0.000420504273716994),
    (0.28, 0.00129868391464776),
    (0.3, 0.000746185083357515),
    (0.49, -0.00385566692380497),
    (0.5, -0.0096242780930112),
]
LGD2_STOPS = [0.0635911045847122, 0.308306846100604]
LGD2_STARTS = [0.230374015885001, 0.472738310500834]


def _lossy_gear_demo2() -> Network:
    # Inertia1 (1 kg m^2) with the drive 10 sin(2 pi t) and a bearing friction 0.5 + 0.5 |w| N m;
    # LossyGear ratio 2 (phi_a = 2 phi_b; here w_out = 0.5 w_in), mesh efficiency 0.5 both ways;
    # Inertia2 (1.5 kg m^2) with the load ramp -10 -> -5 N m over 2 s
    net = Network()
    i1 = net.body("Inertia1", 1.0)
    i2 = net.body("Inertia2", 1.5)
    net.source("DriveSine", i1, Sine(10.0, 1.0))
    net.clutch("bearingFriction", i1, GROUND, 0.5, mu_poly=(1.0, 1.0))
    net.gear("gear", i1, i2, 0.5, 0.5)
    net.source("load", i2, Ramp(0.0, 2.0, -10.0, -5.0))
    return net


def test_lossy_gear_demo2_matches_modelica():
    # steps of at most the reference's output interval: at rest no state changes, and a friction
    # bound crossed twice within one long step would pass unseen
    tr = integrate(_lossy_gear_demo2(), 0.5, dt_out=1e-4, h_max=1e-3)
    w2 = tr.speed("Inertia2")
    for t, ref in LGD2_W2:
        assert w2[int(round(t / 1e-4))] == pytest.approx(ref, abs=1e-7), t
    # the same stick and slip phases, to the reference's event instants
    moving = (w2 != 0.0).astype(int)
    edges = tr.t[np.flatnonzero(np.diff(moving)) + 1]
    edges = edges[edges > 1e-3]
    assert len(edges) == 4
    np.testing.assert_allclose(edges[::2], LGD2_STOPS, atol=1e-4)
    np.testing.assert_allclose(edges[1::2], LGD2_STARTS, atol=1e-4)
    # to the instant: the bearing friction's mode changes (stuck at 0.456 s, backward at 0.4727 s)
    ev = tr.events[:, 0]
    assert ev[0] == pytest.approx(LGD2_STOPS[0], abs=1e-7)
    assert ev[-1] == pytest.approx(LGD2_STARTS[1], abs=1e-7)
    assert tr.energy_residual() < 1e-9
    assert np.all(np.diff(tr.energies()["dissipated_gear"]) >= -1e-12)


# ---------------------------------------------------------------------------- one-way clutch

def test_freewheel_drives_then_lets_the_load_overrun():
    # a drives b through a freewheel with 10 N m for 1 s (together: (Ja + Jb) w' = 10 - 1),
    # then a is braked by -2 N m: b, loaded by a 1 N m brake, overruns it and coasts to rest
    Ja, Jb = 1.0, 3.0
    net = Network()
    a = net.body("a", Ja)
    b = net.body("b", Jb)
    net.source("drive", a, Step(1.0, 10.0, -2.0))
    net.one_way_clutch("fw", a, b)
    net.brake("load", b, 1.0)
    tr = integrate(net, 8.0)
    w1 = 9.0 / (Ja + Jb)
    wa, wb = tr.speed("a"), tr.speed("b")
    assert wa[1000] == pytest.approx(w1, rel=1e-12)
    after = (tr.t > 1.0) & (tr.t < 1.0 + w1 * Jb)
    np.testing.assert_allclose(wb[after], w1 - (tr.t[after] - 1.0) / Jb, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(wa[after], w1 - 2.0 * (tr.t[after] - 1.0) / Ja, rtol=1e-9, atol=1e-9)
    assert np.all(wa <= wb + 1e-12)  # a never overruns b
    assert tr.first_lock("load") == pytest.approx(1.0 + w1 * Jb, abs=1e-9)
    assert tr.energy_residual() < 1e-9


def test_freewheel_locks_when_the_driver_catches_up():
    # b spins freely at 10 rad/s; a, from rest, accelerates with 5 N m: it catches b at
    # t = 10 Ja / 5, then both accelerate with 5 / (Ja + Jb), exactly once locked
    Ja, Jb = 1.0, 1.5
    net = Network()
    a = net.body("a", Ja)
    b = net.body("b", Jb, w0=10.0)
    net.source("drive", a, 5.0)
    net.one_way_clutch("fw", a, b, capacity=0.0)
    tr = integrate(net, 4.0)
    t_lock = 10.0 * Ja / 5.0
    assert tr.first_lock("fw") == pytest.approx(t_lock, abs=1e-9)
    assert tr.stats["mode_switches"] == 1
    assert tr.speed("b")[-1] == pytest.approx(10.0 + 5.0 / (Ja + Jb) * (4.0 - t_lock), rel=1e-10)
    assert tr.energy_residual() < 1e-9


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_one_way_clutch_holds_one_way_without_limit_and_the_other_up_to_its_friction(sign):
    # a held by a strong brake; on b a ramp k t. Backward (b pushed below a) the freewheel holds
    # whatever the torque; forward b overruns a once k t exceeds the clutch's 3 N m, then slides
    # against 3 N m: Jb w' = k t - 3
    Jb, k, C = 2.0, 10.0, 3.0
    net = Network()
    a = net.body("a", 1.0)
    b = net.body("b", Jb)
    net.brake("hold", a, 1e6)
    net.one_way_clutch("owc", a, b, capacity=C)
    net.source("push", b, Ramp(0.0, 10.0, 0.0, sign * 10.0 * k))
    tr = integrate(net, 1.0)
    wb = tr.speed("b")
    if sign < 0:
        assert np.all(wb == 0.0)
        assert tr.clutch_torque("owc")[-1] == pytest.approx(k * 1.0, rel=1e-9)
    else:
        t_break = C / k
        assert _release_times(tr, "owc")[0] == pytest.approx(t_break, abs=1e-9)
        assert wb[-1] == pytest.approx((k * (1.0 - t_break**2) / 2.0 - C * (1.0 - t_break)) / Jb, rel=1e-9)
    assert tr.energy_residual() < 1e-9


def test_constraints_the_engine_cannot_reconcile_are_named_as_such_not_as_a_missing_inertia():
    # a lossy gear whose ratio moves, beside a locked clutch between two bodies with inertia: its velocity term is a
    # constraint of its own that the clutch does not imply; what the engine refuses is that pair of constraints,
    # not a body without inertia
    net = Network()
    b1, b2 = net.body("b1", 1.0, w0=5.0), net.body("b2", 1.0, w0=5.0)
    net.gear("g", b1, b2, 1.0, 0.9, rate=0.1, ratio_range=(0.5, 2.0))
    net.clutch("c", b1, b2, 5.0)
    net.source("d", b1, 3.0)
    with pytest.raises(SimulationError, match="the locks and gears on body 'b[12]' admit no single motion") as err:
        integrate(net, 1.0)
    assert "no inertia" not in str(err.value)
    assert "ratio moves" in str(err.value)
