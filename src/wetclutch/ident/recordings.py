"""Measurement files from any rig, as checked SI recordings for identification.

:func:`load` reads a CSV, MDF 4 or MATLAB file (dSPACE recordings included, see
:func:`wetclutch.rig.files.read_columns`), renames and rescales its channels
with a channel map, checks them and tells which experiment the file holds.

A channel map is a TOML file, one table (or one string) per channel of the rig::

    [p_clutch]
    name = "P_Kupplung"     # the channel's name in the file
    unit = "bar"            # its unit (overrides the file's own)

    omega_p = "n_prim"      # rename only; the unit comes from the file

A table needs ``name`` and may have ``unit``; two channels cannot read one column.

Units are converted to SI (command ``u`` in V or duty; ``oil_temp`` in C) here
and nowhere else. A channel's unit is taken from the map, else from the file,
else from ``meta.json`` beside the file, else the rig's SI unit is assumed.

A file's channels need not all be readable: a column of text or an MDF channel on a raster that does not cover the
record is left out unless the map (or the rig's naming) asks for it. Lost samples (up to :data:`GAP_MAX_SAMPLES` in
a row) and a jittery clock are interpolated onto a uniform grid; missing values (NaN) are refused.
"""

from __future__ import annotations

import json
import os
import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import WetclutchError, kind_of, read_text
from ..physics.actuator import CONFIGS
from ..rig.experiments import EXPERIMENTS, MEASURED_UNITS
from ..rig.files import read_columns

REQUIRED = ("time", "u", "p_clutch", "oil_temp")
#: the driveline channels, present together (clutch runs) or not at all (valve-only runs)
DRIVELINE = ("T_r", "omega_p", "omega_1", "omega_r")
OPTIONAL = ("omega_s",)
CHANNELS = REQUIRED + DRIVELINE + OPTIONAL
#: the keys of a channel map's table: ``name`` (required) and ``unit``
MAP_KEYS = ("name", "unit")

_QUANTITY = {"time": "time", "u": "command", "p_clutch": "pressure", "T_r": "torque", "oil_temp": "temperature",
             **{w: "speed" for w in ("omega_p", "omega_1", "omega_r", "omega_s")}}

#: unit (lower case, spaces removed) -> (factor, offset) to SI, per quantity: si = factor * x + offset
UNITS: Mapping[str, Mapping[str, tuple[float, float]]] = {
    "time": {"s": (1.0, 0.0), "ms": (1e-3, 0.0), "us": (1e-6, 0.0), "min": (60.0, 0.0)},
    "pressure": {"pa": (1.0, 0.0), "kpa": (1e3, 0.0), "mpa": (1e6, 0.0), "bar": (1e5, 0.0), "mbar": (1e2, 0.0),
                 "psi": (6894.757293168, 0.0)},
    "torque": {"nm": (1.0, 0.0), "n*m": (1.0, 0.0), "n.m": (1.0, 0.0), "n·m": (1.0, 0.0), "knm": (1e3, 0.0)},
    "speed": {"rad/s": (1.0, 0.0), "rpm": (2 * math.pi / 60, 0.0), "1/min": (2 * math.pi / 60, 0.0),
              "u/min": (2 * math.pi / 60, 0.0), "rev/s": (2 * math.pi, 0.0), "deg/s": (math.pi / 180, 0.0)},
    "temperature": {"c": (1.0, 0.0), "degc": (1.0, 0.0), "°c": (1.0, 0.0), "k": (1.0, -273.15),
                    "degf": (5 / 9, -160 / 9), "°f": (5 / 9, -160 / 9)},
    "command": {"v": (1.0, 0.0), "mv": (1e-3, 0.0), "duty": (1.0, 0.0), "-": (1.0, 0.0), "%": (0.01, 0.0)},
}
_PWM_UNITS = {"duty", "-", "%"}

