"""The validated parameter record of the rig, addressed by dotted paths.

Parameters live in sections (``driveline``, ``clutch``, ``engage``); each has a
unit, a one-line description and a physical range. They are read from TOML
files (``--param-file``), overridden one by one (``--set driveline.ratio=0.6``,
the value read as a TOML literal), printed (``wetclutch params show``) and
written back complete (``wetclutch params export``). Every parameter is a finite number (an
integer will do; a boolean or a string will not), and some must fit together: the CVT's limits
in order, the kiss point below the supply and the relief pressures, ``mu(slip)``
positive over the slips of a run and friction left at every oil temperature. These are checked
as a record is built (a section's own again when one of its values is assigned), so a set that
cannot run is refused before any run.

Default values and why (see also ``docs/model.md``, "Default parameters"):

* ``J_p`` 1.2 kg m^2 and ``J_s`` 6.5 kg m^2. The study gives no inertias. The
  primary flywheel stands for an engine-side flywheel of a passenger-car
  flywheel hybrid (a steel disc of about 0.45 m and 50 kg has 1.2 kg m^2).
  The secondary flywheel stands for the vehicle seen from the CVT output: a
  1250 kg car with 0.29 m wheels behind a final drive of 4 has
  1250 * 0.29^2 / 4^2 = 6.6 kg m^2.
* ``J_1`` 1e-3 kg m^2: the clutch output hub and CVT input, which the study
  neglects. A body without inertia cannot slide against a spring, so the
  engine keeps this small inertia; ``tests/test_driveline.py`` shows that
  dividing it by 10 moves no reported figure by more than 0.5 %.
* ``ratio`` 0.5 (``w_r / w_1``, an underdrive launch ratio) and ``eta`` 0.95
  (the study's constant CVT efficiency).
* ``ratio_min`` 0.4, ``ratio_max`` 2.5 and ``ratio_rate`` 1 /s: the limits of the CVT when
  its ratio moves (``wetclutch launch --post-sync-hold``); the study's CVT has none stated.
  A passenger-car push-belt CVT spans a ratio coverage of about 6: from 2.5 (underdrive)
  to 0.4 (overdrive) as input over output speed, so ``w_r / w_1`` from 0.4 to 2.5, with the
  launch ratio near the low end. Its hydraulically clamped pulleys shift at most about
  0.3 to 1 ratio units per second (the flow of the pulley actuators limits it); 1 /s is
  the fast end, a kickdown, which is what holding the torque after lock-up asks for.
* ``k_a`` 480 N m/rad: the locked driveline then rings at 2.1 Hz, the study's
  measured resonance. With power flowing alternately forward and back
  through the CVT, the half periods use the primary inertia seen through
  ``eta`` and ``1/eta``; ``k_a = (2.1 pi (sqrt(J_f) + sqrt(J_b)))^2`` with
  ``J_f``, ``J_b`` the two-mass reduced inertias, which gives 480.6.
* ``d_a`` 5 N m s/rad: about 7 % of critical damping of that mode (the
  study calls the driveline's damping small and nonlinear, air drag); less
  lets a hard launch judder, since above 79 rad/s the study's mu(slip) falls
  with slip (see the field's comment).
* ``b_1`` 2e-5 and ``b_2`` 5e-5 N m s^2: windage of a disc flywheel, about
  0.45 N m at 150 rad/s on the primary.

Valve and hydraulics, calibrated together against the study's figures (see
:mod:`wetclutch.rig.calibration` and ``docs/model.md``):

* ``fb_orifice`` 0.15 mm bore and ``fb_gap_85C`` 8.85e-13 m^3/(s Pa): the valve's pressure
  feedback acts on the stem through a chamber fed by a damping orifice and drained by the
  laminar clearance of the stem's guide (a 2.6 um radial gap). Warm oil leaks more through
  the gap, the orifice drops more pressure, the stem feels less than the outlet pressure and
  the valve settles higher. Evidence: the study's static pressure vs oil temperature at pdc
  0.2 is a straight line in the oil's fluidity 1/viscosity within 0.2 %
  (``p = 3.93 bar + 0.0309 bar Pa s / mu``): the rise is carried by a laminar leak. The drop
  over the orifice grows with the square of the leak, so small pressures (the pdc 0.05 fills,
  the kiss point) hardly feel it. The gap is fitted to that curve together with the magnet
  below (the whole-clutch DC curve at 85 C is measured through the same feedback).
* ``I_hyst`` 0.045 A: the magnet's hysteresis (a play on the coil current), about 3 % of
  the 1.4 A the valve test reaches; the up and down staircases of the valve test then
  differ by about 0.15 bar under 1 kHz PWM. ``play_exponent`` 8, the play's smoothing
  (:mod:`wetclutch.physics.actuator`), is chosen, not fitted: the study's valve hysteresis shows
  how far the up and down staircases lie apart, not the shape of the loop's corners.
* ``k_F1`` 8.52 N/A, ``k_F2`` 3.0 N/A^2, ``F_preload`` 0.30 N, ``I_sat`` 0.70 A (force rising
  only linearly above it: saturated iron), ``port_width`` 21.5 mm, ``overlap`` 43 um and
  ``flow_force`` 0.32 (a partly compensated spool): fitted, with the feedback chamber,
  to the whole-clutch DC curve at 85 C, the valve test's ``24 pdc - 1.38`` (the droop of
  the pressure-reducing valve under 32 l/min), the static pressure vs oil temperature and
  the four dead times at once (:mod:`wetclutch.rig.calibration`; the pdc 0.05 dead times
  hinge on the force at 0.2 A, the metering edge's width on the low-duty fill).
* ``feed_orifice`` 13.85 mm^2, ``line_length`` 1.45 m, ``x_contact`` 1.37 mm with
  ``k_reset`` 1.784e5 N/m (contact still at 0.70 bar): the clutch fill, which sets the
  dead times (0.1 s and 0.2 s at pdc 0.2, 85 and 41 C).
* ``seal_orifice`` 0 (laminar seal leakage only): a turbulent seal leak lowered by the
  viscous feed line would also make the cold pressure lower, but with the wrong shape (a
  viscous loss falls fastest at low temperature, the study's curve rises fastest at high
  temperature) and at the cost of the DC curve and the small-input dead times.
* ``C_pack`` 1500 J/K, ``h_oil`` 25 W/K: see :class:`Thermal`.
"""

