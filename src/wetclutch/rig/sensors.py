"""The rig's sensor chain: what its data acquisition records of the true signals.

Per channel: a second-order Butterworth anti-alias low-pass, sampling, white noise,
quantisation, and for speed channels a dropout below a minimum speed. The sensor data in
:data:`DEFAULT_SENSORS` are plausible assumptions, not measured values: the study only
says that the rig's signals are low-pass filtered and that speed measurement is poor at
low speed.

The chain is written once, compiled (:func:`filter_sample`, :func:`reading`): the
closed launch loop runs it sample by sample, and :func:`measure` runs it over whole
arrays. Its settings per channel are a row of a flat table that this module names and
alone packs (:func:`sensor_table`).
"""

from __future__ import annotations

import zlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from types import MappingProxyType

import numpy as np
import pandas as pd
from numba import njit
from scipy import signal

from ..errors import ParameterError, WetclutchError
from .files import _float_column

@dataclass(frozen=True)
class SensorSpec:
    """How one channel is measured.

    Parameters
    ----------
    noise_std : float
        Standard deviation of the white Gaussian noise, in the channel's unit.
    cutoff_hz : float or None
        Cut-off of the 2nd-order Butterworth anti-alias filter (Hz); None: no filter.
    resolution : float
        Quantisation step in the channel's unit; 0: no quantisation.
    min_speed : float or None
        Speed channels (rad/s): below it a pulse-counting sensor sees no pulse within
        its gate time, so the measured speed reads 0.
    """

    noise_std: float = 0.0
    cutoff_hz: float | None = None
    resolution: float = 0.0
    min_speed: float | None = None

    def __post_init__(self) -> None:
        for name in ("noise_std", "resolution", "cutoff_hz", "min_speed"):
            v = getattr(self, name)
            positive = name == "cutoff_hz"
            if v is not None and not (np.isfinite(v) and (v > 0 if positive else v >= 0)):
                raise ParameterError(f"sensor {name} must be a finite number {'>' if positive else '>='} 0, got {v}")


#: Assumed sensors of the rig's channels (SI units; oil temperature in deg C).
DEFAULT_SENSORS: Mapping[str, SensorSpec] = MappingProxyType({
    "p_clutch": SensorSpec(noise_std=2e3, cutoff_hz=200.0, resolution=100.0),
    "T_r": SensorSpec(noise_std=0.5, cutoff_hz=100.0),
    **{w: SensorSpec(noise_std=0.05, cutoff_hz=50.0, min_speed=1.0)
       for w in ("omega_p", "omega_1", "omega_r", "omega_s")},
    "oil_temp": SensorSpec(noise_std=0.2, cutoff_hz=1.0),
})


# one row of the sensor table: the filter's second-order section (transposed direct form II),
# its steady-state initial conditions per unit input, and the reading's noise, resolution, dropout
B0, B1, B2, A1, A2, ZI0, ZI1, NOISE_STD, RESOLUTION, MIN_SPEED, HAS_FILTER = range(11)
N_SENSOR = 11

# IEEE arithmetic in the written order (no fused multiply-add): the filter equals scipy's sosfilt
_inline = njit(cache=True, error_model="numpy", _nrt=False, inline="always")


@lru_cache(maxsize=64)
def _section(cutoff_hz: float, rate_hz: float) -> tuple[float, ...]:
    """The second-order Butterworth section (b0, b1, b2, a1, a2) and its steady-state initial conditions per
    unit input: designed once per cut-off and rate, since every launch builds its sensor table."""
    # second-order sections are the same filter as butter+lfilter but stay accurate for
    # cut-offs far below the sampling rate
    sos = signal.butter(2, cutoff_hz, fs=rate_hz, output="sos")[0]
    return (*sos[:3], *sos[4:6], *signal.sosfilt_zi(sos[None, :])[0])


def sensor_table(channels: Sequence[str], rate_hz: float, sensors: Mapping[str, SensorSpec] | None = None,
                 noise: bool = True, noise_scale: float = 1.0) -> np.ndarray:
    """Rows of the sensor chain (see the slot names) for ``channels`` sampled at ``rate_hz``.

    A channel without a spec, or ``noise`` False (ideal sensors), gets a row of zeros: the
    true value, unfiltered and exact.
    """
    sensors = DEFAULT_SENSORS if sensors is None else sensors
    table = np.zeros((len(channels), N_SENSOR))
    if not noise:
        return table
    for c, name in enumerate(channels):
        spec = sensors.get(name)
        if spec is None:
            continue
        if spec.cutoff_hz is not None:
            if spec.cutoff_hz >= 0.5 * rate_hz:
                raise WetclutchError(f"cut-off {spec.cutoff_hz} Hz of '{name}' is above the Nyquist frequency of "
                                     f"{rate_hz:g} Hz sampling")
            table[c, B0:ZI1 + 1] = _section(spec.cutoff_hz, rate_hz)
            table[c, HAS_FILTER] = 1.0
        table[c, NOISE_STD] = spec.noise_std * noise_scale
        table[c, RESOLUTION] = spec.resolution
        table[c, MIN_SPEED] = spec.min_speed or 0.0
    return table


