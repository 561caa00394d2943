"""Measurement files: CSV, MDF 4 (``.mf4``) and MATLAB (``.mat``), written and read back.

:func:`write_measurement` stores a measurement (a table with ``time`` first) in all three
formats plus ``meta.json``; :func:`read_columns` reads any of them, dSPACE recordings
included, and :func:`read_measurement` reads one back as a checked table.
"""

from __future__ import annotations

import csv
import gc
import io
import itertools
import re
import sys
import warnings
from collections.abc import Collection
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


#: separators a measurement CSV may have, by precedence: a logger's tabs, a European Excel's semicolons (which comes
#: with decimal commas), else commas
_SEPARATORS = ("\t", ";", ",")
_DECIMAL_COMMA = re.compile(r"[-+]?\d*,\d+(?:[eE][-+]?\d+)?")
#: lines read to tell the dialect: the header, a unit row if any, and enough data to see decimal commas
_HEAD_LINES = 50


def _is_number(cell: str, decimal: str) -> bool:
    try:
        float(cell.replace(decimal, ".") if decimal != "." else cell)
    except ValueError:
        return False
    return True


def _csv_dialect(text: str) -> tuple[int, str, str, dict[str, str] | None]:
    """The number of comment lines before the header, the separator, the decimal mark and the unit row (column ->
    unit; None without one) of a CSV's ``text``.

    Comment lines start with ``#`` (a logger's preamble: rig, date, operator). A unit row is a line under the header
    whose cells are all text (``bar``, ``[rpm]``), as DAQ exports and spreadsheets write it; brackets around a unit are
    dropped. A semicolon- or tab-separated file whose numbers have a comma before their digits uses decimal commas (a
    European Excel); a comma-separated file cannot (its cells would split there).
    """
    lines = list(itertools.islice(io.StringIO(text), _HEAD_LINES))
    skip = next((i for i, line in enumerate(lines) if not line.lstrip().startswith("#")), len(lines))
    lines = lines[skip:]
    sep = next((s for s in _SEPARATORS if lines and s in lines[0]), ",")
    head = list(csv.reader(lines, delimiter=sep))
    cells = [c.strip() for row in head[1:] for c in row]
    decimal = "," if sep != "," and any(_DECIMAL_COMMA.fullmatch(c) for c in cells) else "."
    units = None
    if len(head) > 1:
        second = [c.strip() for c in head[1]]
        if any(second) and not any(_is_number(c, decimal) for c in second if c):
            names = [c.strip() for c in head[0]]
            units = {n: u.strip("[]()").strip() for n, u in zip(names, second) if u.strip("[]()").strip()}
    return skip, sep, decimal, units


def _numeric(column: pd.Series, decimal: str) -> tuple[np.ndarray, int | None]:
    """A CSV column as float64 and the row of its first cell that is not a number (None if every cell is one or is
    empty: an empty cell is a missing sample, NaN)."""
    if pd.api.types.is_bool_dtype(column) or pd.api.types.is_numeric_dtype(column):
        return column.to_numpy(dtype=np.float64, na_value=np.nan), None
    text = column.astype("string").str.strip()
    if decimal != ".":
        text = text.str.replace(decimal, ".", regex=False)
    values = pd.to_numeric(text, errors="coerce")
    bad = (values.isna() & text.notna() & (text != "")).to_numpy(dtype=bool)
    return values.to_numpy(dtype=np.float64, na_value=np.nan), (int(np.argmax(bad)) if bad.any() else None)


def _read_csv(path: Path, wanted: Collection[str] | None = None) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:  # a Windows spreadsheet's export ("°C" in cp1252)
        text = raw.decode("cp1252", errors="replace")
    skip, sep, decimal, units = _csv_dialect(text)
    with warnings.catch_warnings():
        # more cells in a row than in the header: pandas would take the first columns for an index and shift the
        # names onto the wrong data (a comma-separated file with decimal commas)
        warnings.simplefilter("error", pd.errors.ParserWarning)
        try:
            frame = pd.read_csv(io.StringIO(text), sep=sep, decimal=decimal, skipinitialspace=True, index_col=False,
                                skiprows=[*range(skip), *([skip + 1] if units is not None else [])])
        except pd.errors.ParserWarning:
            raise _fail(path, "rows have more cells than the header has names"
                        + (" (decimal commas in a comma-separated file?)" if decimal == "." else "")) from None
    first_row = skip + (3 if units is not None else 2)  # the file's line of the first data row
    columns = {}
    for c in frame.columns:
        name = str(c).strip()
        values, bad = _numeric(frame[c], decimal)
        if bad is not None:
            if wanted is None or name in wanted:
                raise _fail(path, f"column '{name}' is not numeric (line {bad + first_row}: "
                                  f"{str(frame[c].iloc[bad])[:40]!r})")
            continue  # an unrelated text column (a status, a comment) is no reason to refuse the file
        columns[name] = values
    return columns, {n: u for n, u in (units or {}).items() if n in columns}


