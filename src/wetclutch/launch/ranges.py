"""Verification ranges as data: what varies between the plant a controller was designed on and the plants it meets.

A ranges file (TOML) has one table per range; :data:`DEFAULT_FILE` is the one shipped,
with every key explained. A range moves one parameter of the plant (``target`` a dotted
path of :class:`~wetclutch.params.Params`) or one launch condition (:data:`CONDITIONS`):

* ``how = "abs"``: the sampled value is the value; ``"rel"``: a factor on the plant's value;
  ``"offset"``: added to the plant's value;
* ``dist = "uniform"`` over ``[low, high]``, or ``"normal"`` with ``low`` and ``high`` at
  minus and plus two standard deviations (truncated there);
* ``corner = true``: the corner cases take this range's extremes (its one value where ``low == high``: a range
  pinned to a value holds it in every corner case, each case made once);
* ``unit``, if given, labels the values in reports: the target's SI unit (``C``, ``N m``, ``-`` for the conditions),
  or ``-`` for the factors of ``rel``; another (a range labelled in bar) is refused, since the values are read in
  the SI unit whatever the label. A ``rel`` factor is never negative (offsets written under ``rel`` are refused).

A quantity is varied by one range: the oil temperature, both a parameter (``rig.oil_temp_C``) and a condition
(``oil_temp_C``), by one of the two.

A condition's range must lie within what a launch takes (:func:`wetclutch.launch.loop.condition_error`): every value drawn lies
between ``low`` and ``high``, so a file whose ends lie within can draw nothing else.

:func:`load` validates a file (one-line errors naming the range and key); :func:`fit`
limits the ranges to what a plant can physically take; :func:`draw` and :func:`corners`
turn ranges into values; :func:`apply` puts values into a plant.
"""

from __future__ import annotations

import functools
import itertools
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import WetclutchError, finite_number, read_text, shown
from ..params import Params, describe, load as load_params
from .loop import condition_error

DEFAULT_FILE = Path(__file__).resolve().parent / "data" / "ranges.toml"
#: launch conditions a range may vary (the rest of a range's targets are parameters)
CONDITIONS = ("oil_temp_C", "t_ref", "noise_scale")
HOWS = ("abs", "rel", "offset")
DISTS = ("uniform", "normal")
KEYS = {"target", "how", "dist", "low", "high", "corner", "unit"}


class RangesError(WetclutchError):
    """A ranges file that cannot be used."""


@dataclass(frozen=True)
class Range:
    """One varied quantity (see the module docstring for the fields)."""

    name: str
    target: str
    how: str = "abs"
    low: float = 0.0
    high: float = 0.0
    dist: str = "uniform"
    corner: bool = False
    unit: str = ""

    @property
    def is_condition(self) -> bool:
        return self.target in CONDITIONS

    def draw(self, rng: np.random.Generator) -> float:
        """One sampled value (a factor or offset for ``rel``/``offset``)."""
        if self.dist == "uniform":
            return float(rng.uniform(self.low, self.high))
        mid, sd = 0.5 * (self.low + self.high), 0.25 * (self.high - self.low)
        return float(np.clip(rng.normal(mid, sd), self.low, self.high))

    def value(self, base: float, x: float) -> float:
        """The target's value for sampled ``x`` on a plant whose value is ``base``."""
        if self.how == "rel":
            return base * x
        if self.how == "offset":
            return base + x
        return x


def _err(where: str, msg: str) -> RangesError:
    return RangesError(f"{where}: {msg}")


def _number(where: str, raw: dict[str, Any], key: str) -> float:
    if key not in raw:
        raise _err(where, f"missing key '{key}'")
    v = raw[key]
    if not finite_number(v):
        raise _err(f"{where}.{key}", f"must be a finite number (got {shown(v)})")
    return float(v)


#: the unit of each launch condition's values
CONDITION_UNITS = {"oil_temp_C": "C", "t_ref": "N m", "noise_scale": "-"}


@functools.cache
def _units() -> dict[str, str]:
    """Every parameter's SI unit by dotted path (:func:`wetclutch.params.describe`), made once: a ranges file
    asks for one per range."""
    return {path: unit for path, _, unit, _ in describe(Params())}


def _target_unit(target: str) -> str:
    """The SI unit of ``target``'s values."""
    return CONDITION_UNITS[target] if target in CONDITION_UNITS else _units()[target]


def _check_unit(where: str, target: str, how: str, unit: str) -> None:
    """Refuse a ``unit`` that is not the one the range's values are in: a range's values are in the target's SI unit
    (``abs``, ``offset``) or factors (``rel``), and the unit is only how reports label them, so a range written in
    bar, or a factor labelled in Pa, would be read as something other than it says."""
    if not unit:
        return
    expected = "-" if how == "rel" else _target_unit(target)
    if unit != expected and not (expected in ("", "-") and unit in ("", "-")):
        what = "a factor on the plant's value" if how == "rel" else f"{target}'s SI unit"
        raise _err(f"{where}.unit", f"must be '{expected}' ({what}; got {shown(unit)}): the values are read in it whatever "
                   "the label says")


