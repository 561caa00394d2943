"""What the launch controller learns across launches: kiss point, friction factor and its slope with slip, and the
hold's margin below the kiss point per oil-temperature band, and the clutch output's inertia.

Within a launch the controller finds the real kiss point (torque onset, or a search
upward from where it believed it) and estimates the friction factor (the clutch's
torque, measured at the axle, over the nominal friction law's; :mod:`wetclutch.launch.controller`). Across
launches, as production transmissions do, it keeps what it found in an adaptation state
per band of :data:`BAND_C` of oil temperature, which the next launch at that temperature
starts from: it then fills to the right place, so it neither slams nor creeps, and its
feedforward asks for the right pressure from the start, so the torque loop has only
the drift since the last launch to correct. The friction factor's slope with slip (how
the clutch's ``mu(slip)`` departs from the design's as the slip falls) moves the next
launch's estimate with the slip, so that its low-pass does not lag that drift. The clutch output's inertia, which
the friction-factor estimate needs to tell the clutch's torque from the axle's, is measured in the slip phase and
taken by the next launch at any temperature. A launch whose waiting vehicle was pushed harder than the design's
``creep_limit`` (the mean of the measured ``T_r`` over the last 0.2 s before the request), by the plates and not only
by the open plates' oil drag, makes the next launches in its band hold the plates :data:`MARGIN_STEP` further below
the kiss point, up to :data:`MARGIN_MAX`: where the valve cannot hold the pressure at the kiss point (cold oil: the
stem creeps into the supply port, and the pressure jumps past the plates' contact) the plates are kept
apart by what the pressure wanders, at the price of a little more stroke at the request. The state is a small TOML file
(``launch``/``verify --sequence``, ``--adaptation``).
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import tomli_w

from ..errors import WetclutchError, finite_number, read_text, shown
from ..params import OIL_TEMP_RANGE_C, Params
from .controller import FRICTION_SLOPE_MAX, J1_MAX, THETA_MAX, THETA_MIN

BAND_C = 20.0
#: the fields of a band in the file (``to_C`` is written for the reader; the band is known by ``from_C``)
BAND_FIELDS = ("from_C", "to_C", "kiss_Pa", "launches", "friction_factor", "friction_slope_per_rad_s",
               "hold_margin_Pa")
#: the fields :meth:`Adaptation.to_toml` writes for every band (the others only where something was learnt)
BAND_REQUIRED = BAND_FIELDS[:4]
#: weight of a new finding against what was learnt (exponential forgetting: drift is followed, noise averaged)
GAIN = 0.5
#: a launch whose standby creep exceeded the design's ``creep_limit`` (the plates' part of it, not the open plates' drag
#: alone) moves the hold of the next launches in its band MARGIN_STEP (Pa) further below the kiss point, up to
#: MARGIN_MAX (Pa)
MARGIN_STEP = 0.02e5
MARGIN_MAX = 0.1e5


def band(temp_C: float) -> int:
    """The band of oil temperature ``temp_C``: bands of :data:`BAND_C` from the lowest allowed temperature."""
    return int((temp_C - OIL_TEMP_RANGE_C[0]) // BAND_C)


def band_from(b: int) -> float:
    """The lowest temperature (C) of band ``b``, the file's ``from_C``."""
    return OIL_TEMP_RANGE_C[0] + b * BAND_C


#: the bands of the allowed oil temperatures (the highest allowed temperature opens the last)
BANDS = range(band(OIL_TEMP_RANGE_C[0]), band(OIL_TEMP_RANGE_C[1]) + 1)


#: the friction factor a learnt value may take: what the controller's estimate may
FRICTION_RANGE = (THETA_MIN, THETA_MAX)


def _blend(old: float | None, new: float) -> float:
    return new if old is None else old + GAIN * (new - old)


