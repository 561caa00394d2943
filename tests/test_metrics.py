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


def test_an_early_lock_up_is_judged_over_the_last_window_before_it():
    # lock-up 0.44 s after the request: 0.04 s of the usual window is left; the last 0.1 s before t_sync - 0.1 s
    # starts 0.24 s after the request, once the 0.2 s allowed for the response are over
    t = _grid()
    y = _first_order(t, 100.0, 0.02)
    r = metrics.response(t, y, np.where(t >= T_REQ, 100.0, 0.0), T_REQ, t_sync=1.44)
    assert r.window == pytest.approx((1.24, 1.34))
    assert r.steady_state_error_pct == pytest.approx(100.0 * np.mean(np.exp(-(t[(t >= 1.24) & (t <= 1.34)] - 1.0)
                                                                           / 0.02)), rel=0.05)
    assert r.t95_settled_s == pytest.approx(0.02 * np.log(20.0), abs=5 * DT)  # the band judged on a centred mean
    assert all(metrics.requirements(r, r).values())


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


def test_a_response_faster_than_the_nominals_is_no_deterioration():
    # a nominal launch at the clutch's capacity answers late (0.03 s + 0.1 s more to 95 %); a launch with the capacity
    # it lacks answers 0.1 s sooner, with no more overshoot: robust, whereas one 0.06 s later than the nominal is not
    t = _grid()
    ref = np.where(t >= T_REQ, 100.0, 0.0)
    late = metrics.response(t, _first_order(t, 100.0, 0.03 + 0.1 / np.log(20.0)), ref, T_REQ, None)
    fast = metrics.response(t, _first_order(t, 100.0, 0.03), ref, T_REQ, None)
    later = metrics.response(t, _first_order(t, 100.0, 0.03 + 0.16 / np.log(20.0)), ref, T_REQ, None)
    assert fast.t95_settled_s < late.t95_settled_s - 0.09
    assert metrics.requirements(fast, late)["robustness"]
    assert not metrics.requirements(later, late)["robustness"]


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


def _hump(t, level, hump):
    """A response that rises to ``hump`` x level at 30 ms, dips to 80 % at 50 ms and rises again to level at 70 ms."""
    s = t - T_REQ
    return np.where(s < 0, 0.0, level * np.interp(s, [0.0, 0.03, 0.05, 0.07, 10.0], [0.0, hump, 0.8, 1.0, 1.0]))


def test_settled_t95_is_stable_where_the_first_crossing_jumps():
    # the steady value moves by 1 N m: the hump ends on either side of 95 %
    t = _grid()
    ref = np.where(t >= T_REQ, 100.0, 0.0)
    lo = metrics.response(t, _hump(t, 100.0, 0.955), ref, T_REQ, None)
    hi = metrics.response(t, _hump(t, 101.0, 0.945), ref, T_REQ, None)
    assert lo.t95_s == pytest.approx(0.03, abs=2 * DT) and hi.t95_s == pytest.approx(0.067, abs=2 * DT)
    # the last entry into the band: where the second rise crosses 95 % (smoothing lags it a few ms)
    assert lo.t95_settled_s == pytest.approx(hi.t95_settled_s, abs=2 * DT)
    assert 0.065 <= lo.t95_settled_s <= 0.075


def _sag(t, depth):
    """A first-order response (tau 20 ms) to 100 N m whose torque sags by ``depth`` x 100 N m, a smooth dip
    0.1 s wide centred 0.8 s after the request, inside the steady window."""
    return _first_order(t, 100.0, 0.02) - depth * 100.0 * np.exp(-(((t - T_REQ - 0.8) / 0.05) ** 2))


def test_settled_t95_does_not_jump_with_a_sag_inside_the_steady_window():
    t = _grid()
    ref = np.where(t >= T_REQ, 100.0, 0.0)
    shallow, deep = (metrics.response(t, _sag(t, d), ref, T_REQ, None) for d in (0.045, 0.06))
    assert deep.T_ss < shallow.T_ss and 0.95 * deep.T_ss > 100.0 * (1.0 - 0.06)  # the deep sag leaves the band
    # both: the first-order rise's 95 % (tau ln 20), smoothing lags it a few samples
    assert [shallow.t95_settled_s, deep.t95_settled_s] == pytest.approx([0.02 * np.log(20.0)] * 2, abs=0.012)
    # the sag is the steady state's: its ripple grows with its depth
    assert deep.ripple_pct > shallow.ripple_pct > 0.5


