"""Measurement files: CSV, MDF 4 (``.mf4``) and MATLAB (``.mat``), written and read back.

:func:`write_measurement` stores a measurement (a table with ``time`` first) in all three
formats plus ``meta.json``; :func:`read_columns` reads any of them, dSPACE recordings
included, and :func:`read_measurement` reads one back as a checked table.
"""

from __future__ import annotations

import gc
import re
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy import io as sio

from ..errors import WetclutchError
from ..output import write_csv, write_json


def _float_column(frame: pd.DataFrame, name: str, what: str) -> np.ndarray:
    try:
        return np.asarray(pd.to_numeric(frame[name], errors="raise"), dtype=np.float64)
    except (KeyError, TypeError, ValueError):
        raise WetclutchError(_one_line(f"{what}: column '{name}' is missing or not numeric")) from None


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
        write_csv(pd.DataFrame(data), directory / "measured.csv")
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