from __future__ import annotations

import os
import tomllib
import weakref
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import tomli_w
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator
from pydantic_core import PydanticCustomError

from .errors import ParameterError, WetclutchError, check_number, read_text

#: oil temperatures (C) at which the rig runs and the oil model holds; every oil temperature is checked against it
OIL_TEMP_RANGE_C = (-30.0, 150.0)


def check_oil_temp(temp_C: float, name: str) -> float:
    """``temp_C`` if it lies within :data:`OIL_TEMP_RANGE_C`, else a one-line error naming ``name``."""
    lo, hi = OIL_TEMP_RANGE_C
    try:
        temp_C = check_number(temp_C, name, "C")
    except WetclutchError as e:
        raise ParameterError(str(e)) from None
    if not lo <= temp_C <= hi:
        raise ParameterError(f"{name} {temp_C:g} C is outside {lo:g}..{hi:g} C")
    return float(temp_C)


def _f(default: float, unit: str, description: str, **bounds: float) -> Any:
    return Field(default, description=description, json_schema_extra={"unit": unit}, **bounds)


#: error type of a check that spans several parameters; its message names them all and is shown as it stands
_INCONSISTENT = "inconsistent"


def _inconsistent(message: str) -> PydanticCustomError:
    """The validation error of parameters that do not fit together; ``message`` names each of them."""
    # the message goes in as context, not as the template, so that braces in it are not read as fields
    return PydanticCustomError(_INCONSISTENT, "{message}", {"message": message})


class _RefusesInOneLine(type(BaseModel)):
    """The metaclass of the sections and of :class:`Params`: ``Driveline(ratio=-1)``, ``Params(...)`` refuse a value
    as a one-line :class:`ParameterError` naming it as a parameter file would (``driveline.ratio``).

    (An ``__init__`` of its own would do the same, but pydantic's validation then runs each record's checks twice.)
    """

    def __call__(cls, *args: Any, **kwargs: Any) -> Any:
        with _in_one_line(_section_name(cls)):
            return super().__call__(*args, **kwargs)


class _Section(BaseModel, metaclass=_RefusesInOneLine):
    # strict: a boolean or a string given for a number is a mistake in the file or on the command line, not a
    # number (pydantic's lax mode reads ``true`` as 1.0 and ``"0.5"`` as 0.5); integers still pass as floats.
    # allow_inf_nan off: every parameter is a finite number, and NaN is refused as such, not by a failed bound.
    # revalidate_instances: a section given as an instance (``Params(driveline=d)``, ``p.driveline = d``) is
    # validated into a copy, so that two records never share a section
    model_config = ConfigDict(extra="forbid", validate_assignment=True, frozen=False, strict=True,
                              allow_inf_nan=False, revalidate_instances="always")

    def __setattr__(self, name: str, value: Any) -> None:
        """Assign and validate ``name``; a refused value is a one-line :class:`ParameterError` naming the parameter
        and leaves the old one in place.

        pydantic runs a section's model validators after it has stored the new value, so without
        this a refused assignment would leave the section holding the very value it refused. A section of a
        :class:`Params` is then checked with the rest of that record (the checks across sections: ``mu(slip)``
        positive up to ``driveline.omega_p0``).
        """
        fields = type(self).model_fields
        old = self.__dict__.get(name)
        try:
            super().__setattr__(name, _plain(value))
        except ValidationError as err:
            if name in fields:
                self.__dict__[name] = old
            raise ParameterError(_one_line(err, _section_name(type(self)))) from None
        holder = _holder(self)
        if holder is not None and name in fields:
            try:
                holder._friction_positive_over_slip()
            except PydanticCustomError as err:
                self.__dict__[name] = old
                raise ParameterError(err.message()) from None

    @classmethod
    def model_validate(cls, obj: Any, *args: Any, **kwargs: Any) -> Any:
        """pydantic's, with a refusal as a one-line :class:`ParameterError` naming the parameter."""
        with _in_one_line(_section_name(cls)):
            return super().model_validate(obj, *args, **kwargs)

    @classmethod
    def model_validate_json(cls, json_data: Any, *args: Any, **kwargs: Any) -> Any:
        """pydantic's, with a refusal as a one-line :class:`ParameterError` naming the parameter."""
        with _in_one_line(_section_name(cls)):
            return super().model_validate_json(json_data, *args, **kwargs)

    def model_copy(self, *, update: Mapping[str, Any] | None = None, deep: bool = True) -> Any:
        """A copy that shares nothing with this one (changing one never changes the other, whatever ``deep``), with
        the values of ``update`` (field name -> value) put in and checked like any other.

        Raises
        ------
        ParameterError
            One line naming an unknown field or a refused value.
        """
        data = self.model_dump()
        if update is not None:
            if not isinstance(update, Mapping):
                raise ParameterError(f"update must be a mapping of field name -> value, not {type(update).__name__}")
            data |= {k: v.model_dump() if isinstance(v, BaseModel) else _plain(v) for k, v in update.items()}
        return type(self).model_validate(data)