def test_settled_t95_of_a_response_still_rising_when_the_steady_window_begins():
    t = _grid()
    ref = np.where(t >= T_REQ, 100.0, 0.0)
    tau = 0.12  # 95 % at tau ln 20 = 0.36 s, after the steady window begins
    r = metrics.response(t, _first_order(t, 100.0, tau), ref, T_REQ, None)
    assert r.t95_settled_s == pytest.approx(r.t95_s, abs=0.012) and r.t95_settled_s > metrics.STEADY_START
    assert not metrics.requirements(r, r)["response_time"]


def test_ripple_of_a_sustained_oscillation_fails_robustness():
    t = _grid()
    ref = np.where(t >= T_REQ, 100.0, 0.0)
    f, amp = 18.0, 40.0  # Hz, N m: the mean is right, the slip phase shakes
    y = _first_order(t, 100.0, 0.02) + np.where(t >= T_REQ + 0.2, amp * np.sin(2 * np.pi * f * t), 0.0)
    r = metrics.response(t, y, ref, T_REQ, None)
    assert r.steady_state_error_pct < 1.0
    assert r.ripple_pct == pytest.approx(amp / np.sqrt(2.0) / r.T_ss * 100.0, rel=0.01)  # the sine's RMS
    # about a constant all of it oscillates: the oscillation is the same sine's RMS
    assert r.oscillation_pct == pytest.approx(r.ripple_pct, rel=0.01)
    calm = metrics.response(t, _first_order(t, 100.0, 0.02), ref, T_REQ, None)
    assert metrics.requirements(calm, calm)["robustness"]
    assert not metrics.requirements(r, calm)["robustness"]


def test_a_sag_has_a_ripple_but_no_oscillation():
    # the torque reaches the request, then sags linearly by 30 N m over the steady window (a clutch at its
    # capacity as the slip falls): its RMS about the mean is the ramp's, drop / sqrt(12)
    t = _grid()
    ref = np.where(t >= T_REQ, 100.0, 0.0)
    w0, w1 = T_REQ + metrics.STEADY_START, T_REQ + metrics.STEADY_END
    drop = 30.0
    y = _first_order(t, 100.0, 0.02) - drop * np.clip((t - w0) / (w1 - w0), 0.0, 1.0)
    r = metrics.response(t, y, ref, T_REQ, None)
    assert r.ripple_pct == pytest.approx(drop / np.sqrt(12.0) / r.T_ss * 100.0, rel=0.02)
    # the same sag with an 18 Hz shake on top: the oscillation is the shake's alone, the sag adds nothing to it
    amp, f = 10.0, 18.0
    shaken = metrics.response(t, y + np.where(t >= T_REQ + 0.2, amp * np.sin(2 * np.pi * f * t), 0.0), ref, T_REQ,
                              None)
    assert shaken.oscillation_pct == pytest.approx(amp / np.sqrt(2.0) / shaken.T_ss * 100.0, rel=0.02)


def _noisy(t, y, sigma, seed=0):
    return y + np.random.default_rng(seed).normal(0.0, sigma, t.size)


@pytest.mark.parametrize("sigma", [0.25, 1.0, 2.0])
def test_noise_std_from_the_standby(sigma):
    # a waiting clutch's slow creep under the white noise of the reading: the noise's deviation comes back
    t = _grid()
    creep = 5.0 + 2.0 * np.sin(2 * np.pi * 0.5 * t)
    got = [metrics.noise_std(t, _noisy(t, creep, sigma, seed), T_REQ) for seed in range(20)]
    assert np.mean(got) == pytest.approx(sigma, rel=0.05)
    assert np.std(got) < 0.15 * sigma  # 200 samples: the median's spread
    assert metrics.noise_std(t, creep, T_REQ) < 0.01  # the creep's own change from sample to sample


def test_the_readings_noise_is_no_ripple():
    # a 25 N m request read with 2 N m of white noise (8 % of it): no ripple once the sensor's noise is taken out
    t = _grid()
    ref = np.where(t >= T_REQ, 25.0, 0.0)
    y = _noisy(t, _first_order(t, 25.0, 0.02), 2.0)
    r = metrics.response(t, y, ref, T_REQ, None, noise=2.0)
    # what is left: the mean square of the window's 1,000 noise samples varies by sqrt(2 / 1000) of the noise's
    # variance, 0.42 N m (1.7 % of 25 N m) at one standard deviation
    assert r.ripple_pct < 2.5 and r.oscillation_pct < 2.5
    assert metrics.requirements(r, r)["robustness"]
    # counted, the noise alone would be ripple: 2 / 25 = 8 %
    assert metrics.response(t, y, ref, T_REQ, None, noise=0.0).ripple_pct == pytest.approx(8.0, rel=0.05)