#: sample rates identification can use (Hz). Below, the onset's stroke line and dead time have too few samples; above,
#: no clutch rig samples: outside the two a time column's unit is wrong (ms read as s, or s as ms)
RATE_MIN_HZ, RATE_MAX_HZ = 50.0, 200e3
#: the shortest record (s) with anything to identify (a step needs the second before its command)
DURATION_MIN_S = 0.1
#: lost samples in a row that are interpolated; a longer gap in the time stamps is refused: filled with a straight line
#: it would pass for measured pressure and torque
GAP_MAX_SAMPLES = 2
#: a record whose clock starts before 0 or this late (s; a DAQ's running or absolute clock) is counted from its first
#: sample: the models that replay a command start it at time 0
CLOCK_START_MAX_S = 60.0


@dataclass
class Recording:
    """One checked measurement file in SI units (``u`` in V or duty, ``oil_temp`` in C).

    Attributes
    ----------
    path : Path
    data : dict of str to ndarray
        ``time`` and the channels of :data:`CHANNELS` the file has, on a uniform time grid. ``time`` is the file's,
        or counted from its first sample where the file's clock starts before 0 or after :data:`CLOCK_START_MAX_S`.
    experiment : str
        One of :data:`wetclutch.rig.experiments.EXPERIMENTS`, from ``meta.json`` or detected.
    config : str
        ``clutch`` (driveline channels present) or ``valve-only``.
    input_mode : str
        ``dc`` (``u`` in V) or ``pwm`` (``u`` a duty cycle).
    meta : dict
        ``meta.json`` beside the file, if any.
    """

    path: Path
    data: dict[str, np.ndarray]
    experiment: str
    config: str
    input_mode: str
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def t(self) -> np.ndarray:
        return self.data["time"]

    @property
    def dt(self) -> float:
        return float(self.t[1] - self.t[0])

    @property
    def oil_temp_C(self) -> float:
        return float(np.median(self.data["oil_temp"]))


#: two recordings are the same if each channel both have agrees to this fraction of its largest magnitude: a CSV's
#: printed digits or an MDF's single-precision channel round at about 1e-7 of it, two runs' sensor noise and
#: quantisation differ far above it
SAME_TOLERANCE = 1e-5


def same_recording(a: Recording, b: Recording) -> bool:
    """Whether ``a`` and ``b`` hold the same recording, whatever their files' formats and units.

    Parameters
    ----------
    a, b : Recording
        Loaded (SI) recordings.

    Returns
    -------
    bool
        True if they have as many samples, the same time steps from their first sample, and every channel that both
        have agrees within :data:`SAME_TOLERANCE` of the channel's largest magnitude.
    """
    if a.t.size != b.t.size:
        return False
    for ch in sorted(set(a.data) & set(b.data)):
        x, y = (a.t - a.t[0], b.t - b.t[0]) if ch == "time" else (a.data[ch], b.data[ch])
        scale = max(float(np.max(np.abs(x))), float(np.max(np.abs(y))))
        if np.any(np.abs(x - y) > SAME_TOLERANCE * scale):
            return False
    return True