class Driveline(_Section):
    """Flywheels, CVT and flexible axle."""

    J_p: float = _f(1.2, "kg m^2", "primary flywheel inertia", gt=0.0, le=1e3)
    J_1: float = _f(1e-3, "kg m^2", "clutch output + CVT input inertia (neglected by the study)", gt=0.0, le=1e2)
    J_s: float = _f(6.5, "kg m^2", "secondary (vehicle-equivalent) flywheel inertia", gt=0.0, le=1e4)
    b_1: float = _f(2e-5, "N m s^2", "primary air drag coefficient (T = b_1 w|w|)", ge=0.0, le=1.0)
    b_2: float = _f(5e-5, "N m s^2", "secondary air drag coefficient (T = b_2 w|w|)", ge=0.0, le=1.0)
    ratio: float = _f(0.5, "-", "CVT speed ratio i = w_r / w_1", gt=0.05, le=20.0)
    eta: float = _f(0.95, "-", "CVT efficiency, either power-flow direction", gt=0.0, le=1.0)
    ratio_min: float = _f(0.4, "-", "least CVT ratio w_r / w_1 when the ratio moves (full underdrive)", gt=0.05,
                          le=20.0)
    ratio_max: float = _f(2.5, "-", "greatest CVT ratio w_r / w_1 when the ratio moves (full overdrive)", gt=0.05,
                          le=20.0)
    ratio_rate: float = _f(1.0, "1/s", "fastest change of the CVT ratio w_r / w_1, either way", gt=0.0, le=100.0)
    k_a: float = _f(480.0, "N m/rad", "flexible axle torsional stiffness", gt=0.0, le=1e8)
    # The study gives no damping figure. 5 N m s/rad keeps the slip phase free of
    # friction-induced judder: above 79 rad/s the study's mu(slip) falls with slip, a
    # negative damping F_n |dmu/dw| on the CVT input that the axle damping, seen through
    # the ratio (d_a i^2), must outweigh up to the 150 N m of a hard launch.
    d_a: float = _f(5.0, "N m s/rad", "flexible axle damping", ge=0.0, le=1e5)
    omega_p0: float = _f(150.0, "rad/s", "primary flywheel speed at the start of a run", ge=0.0, le=2000.0)

    @model_validator(mode="after")
    def _ratio_within_limits(self) -> Driveline:
        """Refuse CVT limits that are crossed.

        Returns
        -------
        Driveline
            This section, unchanged.

        Raises
        ------
        PydanticCustomError
            ``ratio_min`` above ``ratio_max``.
        """
        if self.ratio_min > self.ratio_max:
            raise _inconsistent(f"driveline.ratio_min {self.ratio_min:g} must not exceed driveline.ratio_max "
                                f"{self.ratio_max:g}")
        return self


class Clutch(_Section):
    """Friction behaviour of the wet clutch that the driveline engine needs."""

    peak: float = _f(1.0, "-", "static / sliding torque capacity ratio (breakaway)", ge=1.0, le=3.0)


class Engage(_Section):
    """The ``engage`` scenario: capacity ramp and road load."""

    T_cap: float = _f(40.0, "N m", "clutch torque capacity level reached by the ramp", ge=0.0, le=5e3)
    t_start: float = _f(0.5, "s", "time the capacity ramp starts", ge=0.0, le=1e3)
    t_ramp: float = _f(0.3, "s", "duration of the capacity ramp", gt=0.0, le=1e3)
    T_load: float = _f(10.0, "N m", "road load: brake torque on the secondary flywheel", ge=0.0, le=5e3)


