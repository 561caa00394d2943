"""The virtual rig's sensor chain and its measurement files.

:func:`measure` turns noise-free true signals on a fine uniform grid into what a
rig's data acquisition records: analog anti-alias low-pass filter, sampling,
white noise, quantisation. :func:`write_measurement` stores that as CSV, MDF 4
(``.mf4``) and MATLAB (``.mat``) files; :func:`read_measurement` reads them back.
The sensor data in :data:`DEFAULT_SENSORS` are plausible assumptions, not measured
values: the study only says that the rig's signals are low-pass filtered and that
speed measurement is poor at low speed.
"""

from __future__ import annotations

import gc
import re
import sys
import zlib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
import pandas as pd
from scipy import io as sio
from scipy import signal

from .errors import ParameterError, WetclutchError
from .output import write_json


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


def _float_column(frame: pd.DataFrame, name: str, what: str) -> np.ndarray:
    try:
        return np.asarray(pd.to_numeric(frame[name], errors="raise"), dtype=np.float64)
    except (KeyError, TypeError, ValueError):
        raise WetclutchError(_one_line(f"{what}: column '{name}' is missing or not numeric")) from None


def measure(truth: pd.DataFrame, rate_hz: float, sensors: Mapping[str, SensorSpec] | None = None,
            seed: int | None = 0, noise: bool = True) -> pd.DataFrame:
    """Measure true signals the way the rig's sensors and data acquisition would.

    Per channel with a :class:`SensorSpec`: causal Butterworth filter on the fine
    grid, sampling at ``rate_hz``, white noise, quantisation, low-speed dropout.
    Channels without a spec (e.g. the command ``u``) are only resampled.

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
    sensors = DEFAULT_SENSORS if sensors is None else sensors
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
    for name in (c for c in truth.columns if c != "time"):
        x = _float_column(truth, name, "true signals")
        spec = sensors.get(name)
        if spec is None or not noise:
            out[name] = resample(x)  # ideal measurement, or a signal the rig sets itself
            continue
        if spec.cutoff_hz is not None:
            if spec.cutoff_hz >= 0.5 / dt:
                raise WetclutchError(f"cut-off {spec.cutoff_hz} Hz of '{name}' is above the grid's Nyquist frequency")
            # Causal, like the analog filter in the rig; second-order sections are the
            # same filter as butter+lfilter but stay accurate for cut-offs far below
            # the grid rate. Start in steady state at the first value: the real filter
            # has been running long before the recording starts.
            sos = signal.butter(2, spec.cutoff_hz, fs=1.0 / dt, output="sos")
            x, _ = signal.sosfilt(sos, x, zi=signal.sosfilt_zi(sos) * x[0])
        y = resample(x)
        dropout = np.abs(y) < spec.min_speed if spec.min_speed else None
        if spec.noise_std > 0:
            # One stream per channel, so adding a channel leaves the others' noise unchanged.
            entropy = None if seed is None else [int(seed), zlib.crc32(name.encode())]
            y = y + np.random.default_rng(entropy).normal(0.0, spec.noise_std, n_out)
        if spec.resolution > 0:
            y = np.round(y / spec.resolution) * spec.resolution
        if dropout is not None:
            y[dropout] = 0.0
        out[name] = y
    return pd.DataFrame(out)


def write_measurement(directory: Path, measured: pd.DataFrame, units: dict[str, str], meta: dict[str, Any]) -> None:
    """Write a measurement into the existing ``directory`` in all file formats.

    Writes ``measured.csv``, ``measured.mf4`` (MDF 4.10, one channel group with
    ``time`` as master), ``measured.mat`` (one float64 vector per column plus a
    ``units`` struct) and ``meta.json`` (``meta`` plus the units under ``units``).
    Wrap the call in :func:`wetclutch.output.atomic_dir` to make it atomic.

    Parameters
    ----------
    directory : Path
    measured : DataFrame
        ``time`` plus numeric channels; names must be MATLAB identifiers other than ``units``.
    units : dict of str to str
        Unit per column; missing columns are written without a unit.
    meta : dict
        Description of the run, written to ``meta.json``.
    """
    from asammdf import MDF, Signal  # imported here: asammdf is slow to import
    if not (directory := Path(directory)).is_dir():
        raise WetclutchError(f"measurement directory '{directory}' does not exist")
    names = ["time"] + [c for c in measured.columns if c != "time"]
    if len(names) < 2:  # MDF has no place for a master channel alone
        raise WetclutchError("measurement has no channels besides 'time'")
    for c in names:
        if not isinstance(c, str) or not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]{0,62}", c) or c == "units":
            raise WetclutchError(f"channel name {c!r} cannot be written (must be a MATLAB name other than 'units')")
    data = {c: _float_column(measured, c, "measurement") for c in names}
    unit = {c: str(units[c]) for c in names if units.get(c)}
    try:
        pd.DataFrame(data).to_csv(directory / "measured.csv", index=False, float_format="%.10g")
        with MDF(version="4.10") as mdf:
            mdf.append([Signal(data[c], data["time"], name=c, unit=unit.get(c, "")) for c in names[1:]])
            mdf.save(directory / "measured.mf4", overwrite=True)
        sio.savemat(directory / "measured.mat", {**data, "units": unit}, do_compression=True, oned_as="column")
        write_json(directory / "meta.json", {**meta, "units": unit})
    except OSError as err:
        raise WetclutchError(f"cannot write measurement to '{directory}': {err.strerror or err}") from None


def _one_line(text: object) -> str:  # parser messages may span lines; errors are shown as one
    return re.sub(r"\s*[\r\n]+\s*", " ", str(text)).strip()


def _read_csv(path: Path) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    frame = pd.read_csv(path)
    return {str(c): _float_column(frame, c, f"measurement file '{path}'") for c in frame.columns}, {}


def _read_mat(path: Path) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    raw = sio.loadmat(path, simplify_cells=True)
    units = raw.pop("units", {})
    units = {str(k): v for k, v in units.items() if isinstance(v, str)} if isinstance(units, dict) else {}
    columns = {}
    for name, value in raw.items():
        if isinstance(value, dict) and "X" in value and "Y" in value:
            return _dspace_columns(value)
        value = np.asarray(value)
        # Skip MATLAB's bookkeeping entries and anything that is not one numeric vector.
        if not name.startswith("__") and value.dtype.kind in "biuf" and value.squeeze().ndim <= 1:
            columns[name] = np.atleast_1d(value.squeeze()).astype(np.float64)
    return columns, units


def _dspace_columns(rec: dict[str, Any]) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """A dSPACE recording: struct with ``X`` (time base) and ``Y`` (array of structs ``Name``, ``Data``, ``Unit``)."""
    x = rec["X"][0] if isinstance(rec["X"], list) else rec["X"]
    ys = rec["Y"] if isinstance(rec["Y"], list) else [rec["Y"]]
    columns = {"time": np.atleast_1d(np.asarray(x["Data"], dtype=np.float64).squeeze())}
    units = {"time": str(x.get("Unit") or "s")}
    for y in ys:
        # ControlDesk names are block paths ("Model Root/ctrl/p_clutch"); the last part names the signal
        name = str(y["Name"]).strip().strip('"').split("/")[-1]
        data = np.asarray(y["Data"])
        if data.dtype.kind in "biuf" and data.squeeze().ndim <= 1 and name not in columns:
            columns[name] = np.atleast_1d(data.squeeze()).astype(np.float64)
            if isinstance(y.get("Unit"), str) and y["Unit"]:
                units[name] = y["Unit"]
    return columns, units


def _read_mdf(path: Path) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    from asammdf import MDF  # imported here: asammdf is slow to import

    with open(path, "rb") as stream, MDF(stream) as mdf:
        # The first channel group with a master channel supplies the time base;
        # channels on other rasters are left for a later reader with channel maps.
        group = next((g for g in range(len(mdf.groups)) if mdf.masters_db.get(g) is not None), None)
        if group is None:
            return {}, {}
        columns, units = {"time": np.asarray(mdf.get_master(group), dtype=np.float64)}, {"time": "s"}
        for sig in mdf.iter_channels(skip_master=True):
            samples = np.asarray(sig.samples)
            wanted = sig.group_index == group and sig.name not in columns
            if wanted and samples.dtype.kind in "biuf" and samples.ndim == 1:
                columns[sig.name] = samples.astype(np.float64)
                if sig.unit:
                    units[sig.name] = str(sig.unit)
    return columns, units


_READERS = {".csv": _read_csv, ".mat": _read_mat, ".mf4": _read_mdf, ".mdf": _read_mdf}


def read_columns(path: str | Path) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """Read every numeric channel of a measurement file, unchecked.

    CSV, MDF 4 (``.mf4``/``.mdf``; the first channel group with a master channel,
    which is returned as ``time``) and MATLAB files: one vector per variable, or a
    dSPACE recording (a struct with ``X`` and ``Y``).

    Returns
    -------
    dict of str to ndarray
        Channel name -> float64 samples, as stored (lengths may differ).
    dict of str to str
        Unit per channel, as far as the file records them (none for CSV).

    Raises
    ------
    WetclutchError
        The file is missing, of unknown type, unreadable or corrupt.
    """
    path = Path(path)
    reader = _READERS.get(path.suffix.lower())
    if reader is None:
        raise _fail(path, "unknown type (use .csv, .mf4, .mdf or .mat)")
    if not path.is_file():
        raise _fail(path, "not found")
    problem, previous = None, sys.unraisablehook
    # asammdf's MDF.__del__ fails on objects whose constructor raised, printing a traceback a user
    # would take for a crash. Such objects sit in reference cycles, so collect them here, under a
    # hook that hides that; freezing all older objects keeps the collection cheap.
    sys.unraisablehook = lambda u: None if getattr(u.object, "__module__", "").startswith("asammdf") else previous(u)
    if mdf := reader is _read_mdf:
        gc.freeze()
    try:
        try:
            return reader(path)
        except WetclutchError:
            raise
        except Exception as err:  # parsers of corrupt files raise almost anything
            problem = f"cannot read it ({type(err).__name__}: {_one_line(err)[:200]})"
        if mdf:
            gc.collect()
    finally:
        if mdf:
            gc.unfreeze()
        sys.unraisablehook = previous
    raise _fail(path, problem)


def _fail(path: Path, why: str) -> WetclutchError:
    return WetclutchError(_one_line(f"measurement file '{path}': {why}"))


def read_measurement(path: str | Path) -> tuple[pd.DataFrame, dict[str, str]]:
    """Read a measurement file as written by :func:`write_measurement`.

    Parameters
    ----------
    path : str or Path
        A ``.csv``, ``.mf4``/``.mdf`` or ``.mat`` file.

    Returns
    -------
    DataFrame
        ``time`` first, then the channels as float64.
    dict of str to str
        Unit per channel, as far as the file records them (none for CSV).

    Raises
    ------
    WetclutchError
        The file is missing, unreadable or corrupt, or has no valid time channel.
    """
    path = Path(path)
    columns, units = read_columns(path)
    time = columns.pop("time", None)
    if time is None:
        raise _fail(path, "no time channel")
    if len(time) == 0 or not np.all(np.isfinite(time)) or np.any(np.diff(time) <= 0):
        raise _fail(path, "time is empty, not finite or not increasing")
    for name, values in columns.items():
        if len(values) != len(time):
            raise _fail(path, f"channel '{name}' has {len(values)} samples, time has {len(time)}")
    return pd.DataFrame({"time": time, **columns}), units