def _read_mat(path: Path, wanted: Collection[str] | None = None) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    try:
        raw = sio.loadmat(path, simplify_cells=True)
    except NotImplementedError:  # scipy's word for the HDF5 format of MATLAB's -v7.3
        raise _fail(path, "is a MATLAB v7.3 (HDF5) file, which is not read: save it with save(..., '-v7')") from None
    units = raw.pop("units", {})
    units = {str(k): v for k, v in units.items() if isinstance(v, str)} if isinstance(units, dict) else {}
    columns: dict[str, np.ndarray] = {}
    structs = []
    for name, value in raw.items():
        if isinstance(value, dict) and "X" in value and "Y" in value:
            return _dspace_columns(value)
        if isinstance(value, dict) and not name.startswith("__"):
            structs.append(value)
            continue
        # Skip MATLAB's bookkeeping entries and anything that is not one numeric vector.
        if not name.startswith("__") and (vector := _mat_vector(value)) is not None:
            columns[name] = vector
    # a struct of vectors (``save('run.mat', 'meas')`` of ``meas.time``, ``meas.p_clutch`` ...): its fields are the
    # channels, a variable of the same name winning
    for struct in structs:
        for name, value in struct.items():
            if name == "units" and isinstance(value, dict):
                units = {**{str(k): v for k, v in value.items() if isinstance(v, str)}, **units}
            elif name not in columns and (vector := _mat_vector(value)) is not None:
                columns[name] = vector
    return columns, units


def _mat_vector(value: Any) -> np.ndarray | None:
    """A MATLAB variable as a float64 vector (row or column), or None: not numeric, or not one vector."""
    value = np.asarray(value)
    if value.dtype.kind in "biuf" and value.squeeze().ndim <= 1:
        return np.atleast_1d(value.squeeze()).astype(np.float64)
    return None


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


def _read_mdf(path: Path, wanted: Collection[str] | None = None) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    from asammdf import MDF  # imported here: asammdf is slow to import

    with open(path, "rb") as stream, MDF(stream) as mdf:
        # channel group -> name -> (samples, unit, time stamps), the numeric vectors of groups with a master channel
        groups: dict[int, dict[str, tuple[np.ndarray, str, np.ndarray]]] = {}
        for sig in mdf.iter_channels(skip_master=True):
            samples = np.asarray(sig.samples)
            if mdf.masters_db.get(sig.group_index) is None or samples.dtype.kind not in "biuf" or samples.ndim != 1:
                continue
            groups.setdefault(sig.group_index, {}).setdefault(
                sig.name, (samples.astype(np.float64), str(sig.unit or ""), np.asarray(sig.timestamps, np.float64)))
    if not groups:
        return {}, {}
    # A DAQ writes one channel group per raster (the analog channels at 1 kHz, CAN signals at 100 Hz, a temperature
    # at 10 Hz). The time base is the group with most of the wanted channels (then most channels, then most samples);
    # the other groups' channels are interpolated onto it.
    score = lambda g: (sum(n in wanted for n in groups[g]) if wanted is not None else 0,  # noqa: E731
                       len(groups[g]), next(iter(groups[g].values()))[2].size)
    base = max(sorted(groups), key=score)
    t = next(iter(groups[base].values()))[2]
    columns, units = {"time": t}, {"time": "s"}
    for g in [base, *sorted(set(groups) - {base})]:
        for name, (samples, unit, ts) in groups[g].items():
            if name in columns:
                continue
            if g != base:
                step = float(np.median(np.diff(ts))) if ts.size > 1 else 0.0
                usable = ts.size > 1 and np.all(np.diff(ts) > 0)
                if not (usable and ts[0] - step <= t[0] and t[-1] <= ts[-1] + step):
                    if wanted is None or name in wanted:
                        span = f"t = {ts[0]:.6g}..{ts[-1]:.6g} s" if ts.size else "no samples"
                        raise _fail(path, f"channel '{name}' (channel group {g}, another raster than the time base's "
                                          f"group {base}) " + (f"covers {span}, not the record's t = {t[0]:.6g}.."
                                                               f"{t[-1]:.6g} s" if usable else
                                                               "has too few or no increasing time stamps"))
                    continue
                samples = np.interp(t, ts, samples)
            columns[name] = samples
            if unit:
                units[name] = unit
    return columns, units


_READERS = {".csv": _read_csv, ".mat": _read_mat, ".mf4": _read_mdf, ".mdf": _read_mdf}


def read_columns(path: str | Path,
                 wanted: Collection[str] | None = None) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """Read every numeric channel of a measurement file, unchecked.

    CSV (comma-, semicolon- or tab-separated, decimal commas beside semicolons or tabs, an optional unit row under
    the header), MDF 4 (``.mf4``/``.mdf``; the time base is a channel group's master channel, returned as ``time``,
    and channels of other groups, other rasters, are interpolated onto it) and MATLAB files: one vector per variable
    or per field of a struct, or a dSPACE recording (a struct with ``X`` and ``Y``).

    Parameters
    ----------
    path : str or Path
    wanted : collection of str, optional
        The channels the caller needs. Other channels that cannot be read as one numeric series (a CSV column of text,
        an MDF channel on a raster that does not cover the record) are left out rather than refused; the MDF time
        base is the group holding most of them. None: every channel is wanted.

    Returns
    -------
    dict of str to ndarray
        Channel name -> float64 samples, as stored (lengths may differ).
    dict of str to str
        Unit per channel, as far as the file records them (for a CSV, its unit row).

    Raises
    ------
    WetclutchError
        The file is missing, of unknown type, unreadable or corrupt, or a wanted channel is not numeric.
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
            return reader(path, wanted)
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
        Unit per channel, as far as the file records them (for a CSV, its unit row if it has one).

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