class Valve(_Section):
    """Proportional pressure-reducing valve: electronics, coil, magnet, stem."""

    V_supply: float = _f(24.0, "V", "supply voltage of the valve amplifier / PWM stage", gt=0.0, le=100.0)
    R_coil: float = _f(6.0, "ohm", "coil resistance", gt=0.0, le=1e3)
    L_coil: float = _f(0.1, "H", "coil inductance", gt=0.0, le=10.0)
    R_freewheel: float = _f(30.0, "ohm", "freewheel resistance when the output transistor blocks", ge=0.0, le=1e4)
    amp_gain: float = _f(200.0, "V/A", "current-controller gain of the DC amplifier", gt=0.0, le=1e5)
    g_current: float = _f(0.2, "A/V", "DC mode: coil current setpoint per input volt", gt=0.0, le=10.0)
    pwm_freq: float = _f(1000.0, "Hz", "PWM frequency", gt=0.0, le=1e5)
    k_F1: float = _f(8.52, "N/A", "magnet force, linear coefficient (in the magnetising current I_m)", ge=0.0, le=1e4)
    k_F2: float = _f(3.0, "N/A^2", "magnet force, quadratic coefficient", ge=0.0, le=1e4)
    F_preload: float = _f(0.30, "N", "spring preload on the stem towards opening", ge=-100.0, le=100.0)
    A_fb: float = _f(1.96e-5, "m^2", "stem area under pressure feedback", gt=0.0, le=1e-2)
    m_stem: float = _f(0.01, "kg", "moving mass of stem and armature", gt=0.0, le=10.0)
    c_stem: float = _f(4400.0, "N/m", "stem spring stiffness", gt=0.0, le=1e7)
    d_stem: float = _f(60.0, "N s/m", "stem viscous damping", ge=0.0, le=1e5)
    F_friction: float = _f(0.1, "N", "stem/armature Coulomb friction (dithered out by PWM)", ge=0.0, le=100.0)
    I_hyst: float = _f(0.045, "A", "magnetic hysteresis: half-width of the play between coil and magnetising current", ge=0.0, le=1.0)
    play_exponent: float = _f(8.0, "-", "sharpness of the play: dI_m/dt = dI/dt min(z, 1)^n, z the lag over I_hyst "
                              "(a whole number; larger: sharper, the ideal play as it grows)", ge=1.0, le=64.0)
    I_sat: float = _f(0.70, "A", "coil current above which the magnet force rises only linearly (iron saturation)", gt=0.0, le=1e3)
    overlap: float = _f(4.3e-5, "m", "land overlap around the null position", ge=0.0, le=1e-2)
    x_port: float = _f(5e-3, "m", "stem travel over which a port opens fully (the magnet's working stroke)", gt=0.0, le=1e-1)
    port_width: float = _f(0.0215, "m", "circumferential width of the metering edge", gt=0.0, le=1.0)
    C_d: float = _f(0.65, "-", "orifice discharge coefficient", gt=0.0, le=1.0)
    flow_force: float = _f(0.32, "-", "steady flow force coefficient: F = flow_force * 2 C_d w x dp cos(69 deg)", ge=0.0, le=5.0)
    fb_orifice: float = _f(1.767e-8, "m^2", "damping orifice into the stem's feedback chamber, 0.15 mm bore (0: the stem feels the outlet pressure); with fb_gap_85C it makes the static pressure rise with oil temperature as the study measured", ge=0.0, le=1e-4)
    fb_gap_85C: float = _f(8.85e-13, "m^3/(s Pa)", "laminar clearance of the stem's guide out of the feedback chamber at 85 C (scales with 1/viscosity; a 2.6 um radial gap, 5 mm stem, 3 mm land); fitted to the study's static pressure vs oil temperature", ge=0.0, le=1e-8)
    fb_vent: float = _f(0.0, "m^2", "vent bore of the stem guide's leakage to the tank (0: unrestricted)", ge=0.0, le=1e-4)

    @field_validator("play_exponent")
    @classmethod
    def _whole(cls, n: float) -> float:
        if n != int(n):
            raise ValueError("must be a whole number")
        return n


