"""The clutch pack's heat: closed form, energy balance with heat, friction vs plate temperature, a launch sequence."""

from __future__ import annotations

import numpy as np
import pytest

import wetclutch as wc
from wetclutch.physics import thermal
from wetclutch.plant.scenarios import launch_sequence
from wetclutch.sim.network import Network, integrate


def _braked_flywheel(capacity: float, w0: float, record: np.ndarray) -> Network:
    """A flywheel so heavy that a brake's slip, and so its slip power, stays constant."""
    net = Network()
    a = net.body("a", 1e12, w0=w0)
    c = net.brake("c", a, capacity)
    net.thermal(c, record)
    return net


def test_constant_slip_power_heats_a_lumped_capacity_as_the_closed_form():
    """C dT/dt = P - h (T - T_oil): T(t) = T_oil + P/h (1 - exp(-h t / C)) from T(0) = T_oil."""
    p = wc.load_params()
    rec = thermal.pack(p, 40.0)
    power = 10.0 * 100.0  # 10 N m at 100 rad/s
    tr = integrate(_braked_flywheel(10.0, 100.0, rec), 180.0, dt_out=0.5)
    expected = 40.0 + power / p.thermal.h_oil * (1.0 - np.exp(-p.thermal.h_oil * tr.t / p.thermal.C_pack))
    assert np.max(np.abs(tr.plate_temperature() - expected)) < 1e-6
    # three time constants in: 95 % of the way to P/h = 40 K above the oil
    assert tr.plate_temperature()[-1] == pytest.approx(40.0 + 40.0 * (1 - np.exp(-3.0)), abs=1e-6)


def test_a_hot_pack_cools_to_the_oil_and_the_heat_goes_to_the_oil():
    p = wc.load_params()
    rec = thermal.pack(p, 40.0, plate_temp_C=140.0)
    tr = integrate(_braked_flywheel(0.0, 0.0, rec), 120.0, dt_out=1.0)
    assert np.max(np.abs(tr.plate_temperature() - thermal.closed_form(tr.t, 0.0, rec))) < 1e-6
    e = tr.energies()
    # what the plates lost, the oil took
    assert e["heat_oil_c"][-1] == pytest.approx(-e["heat_plates_c"][-1], rel=1e-9)
    assert e["heat_oil_c"][-1] == pytest.approx(p.thermal.C_pack * (140.0 - tr.plate_temperature()[-1]), rel=1e-9)


def test_energy_balance_closes_with_the_heat_counted():
    """engage: the clutch's slip energy is the heat in the plates plus the heat carried off by the oil."""
    r = wc.simulate("engage")
    s = r.summary
    assert s["E_clutch"] > 1e3
    assert s["E_heat_plates"] + s["E_heat_oil"] == pytest.approx(s["E_clutch"], rel=1e-9)
    assert s["energy_residual"] < 1e-6
    # the plates warm up during the slip phase; they are hottest where the falling slip power
    # equals what the oil takes away (just before synchronisation), and cool after it
    sig = r.signals
    T, t = sig["T_plate"].to_numpy(), sig["time"].to_numpy()
    T_oil = r.params.rig.oil_temp_C
    assert T[0] == pytest.approx(T_oil)
    k = int(np.argmax(T))
    assert 0.5 * s["t_sync"] < t[k] < s["t_sync"]
    slip_power = (sig["T_c"] * sig["slip"]).to_numpy()
    assert slip_power[k] == pytest.approx(r.params.thermal.h_oil * (T[k] - T_oil), rel=0.02)
    assert np.all(np.diff(T[t > s["t_sync"]]) < 0.0)


def test_friction_follows_plate_temperature_when_asked():
    p = wc.load_params(overrides={"thermal.mu_temp": -2e-3, "thermal.T_mu_ref_C": 40.0})
    rec = thermal.pack(p, 40.0)
    tr = integrate(_braked_flywheel(10.0, 100.0, rec), 60.0, dt_out=1.0)
    T = tr.plate_temperature()
    assert np.allclose(np.abs(tr.clutch_torque("c")), 10.0 * (1.0 - 2e-3 * (T - 40.0)), rtol=1e-12)
    assert T[-1] > 55.0  # so the friction did fall by some 3 %
    # default: no dependence
    tr0 = integrate(_braked_flywheel(10.0, 100.0, thermal.pack(wc.load_params(), 40.0)), 60.0, dt_out=1.0)
    assert np.all(np.abs(tr0.clutch_torque("c")) == 10.0)


def test_ten_launches_in_a_row_heat_the_clutch():
    seq = launch_sequence(n=10, pause=10.0)
    assert len(seq) == 10
    peaks = seq["T_plate_peak"].to_numpy()
    starts = seq["T_plate_start"].to_numpy()
    assert np.all(np.diff(peaks) > 0.0) and np.all(np.diff(starts) > 0.0)
    # each launch adds about its slip energy over the heat capacity (less what the oil takes meanwhile)
    rise = peaks[0] - starts[0]
    assert 0.6 * seq["E_clutch"].iloc[0] / wc.load_params().thermal.C_pack < rise < seq["E_clutch"].iloc[0] / 1500.0
    assert peaks[-1] - peaks[0] > 2.0 * rise  # 10 s pauses are short against the 60 s cooling time constant


def test_launch_reports_plate_temperature_against_its_limit():
    from wetclutch import launch

    cond = launch.Conditions(t_ref=100.0, oil_temp_C=85.0)
    ok = launch.simulate(wc.load_params(), "launch", cond)
    s = ok.summary
    assert s["T_plate_peak_C"] == pytest.approx(ok.truth["T_plate"].max())
    assert 85.0 < s["T_plate_peak_C"] < s["T_plate_limit_C"] and not s["T_plate_over_limit"]
    # the plates took the slip energy less what the oil carried off meanwhile
    rise = s["T_plate_peak_C"] - 85.0
    assert 0.7 * s["slip_energy_J"] / 1500.0 < rise < s["slip_energy_J"] / 1500.0
    hot = launch.simulate(wc.load_params(overrides={"thermal.T_plate_limit_C": 86.0}), "launch", cond)
    assert hot.summary["T_plate_over_limit"]


def test_rig_truth_carries_the_plate_temperature():
    from wetclutch.rig import experiments

    r = experiments.run("step", level=2.5, oil_temp_C=41.0, seed=1)
    T = r.truth["T_plate"].to_numpy()
    assert T[0] == pytest.approx(41.0) and T.max() > 43.0