@dataclass(frozen=True)
class Adaptation:
    """Learnt kiss points (Pa), friction factors (-), their slopes with slip (1/(rad/s)) and the number of launches
    behind each, by temperature band."""

    kiss_Pa: dict[int, float] = field(default_factory=dict)
    launches: dict[int, int] = field(default_factory=dict)
    friction: dict[int, float] = field(default_factory=dict)
    slope: dict[int, float] = field(default_factory=dict)
    #: the clutch output's inertia (kg m^2), a property of the mechanics, not of the oil: one for all bands
    inertia: float | None = None
    #: how far (Pa) below the kiss point the hold keeps the plates, by band (none: at it)
    margin: dict[int, float] = field(default_factory=dict)

    def kiss(self, temp_C: float) -> float | None:
        """The learnt kiss point at ``temp_C``, or None if nothing was learnt in its band."""
        return self.kiss_Pa.get(band(temp_C))

    def friction_factor(self, temp_C: float) -> float | None:
        """The learnt friction factor at ``temp_C``, or None if nothing was learnt in its band."""
        return self.friction.get(band(temp_C))

    def friction_slope(self, temp_C: float) -> float | None:
        """The learnt slope of the friction factor with slip at ``temp_C`` (1/(rad/s)), or None."""
        return self.slope.get(band(temp_C))

    def hold_margin(self, temp_C: float) -> float:
        """How far (Pa) below the kiss point the hold keeps the plates at ``temp_C`` (0: nothing learnt)."""
        return self.margin.get(band(temp_C), 0.0)

    def learn(self, temp_C: float, found_Pa: float, friction: float | None = None,
              slope: float | None = None, inertia: float | None = None, crept: bool = False) -> Adaptation:
        """The state after a launch at ``temp_C`` that found the kiss point at ``found_Pa`` and, if it slipped long
        enough to measure them, the friction factor ``friction``, its slope with slip ``slope`` and the clutch
        output's inertia ``inertia``; ``crept``: its plates pushed the waiting vehicle beyond the creep limit."""
        b = band(temp_C)

        def learnt(old: dict[int, float], new: float | None) -> dict[int, float]:
            return old if new is None else old | {b: _blend(old.get(b), new)}

        margin = self.margin | {b: min(self.hold_margin(temp_C) + MARGIN_STEP, MARGIN_MAX)} if crept else self.margin
        # a kiss point found below the floor (within the sensor's noise of zero) is kept at it: a state it
        # writes must load again
        return Adaptation(learnt(self.kiss_Pa, max(found_Pa, KISS_MIN_PA)),
                          self.launches | {b: self.launches.get(b, 0) + 1},
                          learnt(self.friction, friction), learnt(self.slope, slope),
                          self.inertia if inertia is None else _blend(self.inertia, inertia), margin)

    def to_toml(self) -> str:
        bands = [{"from_C": band_from(b), "to_C": band_from(b + 1),
                  "kiss_Pa": v, "launches": self.launches.get(b, 0)}
                 | ({"friction_factor": self.friction[b]} if b in self.friction else {})
                 | ({"friction_slope_per_rad_s": self.slope[b]} if b in self.slope else {})
                 | ({"hold_margin_Pa": self.margin[b]} if b in self.margin else {})
                 for b, v in sorted(self.kiss_Pa.items())]
        top = {"band_C": BAND_C} | ({"output_inertia_kg_m2": self.inertia} if self.inertia is not None else {})
        return ("# wetclutch adaptation state: the clutch output's inertia (kg m^2); per oil-temperature band: kiss "
                "point (Pa), friction factor (-), its slope with slip (1/(rad/s)), the hold's margin below the kiss "
                "point (Pa)\n"
                + tomli_w.dumps(top | {"band": bands}))


#: the least kiss point (Pa) a state may hold. The model bounds a kiss point only by zero: the design's ``p_kiss``
#: takes 0..5e6 Pa, and the ranges' kiss point offset of -0.3 bar stops where the prestress reaches zero (the
#: stroke's ``k_reset x_contact / A_p`` left, 0.2 bar on the built-in rig). The floor is what a launch can learn
#: instead: a kiss point is a pressure the controller measured, and 0.01 bar is half the pressure sensor's noise
#: (0.02 bar, :data:`wetclutch.rig.sensors.DEFAULT_SENSORS`) and a thirtieth of the ranges' spread of kiss points.
#: A kiss point written in bar is at most 50 (the 5e6 Pa a state may hold), far below it.
KISS_MIN_PA = 0.01e5


