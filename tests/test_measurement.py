"""The sensor chain of the virtual rig and its measurement files."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from wetclutch.errors import ParameterError, WetclutchError
from wetclutch.rig.files import read_measurement, write_measurement
from wetclutch.rig.sensors import DEFAULT_SENSORS, SensorSpec, measure
from wetclutch.output import atomic_dir, write_csv


def grid(duration: float, dt: float) -> np.ndarray:
    return np.arange(round(duration / dt) + 1) * dt


# ---------------------------------------------------------------- filter


def test_filter_step_is_causal_butterworth():
    fc, t_step = 50.0, 0.05
    t = grid(0.2, 1e-5)
    truth = pd.DataFrame({"time": t, "x": (t >= t_step).astype(float)})
    # Sampling at the grid rate shows the filter output itself.
    y = measure(truth, 1e5, {"x": SensorSpec(cutoff_hz=fc)})["x"].to_numpy()
    tau = 1.0 / (2 * np.pi * fc)
    before = t < t_step
    assert np.all(y[before] == 0.0)  # causal: nothing before the step
    assert y[~before][0] < 0.01  # ... and no jump at it
    at = lambda dt: y[np.searchsorted(t, t_step + dt)]  # noqa: E731
    assert 0.63 <= at(2 * tau) <= 1.0
    assert at(5 * tau) >= 0.99
    overshoot = y.max() - 1.0
    assert 0.03 < overshoot < 0.055  # 2nd-order Butterworth: 4.3 %
    assert abs(y[-1] - 1.0) < 1e-3


def test_filter_starts_in_steady_state():
    t = grid(0.5, 1e-4)
    truth = pd.DataFrame({"time": t, "oil_temp": np.full(t.size, 80.0)})
    sensors = {"oil_temp": SensorSpec(cutoff_hz=1.0)}
    y = measure(truth, 100.0, sensors)["oil_temp"].to_numpy()
    np.testing.assert_allclose(y, 80.0, rtol=1e-9)


def test_cutoff_above_nyquist_and_bad_spec_are_rejected():
    t = grid(0.1, 1e-3)
    truth = pd.DataFrame({"time": t, "x": t})
    with pytest.raises(WetclutchError, match="Nyquist"):
        measure(truth, 100.0, {"x": SensorSpec(cutoff_hz=600.0)})
    with pytest.raises(ParameterError):
        SensorSpec(noise_std=-1.0)
    with pytest.raises(ParameterError):
        SensorSpec(cutoff_hz=0.0)


# ---------------------------------------------------------------- resampling


def test_resampling_on_the_grid_takes_grid_values():
    t = grid(1.0, 1e-4)
    truth = pd.DataFrame({"time": t, "u": np.sin(2 * np.pi * 3 * t), "omega_p": 5 + t})
    m = measure(truth, 1000.0, noise=False)
    assert list(m.columns) == ["time", "u", "omega_p"]
    assert len(m) == 1001
    np.testing.assert_allclose(m["time"], np.arange(1001) / 1000.0, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(m["u"], truth["u"].to_numpy()[::10])
    np.testing.assert_array_equal(m["omega_p"], truth["omega_p"].to_numpy()[::10])


def test_resampling_off_the_grid_interpolates():
    t = 0.5 + grid(1.0, 1e-4)
    truth = pd.DataFrame({"time": t, "u": 1.0 + 2.0 * t})
    m = measure(truth, 300.0)  # `u` has no sensor: resampled unchanged even with noise
    expected_t = 0.5 + np.arange(301) / 300.0
    np.testing.assert_allclose(m["time"], expected_t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(m["u"], 1.0 + 2.0 * expected_t, rtol=0, atol=1e-12)


def test_bad_grid_or_rate_is_rejected():
    t = grid(0.1, 1e-3)
    with pytest.raises(WetclutchError, match="uniform"):
        measure(pd.DataFrame({"time": t**2, "x": t}), 100.0)
    with pytest.raises(WetclutchError, match="rate"):
        measure(pd.DataFrame({"time": t, "x": t}), 1e4)
    with pytest.raises(WetclutchError, match="time"):
        measure(pd.DataFrame({"t": t, "x": t}), 100.0)


# ---------------------------------------------------------------- noise, quantisation, speed


def noisy_truth() -> pd.DataFrame:
    t = grid(2.0, 1e-4)
    return pd.DataFrame({"time": t, "p": np.full(t.size, 1e5)})


def test_noise_has_requested_std_and_is_seeded():
    sensors = {"p": SensorSpec(noise_std=2e3)}
    a = measure(noisy_truth(), 1e4, sensors, seed=7)["p"].to_numpy()
    assert a.size == 20001
    assert 1800 < np.std(a) < 2200
    assert abs(np.mean(a) - 1e5) < 5 * 2e3 / np.sqrt(a.size)
    np.testing.assert_array_equal(a, measure(noisy_truth(), 1e4, sensors, seed=7)["p"])
    assert not np.array_equal(a, measure(noisy_truth(), 1e4, sensors, seed=8)["p"].to_numpy())


def test_no_noise_returns_resampled_truth_exactly():
    t = grid(0.5, 1e-4)
    truth = pd.DataFrame({"time": t, **{name: 3.0 + np.sin(40 * t + i) for i, name in enumerate(DEFAULT_SENSORS)}})
    m = measure(truth, 1000.0, noise=False)
    for name in DEFAULT_SENSORS:
        np.testing.assert_array_equal(m[name], truth[name].to_numpy()[::10])


def test_quantisation_uses_resolution():
    t = grid(0.1, 1e-4)
    truth = pd.DataFrame({"time": t, "p_clutch": 3e5 + 1e4 * np.sin(50 * t)})
    p = measure(truth, 1000.0)["p_clutch"].to_numpy()
    np.testing.assert_allclose(p / 100.0, np.round(p / 100.0), rtol=0, atol=1e-9)
    assert np.unique(p).size > 10


def test_speed_below_min_speed_reads_zero():
    t = grid(4.0, 1e-4)
    truth = pd.DataFrame({"time": t, "omega_r": -3.0 + 1.5 * t})
    m = measure(truth, 1000.0, seed=3)
    true = -3.0 + 1.5 * m["time"].to_numpy()
    speed = m["omega_r"].to_numpy()
    slow = np.abs(true) < 0.9
    assert slow.sum() > 100
    assert np.all(speed[slow] == 0.0)
    fast = np.abs(true) > 1.2
    assert np.all(speed[fast] != 0.0)
    assert np.max(np.abs(speed[fast] - true[fast])) < 0.4


# ---------------------------------------------------------------- files


@pytest.fixture(scope="module")
def written(tmp_path_factory) -> tuple[Path, pd.DataFrame, dict[str, str]]:
    rng = np.random.default_rng(1)
    n = 500
    frame = pd.DataFrame({
        "p_clutch": rng.normal(3e5, 1e4, n),
        "time": np.arange(n) / 1000.0,  # not first: the writer puts it first
        "omega_p": rng.normal(0, 1e-3, n) * 10.0 ** rng.integers(-8, 8, n),
        "u": np.zeros(n),
    })
    units = {"time": "s", "p_clutch": "Pa", "omega_p": "rad/s"}
    target = tmp_path_factory.mktemp("meas") / "run"
    with atomic_dir(target) as tmp:
        write_measurement(tmp, frame, units, {"rate_hz": 1000.0, "seed": 1})
    return target, frame[["time", "p_clutch", "omega_p", "u"]], units


def test_writer_writes_all_files(written):
    target, _, units = written
    assert sorted(p.name for p in target.iterdir()) == ["measured.csv", "measured.mat", "measured.mf4", "meta.json"]
    meta = json.loads((target / "meta.json").read_text())
    assert meta["rate_hz"] == 1000.0 and meta["units"] == units


@pytest.mark.parametrize("ext", ["csv", "mf4", "mat"])
def test_round_trip(written, ext):
    target, frame, units = written
    back, back_units = read_measurement(target / f"measured.{ext}")
    assert list(back.columns) == list(frame.columns)
    assert all(back.dtypes == np.float64)
    if ext == "csv":
        np.testing.assert_allclose(back.to_numpy(), frame.to_numpy(), rtol=1e-9, atol=0)
    else:
        np.testing.assert_array_equal(back.to_numpy(), frame.to_numpy())
        assert back_units == units


def test_writer_rejects_bad_names_and_missing_directory(tmp_path):
    frame = pd.DataFrame({"time": [0.0, 1.0], "bad name": [1.0, 2.0]})
    with pytest.raises(WetclutchError, match="bad name"):
        write_measurement(tmp_path, frame, {}, {})
    with pytest.raises(WetclutchError, match="no channels"):
        write_measurement(tmp_path, frame[["time"]], {}, {})
    with pytest.raises(WetclutchError, match="does not exist"):
        write_measurement(tmp_path / "nope", frame.rename(columns={"bad name": "x"}), {}, {})


def assert_one_line_error(path: Path) -> None:
    with pytest.raises(WetclutchError) as info:
        read_measurement(path)
    message = str(info.value)
    assert str(path) in message
    assert "\n" not in message and "\r" not in message


@pytest.mark.parametrize("name", ["missing.csv", "missing.mf4", "missing.mat", "data.xyz"])
def test_missing_or_unknown_file(tmp_path, name):
    assert_one_line_error(tmp_path / name)


def test_files_without_valid_time(tmp_path):
    from scipy.io import savemat

    (tmp_path / "no_time.csv").write_text("t,x\n0,1\n1,2\n")
    (tmp_path / "backwards.csv").write_text("time,x\n1,1\n0,2\n")
    (tmp_path / "text.csv").write_text("time,x\n0,a\n1,b\n")
    savemat(tmp_path / "no_time.mat", {"x": np.arange(3.0)})
    savemat(tmp_path / "short.mat", {"time": np.arange(3.0), "x": np.arange(2.0)})
    for name in ["no_time.csv", "backwards.csv", "text.csv", "no_time.mat", "short.mat"]:
        assert_one_line_error(tmp_path / name)


@pytest.mark.filterwarnings("error::pytest.PytestUnraisableExceptionWarning")
@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(ext=st.sampled_from(["csv", "mf4", "mat"]), cut=st.floats(0.0, 1.0), junk=st.binary(max_size=3000),
       mode=st.sampled_from(["random", "truncated", "truncated+junk"]))
def test_corrupt_files_raise_only_wetclutch_error(written, tmp_path_factory, ext, cut, junk, mode):
    good = (written[0] / f"measured.{ext}").read_bytes()
    prefix = good[: int(cut * len(good))]
    content = {"random": junk, "truncated": prefix, "truncated+junk": prefix + junk}[mode]
    path = tmp_path_factory.mktemp("corrupt") / f"bad.{ext}"
    path.write_bytes(content)
    try:
        frame, _ = read_measurement(path)
    except WetclutchError as err:
        assert str(path) in str(err) and "\n" not in str(err)
    else:  # a file cut at a harmless place may still read: then it must be sane
        assert frame.columns[0] == "time" and len(frame) > 0
        assert np.all(np.diff(frame["time"].to_numpy()) > 0)


@given(values=st.lists(st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64), min_size=3, max_size=3),
                       min_size=1, max_size=30),
       flags=st.lists(st.integers(-128, 127), min_size=30, max_size=30), digits=st.sampled_from([6, 8, 10, 17]))
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_write_csv_writes_what_pandas_writes(tmp_path, values, flags, digits):
    frame = pd.DataFrame(values, columns=["time", "p_clutch", "T_r"])
    frame["locked"] = np.array(flags[: len(frame)], dtype=np.int8)
    write_csv(frame, tmp_path / "fast.csv", digits)
    frame.to_csv(tmp_path / "pandas.csv", index=False, float_format=f"%.{digits}g")
    assert (tmp_path / "fast.csv").read_text() == (tmp_path / "pandas.csv").read_text()
