"""Response metrics on synthetic signals with known answers (wetclutch.launch.metrics)."""

import numpy as np
import pytest

from wetclutch.launch import metrics

DT = 1e-3
T_REQ = 1.0


def _grid(t_end=4.0):
    return np.arange(0.0, t_end, DT)


def _first_order(t, level, tau):
    return np.where(t >= T_REQ, level * (1.0 - np.exp(-(t - T_REQ) / tau)), 0.0)


def test_first_order_response():
    t = _grid()
    tau = 0.05
    r = metrics.response(t, _first_order(t, 100.0, tau), np.where(t >= T_REQ, 100.0, 0.0), T_REQ, None)
    assert r.t95_s == pytest.approx(tau * np.log(20.0), abs=DT)  # 95 % of a first-order step at tau ln 20
    # the window starts at 6 tau: mean of exp(-t/tau) over it
    assert r.steady_state_error_pct == pytest.approx(100 * tau / 1.0 * np.exp(-0.3 / tau), rel=0.05)
    assert r.overshoot_pct == pytest.approx(r.steady_state_error_pct, rel=0.01)  # the final value over T_ss
    # largest slope level/tau at the request, smoothed over metrics.SMOOTH
    expected = 100.0 * (1.0 - np.exp(-metrics.SMOOTH / tau)) / metrics.SMOOTH
    assert r.jerk_max == pytest.approx(expected, rel=0.03)


@pytest.mark.parametrize("zeta", [0.3, 0.5, 0.7])
def test_second_order_overshoot(zeta):
    t = _grid()
    wn = 30.0
    wd = wn * np.sqrt(1 - zeta**2)
    s = np.maximum(t - T_REQ, 0.0)
    y = 1.0 - np.exp(-zeta * wn * s) * (np.cos(wd * s) + zeta / np.sqrt(1 - zeta**2) * np.sin(wd * s))
    r = metrics.response(t, 80.0 * y, np.where(t >= T_REQ, 80.0, 0.0), T_REQ, None)
    expected = 100.0 * np.exp(-np.pi * zeta / np.sqrt(1 - zeta**2))
    assert r.overshoot_pct == pytest.approx(expected, abs=1.0)


@pytest.mark.parametrize("gain, passes", [(0.95, True), (0.905, True), (0.88, False), (1.12, False)])
def test_steady_state_error_threshold(gain, passes):
    t = _grid()
    r = metrics.response(t, _first_order(t, 100.0 * gain, 0.02), np.where(t >= T_REQ, 100.0, 0.0), T_REQ, None)
    assert r.steady_state_error_pct == pytest.approx(abs(1 - gain) * 100, abs=1e-3)
    assert metrics.requirements(r, r)["steady_state_error"] is passes


def test_window_ends_before_synchronisation():
    t = _grid()
    y = _first_order(t, 100.0, 0.02)
    y[t > 1.6] = 0.0  # torque collapses after synchronisation
    r = metrics.response(t, y, np.where(t >= T_REQ, 100.0, 0.0), T_REQ, t_sync=1.7)
    assert r.window[1] == pytest.approx(1.6)
    assert r.steady_state_error_pct == pytest.approx(0.0, abs=1e-3)


def test_no_steady_state_when_synchronised_at_once():
    t = _grid()
    r = metrics.response(t, _first_order(t, 100.0, 0.02), np.where(t >= T_REQ, 100.0, 0.0), T_REQ, t_sync=1.35)
    assert np.isnan(r.steady_state_error_pct)
    req = metrics.requirements(r, r)
    assert not req["steady_state_error"] and not req["response_time"] and not req["robustness"]


def test_never_reaching_is_infinite_t95():
    t = _grid()
    r = metrics.response(t, np.where(t > 3.0, 100.0, 0.0), np.where(t >= T_REQ, 100.0, 0.0), T_REQ, None)
    assert r.steady_state_error_pct == pytest.approx(100.0)
    assert not metrics.requirements(r, r)["response_time"]


def test_robustness_compares_with_nominal():
    t = _grid()
    ref = np.where(t >= T_REQ, 100.0, 0.0)
    nominal = metrics.response(t, _first_order(t, 100.0, 0.03), ref, T_REQ, None)
    close = metrics.response(t, _first_order(t, 100.0, 0.04), ref, T_REQ, None)
    slow = metrics.response(t, _first_order(t, 100.0, 0.03 + 0.06 / np.log(20.0)), ref, T_REQ, None)
    assert metrics.requirements(close, nominal)["robustness"]
    assert not metrics.requirements(slow, nominal)["robustness"]
    assert not metrics.requirements(close, metrics.Response.empty())["robustness"]


def test_t95_of_a_ramp_request_is_the_lag_behind_it():
    t = _grid()
    ref = 100.0 * np.clip((t - T_REQ) / 0.3, 0.0, 1.0)
    lag = 0.04
    T_r = 100.0 * np.clip((t - T_REQ - lag) / 0.3, 0.0, 1.0)
    r = metrics.response(t, T_r, ref, T_REQ, None)
    assert r.t95_s == pytest.approx(lag, abs=2 * DT)



def test_no_relative_error_without_a_request_in_the_window():
    t = np.arange(0.0, 3.0, 1e-3)
    req = np.where(t < 1.2, 50.0, 0.0)  # a request dropped before the steady window
    r = metrics.response(t, np.zeros_like(t), req, 1.0, None)
    assert np.isnan(r.steady_state_error_pct) and np.isnan(r.t95_s)