def read_channel_map(path: str | Path | None) -> dict[str, dict[str, str]]:
    """Read a channel map (see the module docstring): canonical channel -> {name, unit}."""
    if path is None:
        return {}
    path = Path(path)
    try:
        raw = tomllib.loads(read_text(path, "channel map"))
    except tomllib.TOMLDecodeError as err:
        raise WetclutchError(f"channel map '{path}' is not valid TOML: {str(err).splitlines()[0]}") from None
    out: dict[str, dict[str, str]] = {}
    for key, entry in raw.items():
        if key not in CHANNELS:
            raise WetclutchError(f"channel map '{path}': unknown channel '{key}' (choose from {', '.join(CHANNELS)})")
        entry = {"name": entry} if isinstance(entry, str) else entry
        where = f"channel map '{path}': '{key}'"
        if not isinstance(entry, dict):
            raise WetclutchError(f"{where} must be a string (the channel's name) or a table with name and unit")
        unknown = sorted(set(entry) - set(MAP_KEYS))
        if unknown:
            raise WetclutchError(f"{where} has unknown key '{unknown[0]}' (known: {', '.join(MAP_KEYS)})")
        # a unit without a name would rescale whatever column is named like the channel: say so here, not as
        # an implausible identification later
        if "name" not in entry:
            raise WetclutchError(f"{where} has no key 'name' (the channel's name in the file)")
        bad = next((k for k in MAP_KEYS if k in entry and not isinstance(entry[k], str)), None)
        if bad is not None:
            raise WetclutchError(f"{where}.{bad} must be a string (got {entry[bad]!r})")
        if not entry["name"].strip():
            raise WetclutchError(f"{where}.name must not be empty")
        if "unit" in entry:
            _conversion(entry["unit"], key, f"channel map '{path}'")
        out[key] = entry
    # a channel not in the map keeps its own name: two channels must not read one column
    reads: dict[str, str] = {}
    for ch in CHANNELS:
        name = out.get(ch, {}).get("name", ch)
        if name in reads:
            first, second = sorted((reads[name], ch), key=lambda c: c not in out)
            raise WetclutchError(f"channel map '{path}': '{first}' and '{second}' both read column '{name}'"
                                 + (f" ('{second}', not in the map, reads the column of its own name)"
                                    if second not in out else ""))
        reads[name] = ch
    return out


def _conversion(unit: str, channel: str, where: str) -> tuple[float, float]:
    table = UNITS[_QUANTITY[channel]]
    key = unit.strip().lower().replace(" ", "")
    if key not in table:
        raise WetclutchError(f"{where}: channel '{channel}' has unknown unit '{unit}' "
                             f"(known: {', '.join(sorted(table))})")
    return table[key]


def _read_meta(path: Path) -> dict[str, Any]:
    meta_path = path.parent / "meta.json"
    if not meta_path.is_file():
        return {}
    try:
        meta = json.loads(meta_path.read_text())
    except (OSError, ValueError) as err:
        raise WetclutchError(f"cannot read '{meta_path}' beside '{path}': {str(err).splitlines()[0]}") from None
    if not isinstance(meta, dict):
        raise WetclutchError(f"'{meta_path}' beside '{path}' is not a JSON object")
    return meta