class Hydraulics(_Section):
    """Supply, line, oil volume and piston of the clutch."""

    p_supply: float = _f(8e5, "Pa", "pump pressure (gauge)", gt=0.0, le=5e6)
    line_diameter: float = _f(4e-3, "m", "supply line diameter (laminar loss)", gt=0.0, le=0.1)
    line_length: float = _f(1.45, "m", "supply line length (laminar loss)", ge=0.0, le=100.0)
    feed_orifice: float = _f(1.385e-5, "m^2", "area of the feed restriction of the clutch installation (0: none)", ge=0.0, le=1e-2)
    V0: float = _f(1e-4, "m^3", "oil volume behind the valve with the piston at its stop", gt=0.0, le=1e-2)
    A_p: float = _f(0.0122, "m^2", "piston area", gt=0.0, le=1.0)
    k_reset: float = _f(1.784e5, "N/m", "reset spring stiffness", gt=0.0, le=1e9)
    p_prestress: float = _f(0.5e5, "Pa", "pressure at which the piston starts to move", ge=0.0, le=5e6)
    x_contact: float = _f(1.37e-3, "m", "piston travel until the plates touch", gt=0.0, le=0.05)
    leak_85C: float = _f(2.4e-12, "m^3/(s Pa)", "seal leakage conductance at 85 C (scales with 1/viscosity)", ge=0.0, le=1e-6)
    leak_orifice: float = _f(0.0, "m^3/(s Pa^0.5)", "turbulent leakage of the rotating seal rings, Q = K sqrt(p)", ge=0.0, le=1e-4)
    seal_orifice: float = _f(0.0, "m^3/(s Pa^0.5)", "turbulent orifice in series with the laminar seal gap (leak_85C): p = Q/G + (Q/K)^2; 0: laminar only", ge=0.0, le=1e-4)
    p_relief: float = _f(8e5, "Pa", "relief valve cracking pressure", gt=0.0, le=5e6)
    relief_conductance: float = _f(1e-9, "m^3/(s Pa)", "relief valve flow per Pa above cracking", gt=0.0, le=1e-3)
    air_fraction: float = _f(0.005, "-", "entrained air volume fraction at atmospheric pressure", ge=0.0, lt=0.5)

    @model_validator(mode="after")
    def _plates_reachable(self) -> Hydraulics:
        """Refuse a clutch whose plates touch only at or above the pressure the supply or the relief valve allows.

        The plates touch at ``p_prestress + k_reset x_contact / A_p`` (the kiss point,
        :func:`wetclutch.physics.actuator.contact_pressure`); the clutch pressure rises at most to
        the supply pressure and stops rising where the relief valve cracks. A kiss point at or
        above either is a clutch that never carries torque.

        Returns
        -------
        Hydraulics
            This section, unchanged.

        Raises
        ------
        PydanticCustomError
            The kiss point is not below ``p_supply`` or not below ``p_relief``.
        """
        # the section cannot call actuator.contact_pressure (it takes a whole Params, and actuator imports this
        # module); the same formula on the section's own fields
        kiss = self.p_prestress + self.k_reset * self.x_contact / self.A_p
        for name, limit in (("p_supply", self.p_supply), ("p_relief", self.p_relief)):
            if not kiss < limit:
                raise _inconsistent(f"hydraulics.{name} {limit:g} Pa is not above the kiss point {kiss:g} Pa "
                                    f"(hydraulics.p_prestress {self.p_prestress:g} Pa + k_reset x_contact / A_p): "
                                    "the clutch would never carry torque")
        return self


class Friction(_Section):
    """Plate friction: T_max = mu(slip) * mu_scale * F_n * F_n / (F_n + F_knee), mu turned by mu_slope about its mean over 0..mu_slip_span."""

    mu_slip_poly: list[float] = Field(
        [-1.7e-6, 2.7e-4, 2.6e-2],
        description="mu vs slip (rad/s) polynomial, highest power first (lumped: faces x radius x coefficient)",
        json_schema_extra={"unit": "m"},
        min_length=1,
        max_length=8,
    )
    mu_scale: float = _f(1.0, "-", "multiplier on mu (unit-to-unit and condition spread)", gt=0.0, le=10.0)
    mu_slope: float = _f(1.0, "-", "multiplier on mu's change with slip about its mean over 0..mu_slip_span (curve steepness)",
                         ge=0.0, le=10.0)
    mu_slip_span: float = _f(150.0, "rad/s", "slip range (from 0) over which mu_slope keeps the mean of mu (a launch's slip)",
                            ge=0.0, le=1e3)
    F_knee: float = _f(100.0, "N", "normal force below which friction drops (plates barely pressed)", ge=0.0, le=1e5)
    drag_20C: float = _f(0.013, "N m s", "open-clutch viscous drag coefficient at 20 C (scales with viscosity)", ge=0.0, le=10.0)

    def curve(self) -> np.ndarray:
        """The ``mu(slip)`` coefficients (highest power first) the model runs on: ``mu_slip_poly`` at level
        ``mu_scale`` and steepness ``mu_slope``.

        ``mu'(w) = mu_scale * (m + mu_slope * (mu(w) - m))`` with ``m`` the mean of ``mu`` over slips
        ``0 .. mu_slip_span`` (its value at zero slip if ``mu_slip_span`` is 0): the slip-dependent terms are
        multiplied by ``mu_slope`` and the constant moved so that the mean over that span is ``mu_scale * m``
        whatever the steepness.
        """
        c = np.asarray(self.mu_slip_poly, dtype=float)
        ref = float(np.polyval(np.polyint(c), self.mu_slip_span)) / self.mu_slip_span if self.mu_slip_span > 0.0 \
            else float(c[-1])
        out = c * self.mu_slope
        out[-1] += (1.0 - self.mu_slope) * ref
        return out * self.mu_scale