def loads(text: str, source: str = "adaptation file") -> Adaptation:
    """An adaptation state from its TOML text (one-line errors naming the field)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise WetclutchError(f"{source}: not valid TOML: {str(e).splitlines()[0]}") from None
    unknown = sorted(set(data) - {"band_C", "band", "output_inertia_kg_m2"})
    if unknown:
        raise WetclutchError(f"{source}: {unknown[0]}: unknown field")
    if data.get("band_C") != BAND_C:
        raise WetclutchError(f"{source}: band_C must be {BAND_C:g} (got {shown(data.get('band_C'))})")
    inertia = data.get("output_inertia_kg_m2")
    if inertia is not None and (not finite_number(inertia) or not 0.0 <= inertia <= J1_MAX):
        raise WetclutchError(f"{source}: output_inertia_kg_m2: must be a number in 0..{J1_MAX:g} "
                             f"(got {shown(inertia)})")
    kiss, count, fric, slopes, margins = {}, {}, {}, {}, {}
    rows = data.get("band", [])
    if not isinstance(rows, list):
        raise WetclutchError(f"{source}: band must be an array of tables")
    for i, row in enumerate(rows):
        where = f"{source}: band[{i}]"
        if not isinstance(row, dict):
            raise WetclutchError(f"{where}: must be a table")
        unknown = sorted(set(row) - set(BAND_FIELDS))
        if unknown:
            raise WetclutchError(f"{where}.{unknown[0]}: unknown field")
        # a band the writer wrote has all of these: one without is not a state this product saved
        missing = next((key for key in BAND_REQUIRED if key not in row), None)
        if missing is not None:
            raise WetclutchError(f"{where}.{missing}: missing (every band has {', '.join(BAND_REQUIRED)})")
        lo, hi, v, n = row["from_C"], row["to_C"], row["kiss_Pa"], row["launches"]
        for key, x in (("from_C", lo), ("to_C", hi), ("kiss_Pa", v)):
            if not finite_number(x):
                raise WetclutchError(f"{where}.{key}: must be a finite number (got {shown(x)})")
        b = band(lo)
        # the state is kept by band: a temperature inside a band would be taken for the whole band
        if b not in BANDS or lo != band_from(b):
            raise WetclutchError(f"{where}.from_C: {lo:g} C is not the lower edge of a band "
                                 f"({', '.join(f'{band_from(k):g}' for k in BANDS)} C)")
        if hi != band_from(b + 1):
            raise WetclutchError(f"{where}.to_C: must be from_C + band_C = {band_from(b + 1):g} C (got {hi:g})")
        if b in kiss:
            raise WetclutchError(f"{where}: band {lo:g}..{hi:g} C is given twice (band[{list(kiss).index(b)}] before)")
        if not 0.0 <= v <= 5e6:
            raise WetclutchError(f"{where}.kiss_Pa: {v:g} Pa is outside 0..5e6")
        if v < KISS_MIN_PA:
            raise WetclutchError(f"{where}.kiss_Pa: {v:g} Pa is below {KISS_MIN_PA:g} Pa, the least kiss point a "
                                 "state may hold (in Pa, not bar?)")
        if isinstance(n, bool) or not isinstance(n, int) or n < 0:
            raise WetclutchError(f"{where}.launches: must be a whole number >= 0 (got {shown(n)})")
        kiss[b], count[b] = float(v), n
        learnable = (("friction_factor", fric, FRICTION_RANGE),
                     ("friction_slope_per_rad_s", slopes, (-FRICTION_SLOPE_MAX, FRICTION_SLOPE_MAX)),
                     ("hold_margin_Pa", margins, (0.0, MARGIN_MAX)))
        for key, learnt, (low, high) in learnable:
            if key in row:
                x = row[key]
                if not finite_number(x) or not low <= x <= high:
                    raise WetclutchError(f"{where}.{key}: must be a number in {low:g}..{high:g} (got {shown(x)})")
                learnt[b] = float(x)
    return Adaptation(kiss, count, fric, slopes, None if inertia is None else float(inertia), margins)


def check_plant(state: Adaptation, plant: Params, source: str = "adaptation file") -> Adaptation:
    """``state`` if the plant it is launched on can reach its kiss points, else a one-line error naming the band: a
    kiss point above the highest pressure the plant's supply gives (``min(p_supply, p_relief)``) is none (a state
    from another clutch, or a hand-edited one): the controller would wait for a contact that never comes and hold the
    valve open, slamming the plates before the request."""
    h = plant.hydraulics
    top = min(h.p_supply, h.p_relief)
    for b, kiss in sorted(state.kiss_Pa.items()):
        if kiss >= top:
            raise WetclutchError(f"{source}: band {band_from(b):g}..{band_from(b + 1):g} C: kiss_Pa {kiss:g} Pa is not "
                                 f"below the highest pressure the plant's supply gives, {top:g} Pa "
                                 "(min(hydraulics.p_supply, hydraulics.p_relief))")
    return state


def load(path: str | Path) -> Adaptation:
    """The adaptation state in file ``path``."""
    return loads(read_text(path, "adaptation file"), str(path))