def load(path: str | Path, channel_map: Mapping[str, Mapping[str, str]] | None = None) -> Recording:
    """Read, map, convert and check one measurement file.

    Parameters
    ----------
    path : str or Path
        ``.csv``, ``.mf4``/``.mdf`` or ``.mat``.
    channel_map : mapping, optional
        From :func:`read_channel_map`.

    Returns
    -------
    Recording

    Raises
    ------
    WetclutchError
        One line naming the file (and channel): unreadable file, missing channel (with the columns the file has),
        unknown unit, non-finite samples, time stamps not increasing, a gap of more than :data:`GAP_MAX_SAMPLES`
        samples, a sample rate outside :data:`RATE_MIN_HZ` .. :data:`RATE_MAX_HZ` or a record shorter than
        :data:`DURATION_MIN_S` (both a time column in the wrong unit).
    """
    if not isinstance(path, (str, os.PathLike)):
        raise WetclutchError(f"path must be a measurement file's path (str or pathlib.Path), not {kind_of(path)}")
    if channel_map is not None and not isinstance(channel_map, Mapping):
        raise WetclutchError(f"channel_map must be a mapping of channel -> {{name, unit}} (read_channel_map(path)), "
                             f"not {kind_of(channel_map)}")
    path = Path(path)
    cmap = dict(channel_map or {})
    # the columns the map names: another column the reader cannot read (text, another raster) is no reason to refuse
    columns, file_units = read_columns(path, {cmap.get(ch, {}).get("name", ch) for ch in CHANNELS})
    meta = _read_meta(path)
    settings = meta.get("settings") if isinstance(meta.get("settings"), dict) else {}
    meta_units = meta.get("units") if isinstance(meta.get("units"), dict) else {}
    fail = lambda why: WetclutchError(f"measurement file '{path}': {why}")  # noqa: E731

    data: dict[str, np.ndarray] = {}
    command_unit = ""
    for ch in CHANNELS:
        entry = cmap.get(ch, {})
        name = entry.get("name", ch)
        if name not in columns:
            if ch in REQUIRED:
                raise fail(f"required channel '{ch}'" + (f" (mapped to '{name}')" if name != ch else "")
                           + f" missing ({_found(columns)})")
            continue
        default = MEASURED_UNITS[ch] if ch != "u" else ("duty" if settings.get("input_mode") == "pwm" else "V")
        unit = entry.get("unit") or file_units.get(name) or meta_units.get(name) or default
        factor, offset = _conversion(str(unit), ch, f"measurement file '{path}'")
        if ch == "u":
            command_unit = str(unit).strip().lower()
        data[ch] = factor * np.asarray(columns[name], dtype=np.float64) + offset
    present = [c for c in DRIVELINE if c in data]
    if 0 < len(present) < len(DRIVELINE):
        missing = next(c for c in DRIVELINE if c not in data)
        raise fail(f"channel '{missing}' missing (a clutch run needs all of {', '.join(DRIVELINE)})")
    _check(data, fail)
    t = data["time"]
    if t[0] < 0.0 or t[0] > CLOCK_START_MAX_S:
        data["time"] = t = t - t[0]
    steps = np.diff(t)
    dt = float(np.median(steps))
    if np.max(np.abs(steps - dt)) > 0.01 * dt:
        # estimators filter and take spectra on a uniform grid; a jittery DAQ clock is resampled
        # (the tolerance keeps the last sample where the span is a whole number of steps but for rounding)
        grid = t[0] + dt * np.arange(int((t[-1] - t[0]) / dt + 1e-6) + 1)
        data = {c: grid if c == "time" else np.interp(grid, t, x) for c, x in data.items()}
    config = settings.get("config") if settings.get("config") in CONFIGS else ("clutch" if present else "valve-only")
    if config == "clutch" and not present:
        raise fail(f"channel '{DRIVELINE[0]}' missing (meta.json says it is a clutch run)")
    input_mode = "pwm" if command_unit in _PWM_UNITS else "dc"
    experiment = meta.get("experiment")
    if experiment not in EXPERIMENTS:
        experiment = detect_experiment(data["time"], data["u"], str(path))
    return Recording(path, data, str(experiment), config, input_mode, meta)