class Thermal(_Section):
    """Heat of the clutch pack: a lumped heat capacity cooled by the oil flowing through it."""

    # 16 plates of a 0.2 m clutch: 8 steel separators (~0.25 kg) and 8 friction plates' steel
    # cores (~0.15 kg), 3.2 kg of steel at 460 J/(kg K), plus the oil between them: ~1500 J/K
    C_pack: float = _f(1500.0, "J/K", "heat capacity of the clutch pack (plates and the oil between them)", gt=0.0, le=1e6)
    # a cooling flow of ~1 l/min of ATF (rho c = 1.6 MJ/(m^3 K)) carries at most 27 W/K; the
    # plates' surfaces pass about that to it: 25 W/K, a cooling time constant C/h of 60 s
    h_oil: float = _f(25.0, "W/K", "heat transfer from the plates to the cooling oil flow", gt=0.0, le=1e5)
    mu_temp: float = _f(0.0, "1/K", "relative change of friction per kelvin of plate temperature (0: none, as the study found)", ge=-0.05, le=0.05)
    T_mu_ref_C: float = _f(85.0, "C", "plate temperature at which friction has its nominal value", ge=-30.0, le=400.0)
    T_plate_limit_C: float = _f(200.0, "C", "plate temperature above which the launch report warns (paper linings and ATF age fast above it)", gt=0.0, le=600.0)

    @model_validator(mode="after")
    def _friction_at_every_oil_temperature(self) -> Thermal:
        """Refuse a temperature law that leaves the clutch without friction at an oil temperature the rig runs at.

        The capacity is multiplied by ``1 + mu_temp (T - T_mu_ref_C)`` (clipped at 0,
        :func:`wetclutch.physics.thermal.friction_factor`); a run's plates start at the oil's
        temperature, anywhere in :data:`OIL_TEMP_RANGE_C`. The factor is linear in ``T``, so it is
        positive over that range if it is at both ends. Hotter plates may still fade to no
        friction (the clip): that is a state of a run, not of the parameters.

        Returns
        -------
        Thermal
            This section, unchanged.

        Raises
        ------
        PydanticCustomError
            The factor is not positive at one end of the oil temperature range.
        """
        for temp in OIL_TEMP_RANGE_C:
            factor = 1.0 + self.mu_temp * (temp - self.T_mu_ref_C)
            if not factor > 0.0:
                raise _inconsistent(f"thermal.mu_temp {self.mu_temp:g} 1/K with thermal.T_mu_ref_C "
                                    f"{self.T_mu_ref_C:g} C leaves no friction at oil temperature {temp:g} C "
                                    f"(1 + mu_temp (T - T_mu_ref_C) = {factor:g}); runs start at oil temperatures "
                                    f"{OIL_TEMP_RANGE_C[0]:g}..{OIL_TEMP_RANGE_C[1]:g} C")
        return self


class Rig(_Section):
    """Conditions of an experiment on the virtual rig."""

    oil_temp_C: float = _f(85.0, "C", "oil temperature (held constant during a run)", ge=OIL_TEMP_RANGE_C[0],
                          le=OIL_TEMP_RANGE_C[1])


@contextmanager
def _in_one_line(section: str = "") -> Iterator[None]:
    """pydantic's refusal inside the block as a one-line :class:`ParameterError` naming the parameter (its path
    below ``section``, if given)."""
    try:
        yield
    except ValidationError as err:
        raise ParameterError(_one_line(err, section)) from None


class Params(_Section):
    """All parameters of the rig and its scenarios, SI units.

    ``Params(driveline={"ratio": 0.6})``, ``Params.model_validate(...)``, ``model_copy(update=...)`` and assignments
    (``p.driveline.ratio = 0.6``) are checked; a refused value is a one-line :class:`ParameterError` naming the
    parameter. A section given as an instance is copied, not shared.
    """

    driveline: Driveline = Field(default_factory=Driveline)
    clutch: Clutch = Field(default_factory=Clutch)
    engage: Engage = Field(default_factory=Engage)
    valve: Valve = Field(default_factory=Valve)
    hydraulics: Hydraulics = Field(default_factory=Hydraulics)
    friction: Friction = Field(default_factory=Friction)
    thermal: Thermal = Field(default_factory=Thermal)
    rig: Rig = Field(default_factory=Rig)

    @model_validator(mode="after")
    def _friction_positive_over_slip(self) -> Params:
        """Refuse a friction law whose ``mu(slip)`` is not positive over the slips of a run.

        A run starts with the primary at ``driveline.omega_p0`` and the clutch output at rest, so
        the slip runs through ``0 .. omega_p0``; the model runs on the curve of
        :meth:`Friction.curve` (``mu_slip_poly`` times ``mu_scale``, turned by
        ``mu_slope`` about its mean over ``0 .. mu_slip_span``). Where that is zero the controller and
        the design divide by it; where it is negative the clutch would drive instead of brake.

        Returns
        -------
        Params
            This record, unchanged.

        Raises
        ------
        PydanticCustomError
            ``mu`` is zero or negative somewhere in ``0 .. omega_p0``.
        """
        _hold(self)
        f, span = self.friction, self.driveline.omega_p0
        slip, mu = lowest_mu(f, span)
        if not mu > 0.0:
            shaped = ("" if f.mu_scale == 1.0 and f.mu_slope == 1.0
                      else " (times friction.mu_scale, turned by friction.mu_slope)")
            raise _inconsistent(f"friction.mu_slip_poly {_shown(f.mu_slip_poly)}: mu(slip){shaped} must be > 0 for "
                                f"slip 0..{span:g} rad/s (0..driveline.omega_p0); it is {mu:.3g} at {slip:.4g} rad/s")
        return self

    def __deepcopy__(self, memo: dict[int, Any] | None = None) -> Params:
        new = super().__deepcopy__(memo)
        _hold(new)
        return new

    def __setstate__(self, state: dict[Any, Any]) -> None:
        super().__setstate__(state)
        _hold(self)