def parse(data: dict[str, Any], source: str = "ranges") -> list[Range]:
    """Ranges from the parsed TOML ``data``; ``source`` names the file in errors."""
    if not isinstance(data, dict) or not data:
        raise _err(source, "no ranges (one table per range)")
    defaults = Params().model_dump()
    out = []
    for name, raw in data.items():
        where = f"{source}: [{name.encode('unicode_escape').decode()}]"
        if not isinstance(raw, dict):
            raise _err(where, "must be a table (target, how, low, high, ...)")
        unknown = sorted(set(raw) - KEYS)
        if unknown:
            raise _err(where, f"unknown key '{unknown[0]}' (known: {', '.join(sorted(KEYS))})")
        target = raw.get("target")
        if not isinstance(target, str):
            raise _err(where, "missing key 'target' (a parameter path or one of " + ", ".join(CONDITIONS) + ")")
        if target not in CONDITIONS:
            section, _, key = target.partition(".")
            value = defaults.get(section, {}).get(key) if isinstance(defaults.get(section), dict) else None
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise _err(f"{where}.target", f"'{target}' is neither a numeric parameter nor one of "
                           + ", ".join(CONDITIONS))
        how = raw.get("how", "abs")
        if how not in HOWS:
            raise _err(f"{where}.how", f"must be one of {', '.join(HOWS)} (got {shown(how)})")
        if target in CONDITIONS and how != "abs":
            raise _err(f"{where}.how", f"a condition ('{target}') takes absolute values only")
        dist = raw.get("dist", "uniform")
        if dist not in DISTS:
            raise _err(f"{where}.dist", f"must be one of {', '.join(DISTS)} (got {shown(dist)})")
        low, high = _number(where, raw, "low"), _number(where, raw, "high")
        if not low <= high:
            raise _err(f"{where}.low", f"must not exceed high ({low:g} > {high:g})")
        if how == "rel" and low < 0.0:
            # a factor below zero turns the parameter's sign: offsets written under "rel", most likely
            raise _err(f"{where}.low", f"a factor on the plant's value must be >= 0 (got {low:g}); "
                       "how = \"offset\" adds values in the parameter's unit")
        if target in CONDITIONS:
            # a condition is absolute and every draw (a normal one clipped) lies between the ends, and each
            # condition's allowed values form one interval: the ends decide
            for key, end in (("low", low), ("high", high)):
                if (why := condition_error(target, end)) is not None:
                    raise _err(f"{where}.{key}", why)
        corner = raw.get("corner", False)
        if not isinstance(corner, bool):
            raise _err(f"{where}.corner", f"must be true or false (got {shown(corner)})")
        unit = raw.get("unit", "")
        if not isinstance(unit, str):
            raise _err(f"{where}.unit", f"must be a string (got {shown(unit)})")
        _check_unit(where, target, how, unit)
        out.append(Range(name, target, how, low, high, dist, corner, unit))
    targets = [r.target for r in out]
    dup = next((t for t in targets if targets.count(t) > 1), None)
    if dup:
        raise _err(source, f"target '{dup}' is varied by two ranges")
    # the oil temperature is a parameter and a condition: a launch given the condition runs at it whatever the
    # plant's, so the parameter's range would be drawn and reported but never run
    both = [next((r for r in out if r.target == t), None) for t in ("rig.oil_temp_C", "oil_temp_C")]
    if None not in both:
        names = [r.name.encode("unicode_escape").decode() for r in both]
        raise _err(source, f"[{names[0]}] (target 'rig.oil_temp_C') and [{names[1]}] (target 'oil_temp_C') both vary "
                   "the oil temperature, and a launch takes the condition's: keep one of the two")
    # a range pinned to one value adds no corner cases
    if sum(r.corner and r.low != r.high for r in out) > 10:
        raise _err(source, "more than 10 corner ranges (2^n corner cases)")
    return out


def load(path: str | Path | None = None) -> list[Range]:
    """The ranges of the TOML file ``path`` (default: :data:`DEFAULT_FILE`)."""
    path = Path(path) if path is not None else DEFAULT_FILE
    try:
        data = tomllib.loads(read_text(path, "ranges file", RangesError))
    except tomllib.TOMLDecodeError as e:
        raise RangesError(f"ranges file '{path}' is not valid TOML: {str(e).splitlines()[0]}") from None
    return parse(data, str(path))


def draw(ranges: list[Range], rng: np.random.Generator) -> dict[str, float]:
    """One random sample: range name -> sampled value (a factor or offset where ``how`` says so)."""
    return {r.name: r.draw(rng) for r in ranges}


