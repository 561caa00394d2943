"""The controller file: a design as TOML, every setting named with its unit and source, the tables included.

Layout::

    kind = "launch"                 # or "baseline"
    [settings.p_kiss]
    value = 70033.4
    unit = "Pa"
    source = "plant (identified): p_prestress + k_reset x_contact / A_p"
    ...
    [tables]
    temps_C = [...]                 # feedforward map: oil temperatures
    pressures_Pa = [...]            #                  pressures
    input_V = [[...], ...]          #                  input for each (temperature, pressure)
    fill_s = [...]                  # the baseline's fill pulse per temperature
    source, fill_source = "..."     # where the tables came from
    [plant]                         # the parameter set the controller was designed on
    ...

:func:`to_toml` writes it, :func:`loads`/:func:`load` read and validate it (one line
naming the offending field; a file of another kind than asked for is refused; a key the
file's writer does not write is refused, not ignored; the tables' axes lie within the oil
temperatures and pressures a plant takes, the map's inputs within the valve's range and
never falling as the pressure rises, the kiss point below the supply's pressure, and a ``[plant]`` that is not
empty: it is not read as the built-in rig). A setting
that is not derived from the plant and is absent from the file (one written before the
setting existed) takes the controller's default, its source saying so; a plant-derived one
absent is an error.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import tomli_w

from ..errors import ParameterError, WetclutchError, finite_number, read_text, shown
from ..params import OIL_TEMP_RANGE_C, flatten, load as load_params
from ..rig.experiments import INPUT_RANGE
from .design import (BASELINE_DEFAULTS, KINDS, LAUNCH_DEFAULTS, MAP_TEMPS, PLANT_SETTINGS, SETTINGS, Design,
                     plant_settings)


class ControllerFileError(WetclutchError):
    """A controller file that cannot be used."""


#: the keys a setting's table may hold (:func:`to_toml` writes them all)
SETTING_KEYS = {"value", "unit", "source", "description"}
#: the keys of the [tables] section
TABLE_KEYS = {"temps_C", "pressures_Pa", "input_V", "fill_s", "source", "fill_source"}
#: the longest fill pulse a file may give, s (the design's are the full input's fill times, under 3 s)
FILL_MAX_S = 10.0


def to_toml(d: Design) -> str:
    """The controller file of design ``d``."""
    data: dict[str, Any] = {
        "kind": d.kind,
        "settings": {name: {"value": float(d.settings[name]), "unit": spec.unit, "source": d.sources.get(name, ""),
                            "description": spec.description}
                     for name, spec in SETTINGS[d.kind].items()},
        "tables": {"temps_C": d.temps_C.tolist(), "pressures_Pa": d.pressures_Pa.tolist(),
                   "input_V": d.input_V.tolist(), "fill_s": d.fill_s.tolist(),
                   "source": d.sources.get("input_V", ""), "fill_source": d.sources.get("fill_s", "")},
        "plant": d.plant.model_dump(),
    }
    head = f"# wetclutch controller file: the {d.kind} controller, SI units (each setting's unit beside it)\n"
    return head + tomli_w.dumps(data)


def _err(where: str, msg: str) -> ControllerFileError:
    return ControllerFileError(f"{where}: {msg}")


def _array(where: str, raw: Any, ndim: int) -> np.ndarray:
    try:
        a = np.array(raw, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise _err(where, "must be an array of numbers") from None
    if a.ndim != ndim or a.size == 0 or not np.all(np.isfinite(a)):
        raise _err(where, f"must be a {ndim}-D array of finite numbers")
    return a


def _uniform(where: str, a: np.ndarray) -> None:
    if a.size < 2 or np.any(np.diff(a) <= 0) or not np.allclose(np.diff(a), a[1] - a[0], rtol=1e-9, atol=0):
        raise _err(where, "must be evenly spaced and increasing")


#: the pressures a feedforward table may tabulate, Pa (those of a setting in Pa)
_PRESSURE_RANGE = (0.0, 5e6)
#: rounding allowed in the table's inputs, V (an interpolation's last digits)
_U_TOL = 1e-9


def loads(text: str, source: str = "controller file", kind: str | None = None) -> Design:
    """A design from controller-file ``text``; ``kind``, if given, is the kind the caller needs."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise _err(source, f"not valid TOML: {str(e).splitlines()[0]}") from None
    unknown = sorted(set(data) - {"kind", "settings", "tables", "plant"})
    if unknown:
        raise _err(source, f"unknown section '{unknown[0]}'")
    k = data.get("kind")
    if k not in KINDS:
        raise _err(f"{source}: kind", f"must be one of {', '.join(KINDS)} (got {shown(k)})")
    if kind is not None and k != kind:
        raise _err(f"{source}: kind", f"is a {k} controller, but a {kind} controller is needed here")
    for section in ("settings", "tables", "plant"):
        if not isinstance(data.get(section), dict):
            raise _err(source, f"missing section [{section}]")
    spec = SETTINGS[k]
    given = data["settings"]
    extra = sorted(set(given) - set(spec))
    if extra:
        raise _err(f"{source}: settings.{extra[0]}", f"unknown setting of the {k} controller")
    designed_on = flatten(data["plant"])
    # an empty [plant] would read as the built-in rig: no design writes one (it writes every parameter), and the
    # settings derived from the plant, and any mismatch verified, would be taken from a plant the file never named
    if not designed_on:
        raise _err(source, "[plant] is empty: it must hold the parameter set the controller was designed on "
                   "(wetclutch design writes it)")
    try:
        plant = load_params(None, designed_on)
    except ParameterError as e:
        raise _err(f"{source}: [plant]", str(e)) from None
    values, sources = {}, {}
    defaults = LAUNCH_DEFAULTS if k == "launch" else BASELINE_DEFAULTS
    derived: dict[str, tuple[float, str]] | None = None
    for name, s in spec.items():
        where = f"{source}: settings.{name}"
        entry = given.get(name)
        if entry is None and name in defaults:
            # a setting the file's writer did not have yet: the controller's default, said so
            entry = {"value": defaults[name], "unit": s.unit, "source": "controller default (not in the file)"}
        elif entry is None and name in PLANT_SETTINGS:
            # or one it takes from the plant: from the file's [plant], said so
            derived = derived or plant_settings(plant)
            entry = {"value": derived[name][0], "unit": s.unit, "source": derived[name][1] + " (not in the file)"}
        if entry is None:
            raise _err(where, "missing")
        if not isinstance(entry, dict) or "value" not in entry:
            raise _err(where, "must be a table with 'value' (and 'unit')")
        unknown_keys = sorted(set(entry) - SETTING_KEYS)
        if unknown_keys:
            # a misspelt 'value' beside the written one would be ignored, and the edit with it
            raise _err(f"{where}.{unknown_keys[0]}", f"unknown key (known: {', '.join(sorted(SETTING_KEYS))})")
        v = entry["value"]
        if not finite_number(v):
            raise _err(f"{where}.value", f"must be a finite number (got {shown(v)})")
        unit = entry.get("unit", s.unit)
        if unit != s.unit:
            raise _err(f"{where}.unit", f"must be '{s.unit}' (got {shown(unit)}; values are in SI units)")
        if not s.low <= v <= s.high:
            raise _err(f"{where}.value", f"{v:g} {s.unit} is outside {s.low:g}..{s.high:g}")
        values[name] = float(v)
        sources[name] = str(entry.get("source", ""))
    # each within its range, but together no clutch: the plates would touch only above what the supply gives, and
    # the controller, holding the valve open for a contact that never comes, slams them shut before the request
    top, top_name = ((values["p_max"], "settings.p_max") if "p_max" in values else
                     (min(plant.hydraulics.p_supply, plant.hydraulics.p_relief),
                      "[plant]'s min(hydraulics.p_supply, hydraulics.p_relief)"))
    if values["p_kiss"] >= top:
        raise _err(f"{source}: settings.p_kiss.value", f"{values['p_kiss']:g} Pa is not below {top_name} ({top:g} Pa, "
                   "the highest pressure the supply gives): the plates would never touch")
    tables = data["tables"]
    unknown_keys = sorted(set(tables) - TABLE_KEYS)
    if unknown_keys:
        raise _err(f"{source}: tables.{unknown_keys[0]}", f"unknown key (known: {', '.join(sorted(TABLE_KEYS))})")
    for name in ("temps_C", "pressures_Pa", "input_V", "fill_s"):
        if name not in tables:
            raise _err(f"{source}: tables.{name}", "missing")
    temps = _array(f"{source}: tables.temps_C", tables["temps_C"], 1)
    pressures = _array(f"{source}: tables.pressures_Pa", tables["pressures_Pa"], 1)
    table = _array(f"{source}: tables.input_V", tables["input_V"], 2)
    fill = _array(f"{source}: tables.fill_s", tables["fill_s"], 1)
    _uniform(f"{source}: tables.temps_C", temps)
    _uniform(f"{source}: tables.pressures_Pa", pressures)
    if temps.size != MAP_TEMPS.size:
        raise _err(f"{source}: tables.temps_C", f"must have {MAP_TEMPS.size} temperatures (got {temps.size})")
    if table.shape != (temps.size, pressures.size):
        raise _err(f"{source}: tables.input_V", f"must be {temps.size} x {pressures.size} (temps_C x pressures_Pa), "
                   f"got {table.shape[0]} x {table.shape[1]}")
    if fill.shape != temps.shape or np.any(fill < 0) or np.any(fill > FILL_MAX_S):
        raise _err(f"{source}: tables.fill_s", f"must be {temps.size} times in 0..{FILL_MAX_S:g} s, one per "
                   "temperature")
    # the tables' axes and values within what the plant and the valve take (SI units: a table in bar or mA is refused)
    t_lo, t_hi = OIL_TEMP_RANGE_C
    if temps[0] < t_lo or temps[-1] > t_hi:
        raise _err(f"{source}: tables.temps_C", f"must lie within {t_lo:g}..{t_hi:g} C (got {temps[0]:g}..{temps[-1]:g})")
    p_lo, p_hi = _PRESSURE_RANGE
    if pressures[0] < p_lo or pressures[-1] > p_hi:
        raise _err(f"{source}: tables.pressures_Pa", f"must lie within {p_lo:g}..{p_hi:g} Pa "
                   f"(got {pressures[0]:g}..{pressures[-1]:g})")
    u_lo, u_hi = INPUT_RANGE["dc"]
    if table.min() < u_lo - _U_TOL or table.max() > u_hi + _U_TOL:
        raise _err(f"{source}: tables.input_V", f"must lie within the valve's input range {u_lo:g}..{u_hi:g} V "
                   f"(got {table.min():g}..{table.max():g})")
    falls = np.argwhere(np.diff(table, axis=1) < -_U_TOL)
    if falls.size:
        i, j = falls[0]
        raise _err(f"{source}: tables.input_V", f"must not fall as the pressure rises (row {i}, {temps[i]:g} C: "
                   f"{table[i, j]:g} V at {pressures[j]:g} Pa, {table[i, j + 1]:g} V at {pressures[j + 1]:g} Pa)")
    for key, name in (("source", "input_V"), ("fill_source", "fill_s")):
        if tables.get(key):
            sources[name] = str(tables[key])
    return Design(k, plant, values, sources, temps, pressures, table, fill)


def load(path: str | Path, kind: str | None = None) -> Design:
    """The design in controller file ``path`` (see :func:`loads`)."""
    path = Path(path)
    return loads(read_text(path, "controller file", ControllerFileError), str(path), kind)
