"""The study's driveline: closed-form slip phase, energy account, 2.1 Hz, massless limit."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq

import wetclutch as wc
from wetclutch.errors import WetclutchError
from wetclutch.plant import driveline
from wetclutch.sim.network import integrate
from wetclutch.sim.signals import Step


def test_constant_capacity_sync_time_matches_closed_form():
    """With drag off and capacity constant from t0, the slip phase is linear:
    the primary decelerates uniformly, the secondary side is a linear ODE solved
    exactly with a matrix exponential; sync is where the two speeds meet."""
    # an overdamped axle keeps the CVT output turning forward from the first instant,
    # so power flows forward all through the slip phase (one linear regime)
    p = wc.load_params(
        overrides={"driveline.b_1": 0.0, "driveline.b_2": 0.0, "engage.T_load": 0.0, "driveline.d_a": 10.0}
    )
    d = p.driveline
    T, t0 = 30.0, 0.2
    tr = integrate(driveline.build(p, Step(t0, 0.0, T), 0.0), 8.0)
    slipping = tr.t < tr.first_lock("clutch")
    assert np.all(tr.speed("r")[slipping] >= 0.0) and np.all(tr.gear_torque("cvt")[slipping] >= 0.0)
    i, c = d.ratio, 1.0 / d.eta  # power flows forward during the slip phase
    # states (w_1, phi, w_s); input T on the clutch output
    A = np.array(
        [
            [-i * c * d.d_a * i / d.J_1, -i * c * d.k_a / d.J_1, i * c * d.d_a / d.J_1],
            [i, 0.0, -1.0],
            [d.d_a * i / d.J_s, d.k_a / d.J_s, -d.d_a / d.J_s],
        ]
    )
    # constant input: expm of the augmented matrix [[A, B], [0, 0]] (A itself is singular)
    M = np.zeros((4, 4))
    M[:3, :3] = A
    M[0, 3] = T / d.J_1

    def slip(t):
        x = expm(M * (t - t0)) @ np.array([0.0, 0.0, 0.0, 1.0])
        return d.omega_p0 - T / d.J_p * (t - t0) - x[0]

    expected = brentq(slip, t0 + 0.1, 7.0, xtol=1e-14)
    assert tr.first_lock("clutch") == pytest.approx(expected, rel=1e-6)


def test_engage_energy_balance_closes(engage_default):
    assert engage_default.summary["energy_residual"] < 1e-6
    e = engage_default.trajectory.energies()
    stored = e["kinetic"] + e["spring"]
    lost = sum(v for k, v in e.items() if k.startswith("dissipated_"))
    assert np.max(np.abs(stored + lost - stored[0] - e["source_work"])) < 1e-6 * stored[0]
    for k, v in e.items():
        if k.startswith("dissipated_"):
            assert np.all(np.diff(v) >= -1e-9 * stored[0]), k


def test_post_sync_oscillation_at_2_1_hz(engage_default):
    s = engage_default.signals
    t_sync = engage_default.summary["t_sync"]
    after = s[s.time > t_sync + 0.2]
    f = driveline.ring_frequency(after.time.to_numpy(), after.T_r.to_numpy())
    assert f == pytest.approx(2.1, rel=0.03)
    # an FFT of the same window agrees
    y = after.T_r.to_numpy() - after.T_r.mean()
    n = 1 << 16
    spec = np.abs(np.fft.rfft(y * np.hanning(y.size), n))
    freqs = np.fft.rfftfreq(n, d=1e-3)
    assert freqs[np.argmax(spec)] == pytest.approx(2.1, rel=0.03)


def test_engage_sequence(engage_default):
    s = engage_default.signals
    summ = engage_default.summary
    assert 2.0 < summ["t_sync"] < 5.0
    # slip phase: T_r = eta T_c / i, the massless relation of the spec, within 0.5 %
    p = wc.Params().driveline
    slip = s[(s.time > 1.2) & (s.time < summ["t_sync"] - 0.2)]
    np.testing.assert_allclose(slip.T_r, p.eta * slip.T_c / p.ratio, rtol=5e-3)
    assert np.all(s.locked[s.time > summ["t_sync"] + 1e-3] == 1)
    assert summ["mode_switches"] == 3  # clutch starts sliding, brake releases, clutch locks


def test_small_clutch_output_inertia_changes_no_figure(engage_default):
    """J_1 stands in for the study's massless clutch output; the figures converge."""
    p = wc.load_params(overrides={"driveline.J_1": wc.Params().driveline.J_1 / 10})
    light = wc.simulate("engage", p)
    for key in ("t_sync", "T_r_peak", "E_clutch"):
        assert light.summary[key] == pytest.approx(engage_default.summary[key], rel=5e-3), key


def test_result_columns(engage_default):
    cols = ["time", "omega_p", "omega_1", "omega_r", "omega_s", "T_c", "T_r", "T_cap", "locked"]
    assert list(engage_default.signals.columns[: len(cols)]) == cols
    assert set(engage_default.signals.locked.unique()) <= {0, 1}
    assert engage_default.signals.time.iloc[-1] == pytest.approx(8.0)
    assert np.allclose(np.diff(engage_default.signals.time), 1e-3)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"rtol": "1e-6"}, "rtol must be a number"), ({"t_end": "1 s"}, "t_end must be a number"),
    ({"t_end": 0}, "t_end must be > 0"), ({"rtol": -1}, r"rtol must be in \(0, 1\)"), ({"h_max": 0}, "h_max"),
    ({"solver": "bdf"}, "unknown option 'solver'")])
def test_simulate_refuses_bad_options_in_one_line(kwargs, message):
    # before the compiled core: a string would fail there only after its compilation, as a typing error
    with pytest.raises(WetclutchError, match=message):
        wc.simulate("engage", **kwargs)


def test_simulate_refuses_a_table_for_a_parameter_set():
    with pytest.raises(WetclutchError, match="params must be a parameter set"):
        wc.simulate("engage", {"driveline.ratio": 0.6})
    assert wc.simulate("engage", t_end=np.float64(1.0), rtol=np.float32(1e-6)).summary["t_sync"] is None