#: the record that holds each section, by the section's id (the entry goes with the section): a value assigned to a
#: section is checked with the rest of its record
_HOLDERS: dict[int, weakref.ref] = {}


def _hold(params: Params) -> None:
    """Tie each section of ``params`` to it."""
    for name in Params.model_fields:
        section = params.__dict__.get(name)
        if section is None:
            continue
        key = id(section)
        if key not in _HOLDERS:
            weakref.finalize(section, _HOLDERS.pop, key, None)
        _HOLDERS[key] = weakref.ref(params)


def _holder(section: _Section) -> Params | None:
    """The record that holds ``section`` (None: a section on its own, or one since replaced in its record)."""
    ref = _HOLDERS.get(id(section))
    params = ref() if ref is not None else None
    name = _section_name(type(section))
    if params is None or params.__dict__.get(name) is not section:
        return None
    return params


def _section_name(kind: type[_Section]) -> str:
    """The name of a section of kind ``kind`` in a :class:`Params` (``driveline``), or "" for a whole record."""
    return next((name for name, info in Params.model_fields.items() if info.annotation is kind), "")


def lowest_mu(f: Friction, slip_max: float) -> tuple[float, float]:
    """The least ``mu`` of the friction law ``f`` (as the model runs it) over slips ``0 .. slip_max``, and where.

    Parameters
    ----------
    f
        The friction section.
    slip_max
        The greatest slip (rad/s), at least 0.

    Returns
    -------
    tuple[float, float]
        ``(slip, mu)``: the slip (rad/s) at which ``mu`` (m) is least, and that ``mu``.
    """
    coef = f.curve()
    # the least of a polynomial on an interval lies at an end or where its derivative vanishes; a grid besides
    # guards against roots lost to rounding (every candidate is a true value, so none can refuse a good law)
    slips = [np.linspace(0.0, slip_max, 65)]
    if coef.size > 2:
        crit = np.roots(np.polyder(coef))
        slips.append(np.clip(crit.real, 0.0, slip_max))
    s = np.concatenate(slips)
    mu = np.polyval(coef, s)
    i = int(np.argmin(mu))
    return float(s[i]), float(mu[i])


#: what a parameter must be, by pydantic's error type, where its own message speaks of Python ("Input should be a
#: valid number" for a boolean, a string or a table; NaN failing a bound as if it were a number)
_MUST_BE = {
    "float_type": "must be a number",
    "finite_number": "must be a finite number",
    "list_type": "must be an array of numbers",
}


def _shown(value: Any) -> str:
    """``value`` as it would be written in a parameter file or after ``--set`` (TOML), for an error message."""
    if isinstance(value, dict):
        text = "{" + ", ".join(f"{k} = {_shown(v)}" for k, v in value.items()) + "}"
    elif isinstance(value, (list, tuple)):
        text = "[" + ", ".join(_shown(v) for v in value) + "]"
    else:
        try:
            text = _literal(value)
        except (TypeError, ValueError):  # not a TOML value (None, an object given through the Python API)
            text = repr(value)
    # one line, and short: the parameter's name comes first and must not drown
    text = text.encode("unicode_escape").decode()
    return text if len(text) <= 80 else text[:77] + "..."


def _one_line(err: ValidationError, section: str = "") -> str:
    """The first error of ``err`` on one line, naming the parameter (its path below ``section``, if given)."""
    e = err.errors()[0]
    path = ".".join(str(p) for p in ((section,) if section else ()) + tuple(e["loc"])).encode("unicode_escape").decode()
    if e["type"] == "model_type":
        what = f"'{path}' must be a table of parameters" if path else \
            f"a parameter set must be a table of sections ({', '.join(Params.model_fields)})"
        return f"{what}, not {type(e.get('input')).__name__} (got {_shown(e.get('input'))})"
    if e["type"] in ("extra_forbidden", "no_such_attribute"):
        return f"unknown parameter '{path}'"
    if e["type"] == _INCONSISTENT:
        # a check across parameters: its message names each of them with its value
        return e["msg"]
    msg = _MUST_BE.get(e["type"]) or e["msg"].removeprefix("Value error, ")  # a validator's own message
    return f"parameter '{path}': {msg} (got {_shown(e.get('input'))})"


def _validate(data: dict[str, Any]) -> Params:
    return Params.model_validate(data)