def nominal(ranges: list[Range], plant: Params, conditions: dict[str, float]) -> dict[str, float]:
    """Each range's value that leaves the plant and the conditions as they are."""
    out = {}
    for r in ranges:
        if r.how == "rel":
            out[r.name] = 1.0
        elif r.how == "offset":
            out[r.name] = 0.0
        elif r.is_condition:
            out[r.name] = float(conditions[r.target])
        else:
            section, key = r.target.split(".")
            out[r.name] = float(getattr(getattr(plant, section), key))
    return out


def corners(ranges: list[Range]) -> list[dict[str, float]]:
    """Every combination of the corner ranges' extremes (the other ranges left out: their nominal values)."""
    cr = [r for r in ranges if r.corner]
    # a range pinned to one value (low == high) has one extreme: taken twice, every corner case would run twice
    ends = [(r.low, r.high) if r.low != r.high else (r.low,) for r in cr]
    return [dict(zip([r.name for r in cr], combo)) for combo in itertools.product(*ends)]


def apply(ranges: list[Range], values: dict[str, float], plant: Params) -> tuple[Params, dict[str, float]]:
    """The plant with the parameter ranges' values put in, and the conditions' values (by condition name).

    Raises a one-line error if a value leaves the parameter's physical range.
    """
    sets, cond = {}, {}
    for r in ranges:
        if r.name not in values:
            continue
        if r.is_condition:
            cond[r.target] = r.value(0.0, values[r.name])
        else:
            section, key = r.target.split(".")
            sets[r.target] = r.value(float(getattr(getattr(plant, section), key)), values[r.name])
    return (load_params(None, sets, base=plant) if sets else plant), cond


def _dotted(plant: Params, target: str) -> float:
    section, key = target.split(".")
    return float(getattr(getattr(plant, section), key))


def _error(r: Range, x: float, plant: Params) -> WetclutchError | None:
    """Why ``r`` at ``x`` leaves ``plant``'s physical range, or a condition what a launch takes (None: it does not)."""
    if r.is_condition:
        why = condition_error(r.target, r.value(0.0, x))
        return None if why is None else RangesError(why)
    try:
        apply([r], {r.name: x}, plant)
    except WetclutchError as e:
        return e
    return None


def _edge(r: Range, inside: float, end: float, plant: Params) -> float:
    """The value nearest ``end`` on the way from ``inside`` (valid) that keeps ``r`` within the physical range."""
    ok, bad = inside, end
    while abs(bad - ok) > 1e-6 * (r.high - r.low):
        mid = 0.5 * (ok + bad)
        ok, bad = (mid, bad) if _error(r, mid, plant) is None else (ok, mid)
    return ok


def fit(ranges: list[Range], plant: Params) -> tuple[list[Range], list[str]]:
    """The ranges as they apply to ``plant``: a range relative to the plant (``rel``, ``offset``) whose end would take
    a parameter out of its physical range is limited to the part within it (a prestress 0.3 bar low on a clutch
    whose prestress is 0.2 bar stops at zero), found by bisection to a millionth of the range; returns the ranges
    and one sentence per limited range. Refuses (one line naming the range) an absolute range with an end out of
    the physical range (a condition's: out of what a launch takes, :func:`condition_error`), and a range with no
    value within it. A ``rel`` range on a parameter that is 0 on ``plant`` is kept, with a sentence saying that it
    varies nothing there."""
    out, notes = [], []
    for r in ranges:
        if r.how == "rel" and not r.is_condition and _dotted(plant, r.target) == 0.0 and r.low != r.high:
            # a factor on zero is zero: reported as varied, its bins and all, the range varies nothing on this plant
            # (a plant may have none of it, a seal that does not leak: the shipped ranges must still run), so said
            notes.append(f"{r.name} ({r.target}, rel) varies nothing on this plant: its value is 0, and so is every "
                         "factor of it (how = \"abs\" or \"offset\" would vary it)")
        errors = [_error(r, end, plant) for end in (r.low, r.high)]
        if errors == [None, None]:
            out.append(r)
            continue
        inside = 1.0 if r.how == "rel" else 0.0  # the plant's own value
        if r.how == "abs" or not r.low <= inside <= r.high:
            bad, e = next((end, e) for end, e in zip((r.low, r.high), errors) if e is not None)
            what = "is outside what a launch takes" if r.is_condition else "leaves the plant's physical range"
            raise RangesError(f"range [{r.name}] at {bad:g} {what}: {e}")
        low, high = (end if e is None else _edge(r, inside, end, plant) for end, e in zip((r.low, r.high), errors))
        out.append(replace(r, low=low, high=high))
        notes.append(f"{r.name} ({r.target}, {r.how}) limited from {r.low:g}..{r.high:g} to {low:g}..{high:g} "
                     "on this plant: beyond, the parameter leaves its physical range")
    return out, notes