def _check(data: dict[str, np.ndarray], fail: Any) -> None:
    t = data["time"]
    n = len(t)
    for ch, x in data.items():
        if len(x) != n:
            raise fail(f"channel '{ch}' has {len(x)} samples, time has {n}")
        bad = ~np.isfinite(x)
        if bad.any():
            i = int(np.argmax(bad))
            where = f"sample {i}" if ch == "time" or not np.isfinite(t[i]) else f"t = {t[i]:.6g} s"
            k = int(bad.sum())
            raise fail(f"channel '{ch}' has {k} non-finite sample{'' if k == 1 else 's'} (NaN run from {where})")
    if n < 16:
        raise fail(f"channel 'time' has only {n} sample{'' if n == 1 else 's'}")
    steps = np.diff(t)
    if np.any(steps == 0.0):
        i = int(np.argmax(steps == 0.0))
        raise fail(f"channel 'time' has a duplicated time stamp {t[i]:.6g} s at sample {i + 1}")
    if np.any(steps < 0.0):
        i = int(np.argmax(steps < 0.0))
        raise fail(f"channel 'time' is not increasing: {t[i]:.6g} s then {t[i + 1]:.6g} s at sample {i + 1}")
    dt = float(np.median(steps))
    # a time column in ms read as s (or the reverse) passes every check above and gives numbers 1000 times off
    unit = "; is its unit right? (a channel map gives it: time = {{ name = \"...\", unit = \"{}\" }})"
    if 1.0 / dt < RATE_MIN_HZ:
        raise fail(f"channel 'time' steps {dt:.3g} s, a sample rate of {1.0 / dt:.3g} Hz below the {RATE_MIN_HZ:g} Hz "
                   "identification needs" + unit.format("ms"))
    if 1.0 / dt > RATE_MAX_HZ:
        raise fail(f"channel 'time' steps {dt:.3g} s, a sample rate of {1.0 / dt:.3g} Hz above {RATE_MAX_HZ:g} Hz"
                   + unit.format("s"))
    if t[-1] - t[0] < DURATION_MIN_S:
        raise fail(f"channel 'time' spans {t[-1] - t[0]:.3g} s, too short to identify anything "
                   f"(at least {DURATION_MIN_S:g} s)" + unit.format("s"))
    if np.any(gaps := steps > (GAP_MAX_SAMPLES + 1.5) * dt):
        i = int(np.argmax(gaps))
        raise fail(f"channel 'time' has a gap of {steps[i]:.3g} s after t = {t[i]:.6g} s (about "
                   f"{round(steps[i] / dt) - 1} samples of {dt:.3g} s missing; {GAP_MAX_SAMPLES} in a row are "
                   "interpolated): cut the file there or fill the gap")


def _found(columns: Mapping[str, Any]) -> str:
    """The columns a file has, for an error that cannot find one: a header with units in it or a wrong separator
    shows at once."""
    names = list(columns)
    if not names:
        return "the file has no numeric channels"
    more = f" and {len(names) - 8} more" if len(names) > 8 else ""
    return "the file has " + ", ".join(f"'{n}'" for n in names[:8]) + more


def command_changes(t: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Indices where a piecewise constant command changes (a DAQ may spread one change over a few samples: it counts once)."""
    span = float(np.ptp(u))
    if span <= 0.0:
        return np.zeros(0, dtype=int)
    jump = np.abs(np.diff(u)) > 0.02 * span
    starts = np.flatnonzero(jump & ~np.concatenate([[False], jump[:-1]]))
    if starts.size == 0:
        return starts
    return starts[np.concatenate([[True], np.diff(t[starts]) > 0.02])] + 1


def detect_experiment(t: np.ndarray, u: np.ndarray, where: str = "") -> str:
    """The experiment type of a command signal (used when no ``meta.json`` says it).

    Piecewise constant commands are a ``step`` (one rise), a ``relaxation`` (one
    fall) or a ``staircase`` (several changes); a command that varies all the
    time is a ``chirp`` if its zero-crossing rate grows along the record, a
    ``multisine`` if a few spectral lines carry its power, else ``noise``.
    """
    span = float(np.ptp(u))
    if span <= 0.0:
        raise WetclutchError(f"measurement file '{where}': channel 'u' is constant (no experiment to identify)")
    du = np.diff(u)
    events = command_changes(t, u) - 1  # index into du of each change
    if 0 < events.size <= 50 and np.count_nonzero(np.abs(du) > 0.005 * span) <= 10 * events.size:
        if events.size == 1:
            return "step" if du[events[0]:events[0] + 5].sum() > 0 else "relaxation"
        return "staircase"
    x = u - np.median(u)
    crossings = np.flatnonzero(np.signbit(x[:-1]) != np.signbit(x[1:]))
    third = (t[-1] - t[0]) / 3
    early = np.count_nonzero(t[crossings] < t[0] + third)
    late = np.count_nonzero(t[crossings] > t[-1] - third)
    if late > 4 * max(early, 1):
        return "chirp"
    power = np.abs(np.fft.rfft(x)) ** 2
    top = np.sort(power)[::-1][:40].sum()
    return "multisine" if top > 0.8 * power.sum() else "noise"