@pytest.mark.parametrize("f", [18.0, 110.0])
def test_an_oscillation_fails_whatever_its_frequency(f):
    # a valve in a limit cycle: the axle torque swings by 30 N m about the right mean, read with noise; a
    # smoothing that hides the noise would hide most of 110 Hz as well
    t = _grid()
    ref = np.where(t >= T_REQ, 180.0, 0.0)
    amp = 30.0
    y = _first_order(t, 180.0, 0.02) + np.where(t >= T_REQ + 0.2, amp * np.sin(2 * np.pi * f * t), 0.0)
    r = metrics.response(t, _noisy(t, y, 1.0), ref, T_REQ, None)  # the noise estimated from the standby
    assert r.steady_state_error_pct < 1.0
    assert r.ripple_pct == pytest.approx(amp / np.sqrt(2.0) / r.T_ss * 100.0, rel=0.02)
    calm = metrics.response(t, _noisy(t, _first_order(t, 180.0, 0.02), 1.0), ref, T_REQ, None, noise=1.0)
    assert not metrics.requirements(r, calm)["robustness"] and metrics.requirements(calm, calm)["robustness"]


def test_creep_is_the_standby_torque_before_the_request():
    t = _grid()
    ref = np.where(t >= T_REQ, 100.0, 0.0)
    # a contact jolt of 30 N m for 50 ms at 0.4 s, then 6 N m of creep until the request
    before = np.where((t >= 0.4) & (t < 0.45), 30.0, np.where(t >= 0.45, 6.0, 0.0))
    y = np.where(t >= T_REQ, _first_order(t, 100.0, 0.02), before)
    r = metrics.response(t, y, ref, T_REQ, None)
    assert r.creep_Nm == pytest.approx(6.0)
    assert r.standby_peak_Nm == pytest.approx((30.0 * 0.05 + 6.0 * 0.05) / metrics.PEAK_WINDOW, rel=0.02)
    assert metrics.requirements(r, r)["standby"]
    y2 = np.where(t < T_REQ, y + 5.0, y)
    assert not metrics.requirements(metrics.response(t, y2, ref, T_REQ, None), r)["standby"]


def test_input_at_max_is_the_share_of_the_window_at_the_top_of_the_range_short_of_the_request():
    t = _grid()
    ref = np.where(t >= T_REQ, 100.0, 0.0)
    # the input at its top (5 V) from 1.5 s on, and in the fill before the request (outside the window)
    u = np.where((t >= 1.5) | (t < 0.2), 5.0, 3.0)
    w = (T_REQ + metrics.STEADY_START, T_REQ + metrics.STEADY_END)  # 1.3 to 2.3 s: at the top for its last 0.8 s
    short = np.full_like(t, 90.0)
    assert metrics.input_at_max(t, u, 5.0, w, short, ref) == pytest.approx(80.0, abs=0.2)
    # the torque short of the request only from 2.1 s: at the top and short for the window's last 0.2 s
    assert metrics.input_at_max(t, u, 5.0, w, np.where(t >= 2.1, 90.0, 110.0), ref) == pytest.approx(20.0, abs=0.2)
    assert metrics.input_at_max(t, np.minimum(u, 4.99), 5.0, w, short, ref) == 0.0
    assert np.isnan(metrics.input_at_max(t, u, 5.0, (9.0, 9.5), short, ref))


def test_settled_t95_is_never_before_the_first_crossing():
    # a linear rise to 50 N m over 0.2 s whose sample at 95 % reads 1 N m low: the reading first reaches 95 % a
    # sample later, while the centred average the settled time is read on, looking ahead, enters the band on time
    t = _grid(2.5)
    y = 50.0 * np.clip((t - T_REQ) / 0.2, 0.0, 1.0)
    k = np.flatnonzero(y >= 0.95 * 50.0)[0]
    y[k] -= 1.0
    r = metrics.response(t, y, np.where(t >= T_REQ, 50.0, 0.0), T_REQ, None)
    assert r.t95_s == pytest.approx(t[k + 1] - T_REQ)
    assert r.t95_settled_s == r.t95_s