@_inline
def filter_sample(row, zf, v, first):
    """One sample through the channel's filter (state ``zf``, 2 values); ``first`` starts it in steady state
    at ``v``, as the rig's analog filter has been running long before a recording starts."""
    if row[HAS_FILTER] == 0.0:
        return v
    if first:
        zf[0] = row[ZI0] * v
        zf[1] = row[ZI1] * v
    y = row[B0] * v + zf[0]
    zf[0] = row[B1] * v - row[A1] * y + zf[1]
    zf[1] = row[B2] * v - row[A2] * y
    return y


@_inline
def reading(row, v, z):
    """What the DAQ records of the filtered value ``v``: plus ``z`` standard deviations of noise, quantised,
    and 0 for a speed below the sensor's minimum."""
    dropout = row[MIN_SPEED] > 0.0 and abs(v) < row[MIN_SPEED]
    if row[NOISE_STD] > 0.0:
        v += row[NOISE_STD] * z
    if row[RESOLUTION] > 0.0:
        v = np.round(v / row[RESOLUTION]) * row[RESOLUTION]
    return 0.0 if dropout else v


@njit(cache=True, error_model="numpy")
def _filtered(row, x):
    zf = np.zeros(2)
    out = np.empty(x.shape[0])
    for k in range(x.shape[0]):
        out[k] = filter_sample(row, zf, x[k], k == 0)
    return out


@njit(cache=True, error_model="numpy")
def _readings(row, v, z):
    out = np.empty(v.shape[0])
    for k in range(v.shape[0]):
        out[k] = reading(row, v[k], z[k])
    return out


def measure(truth: pd.DataFrame, rate_hz: float, sensors: Mapping[str, SensorSpec] | None = None,
            seed: int | None = 0, noise: bool = True) -> pd.DataFrame:
    """Measure true signals the way the rig's sensors and data acquisition would.

    Per channel with a :class:`SensorSpec`: the filter on the fine grid, sampling at
    ``rate_hz``, noise, quantisation, low-speed dropout (:func:`filter_sample`,
    :func:`reading`). Channels without a spec (e.g. the command ``u``) are only resampled.

    Parameters
    ----------
    truth : DataFrame
        ``time`` (s, uniform grid finer than ``1/rate_hz``) and one column per channel.
    rate_hz : float
        Sampling rate; samples are taken at ``time[0] + k / rate_hz``.
    sensors : mapping of str to SensorSpec, optional
        Sensor per channel; default :data:`DEFAULT_SENSORS`.
    seed : int or None
        Seed of the noise; None draws fresh noise.
    noise : bool
        False gives a clean, ideal measurement: resampling only (no filter, noise,
        quantisation or low-speed dropout).

    Returns
    -------
    DataFrame
        ``time`` first, then the channels of ``truth`` in their order, as float64.
    """
    t = _float_column(truth, "time", "true signals")
    dt = (t[-1] - t[0]) / (len(t) - 1) if len(t) > 1 else np.nan
    if not (np.isfinite(dt) and dt > 0 and np.all(np.abs(np.diff(t) - dt) <= 1e-6 * dt)):
        raise WetclutchError("true signals need a uniform, increasing time grid of at least 2 samples")
    if not (np.isfinite(rate_hz) and 0 < rate_hz <= (1 + 1e-9) / dt):
        raise WetclutchError(f"sampling rate {rate_hz} Hz must be positive and at most the grid rate {1 / dt:.6g} Hz")
    if seed is not None and not (isinstance(seed, (int, np.integer)) and seed >= 0):
        raise WetclutchError(f"noise seed must be a non-negative integer or None, got {seed!r}")
    names = [c for c in truth.columns if c != "time"]
    table = sensor_table(names, 1.0 / dt, sensors, noise)
    n_out = int(np.floor((t[-1] - t[0]) * rate_hz + 1e-9)) + 1
    times = t[0] + np.arange(n_out) / rate_hz
    ratio = 1.0 / (rate_hz * dt)
    stride = round(ratio)
    # When the sampling instants fall on the grid take the grid values themselves,
    # so that an ideal measurement equals the truth exactly, not up to rounding.
    aligned = abs(ratio - stride) <= 1e-9 * ratio and (n_out - 1) * stride < len(t)

    def resample(x: np.ndarray) -> np.ndarray:
        return x[np.arange(n_out) * stride].copy() if aligned else np.interp(times, t, x)

    out = {"time": times}
    for c, name in enumerate(names):
        row = table[c]
        x = _filtered(row, _float_column(truth, name, "true signals"))
        # one stream per channel, so adding a channel leaves the others' noise unchanged
        entropy = None if seed is None else [int(seed), zlib.crc32(name.encode())]
        z = np.random.default_rng(entropy).standard_normal(n_out) if row[NOISE_STD] > 0 else np.zeros(n_out)
        out[name] = _readings(row, resample(x), z)
    return pd.DataFrame(out)