def _merge(base: dict[str, Any], path: str, value: Any) -> None:
    keys = path.split(".")
    node = base
    for k in keys[:-1]:
        nxt = node.get(k)
        if not isinstance(nxt, dict):
            raise ParameterError(f"unknown parameter {path!r}")
        node = nxt
    if keys[-1] not in node:
        raise ParameterError(f"unknown parameter {path!r}")
    if isinstance(node[keys[-1]], dict):
        raise ParameterError(f"'{path}' is a section, not a parameter (name one, e.g. '{path}.{next(iter(node[keys[-1]]))}')")
    node[keys[-1]] = value


def load(
    param_file: str | Path | None = None,
    overrides: dict[str, Any] | None = None,
    base: Params | None = None,
) -> Params:
    """Build a parameter record: defaults (or ``base``), then ``param_file``, then ``overrides``.

    Parameters
    ----------
    param_file
        A TOML file with any subset of the sections and keys.
    overrides
        Dotted path -> value, e.g. ``{"driveline.ratio": 0.6}``.

    Raises
    ------
    ParameterError
        One line naming the offending file or parameter.
    """
    if base is not None and not isinstance(base, Params):
        raise ParameterError(f"base must be a parameter set (wetclutch.load_params(...)), not {type(base).__name__}")
    if param_file is not None and not isinstance(param_file, (str, os.PathLike)):
        raise ParameterError(f"param_file must be a path (str or pathlib.Path), not {type(param_file).__name__}")
    if overrides is not None and not isinstance(overrides, Mapping):
        raise ParameterError("overrides must be a mapping of dotted parameter path -> value, e.g. "
                             f"{{'driveline.ratio': 0.6}}, not {type(overrides).__name__}")
    if overrides is not None and (bad := next((k for k in overrides if not isinstance(k, str)), None)) is not None:
        raise ParameterError(f"overrides: a parameter path must be a string such as 'driveline.ratio' (got {bad!r})")
    data = (base or Params()).model_dump()
    if param_file is not None:
        path = Path(param_file)
        text = read_text(path, "parameter file", ParameterError)
        try:
            given = tomllib.loads(text)
        except tomllib.TOMLDecodeError as err:
            reason = str(err).replace("\n", " ")
            raise ParameterError(f"parameter file '{path}' is not valid TOML: {reason}") from None
        try:
            for dotted, value in flatten(given).items():
                _merge(data, dotted, value)
            # the file on its own: an error in it names the file (a controller file given as a parameter file would
            # say only "unknown parameter 'kind'")
            from_file = _validate(data)
        except ParameterError as err:
            raise ParameterError(f"parameter file '{path}': {err}") from None
        if not overrides:
            return from_file
    for dotted, value in (overrides or {}).items():
        _merge(data, dotted, _plain(value))
    return _validate(data)


def _plain(value: Any) -> Any:
    """An override as TOML would give it: a numpy array, tuple or numpy number (``np.polyfit``'s coefficients) as a
    list of Python numbers or a Python number; anything else as it is, for the check to judge."""
    if isinstance(value, (np.ndarray, np.generic)):
        return value.tolist()
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def flatten(d: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """Dotted path -> value of a nested table (``{"a": {"b": 1}}`` -> ``{"a.b": 1}``)."""
    out: dict[str, Any] = {}
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(flatten(v, key + "."))
        else:
            out[key] = v
    return out


def parse_set(item: str) -> tuple[str, Any]:
    """Parse one ``--set path=value`` item; the value is a TOML literal (``1.2``, ``[1, 2]``)."""
    if "=" not in item:
        raise ParameterError(f"--set {item!r}: expected PATH=VALUE")
    path, _, raw = item.partition("=")
    path = path.strip()
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        raise ParameterError(f"--set {path!r}: {raw!r} is not a TOML value") from None
    return path, value


def describe(params: Params) -> list[tuple[str, Any, str, str]]:
    """Rows ``(dotted path, value, unit, description)`` for every parameter."""
    rows = []
    for sname, section in params:
        for fname, info in type(section).model_fields.items():
            extra = info.json_schema_extra or {}
            rows.append((f"{sname}.{fname}", getattr(section, fname), str(extra.get("unit", "")), info.description or ""))
    return rows


def _literal(value: Any) -> str:
    """A TOML literal on one line (tomli_w would spread a list over several)."""
    if isinstance(value, list):
        return "[" + ", ".join(_literal(v) for v in value) + "]"
    return tomli_w.dumps({"v": value}).split("=", 1)[1].strip()


def to_toml(params: Params) -> str:
    """A complete TOML file, one commented line per parameter, that :func:`load` reads back identically."""
    lines = ["# wetclutch parameters, SI units", ""]
    current = None
    for path, value, unit, desc in describe(params):
        section, key = path.split(".", 1)
        if section != current:
            if current is not None:
                lines.append("")
            lines.append(f"[{section}]")
            current = section
        lines.append(f"{key} = {_literal(value)}  # [{unit}] {desc}")
    return "\n".join(lines) + "\n"
