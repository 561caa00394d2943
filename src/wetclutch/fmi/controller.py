"""A launch controller as a stepped model: the measured channels and the request in, the valve input out.

:class:`Controller` is what the controller FMU runs (:mod:`wetclutch.fmi.controller_fmu`):
the compiled controller of :mod:`wetclutch.launch.controller` on the record of a design
(:func:`wetclutch.launch.design.record`: a controller kind designed on a plant, or a
controller file), sampled once per step as the closed launch loop samples it.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..errors import WetclutchError
from ..launch import adaptation
from ..launch import controller as control
from ..launch import design

#: inputs: the measured channels (SI; oil temperature in C) and the torque request (N m)
INPUTS = (*control.MEASURED, "t_ref")


class Controller:
    """A launch controller, one sample per call of :meth:`step`.

    Parameters
    ----------
    record
        The controller's flat record (:func:`wetclutch.launch.design.record`).
    kiss_Pa
        The kiss point the controller starts from, Pa: the design's, or one learnt in earlier
        launches (:class:`wetclutch.launch.adaptation.Adaptation`). A learnt one (any other than the
        design's) is searched above only once the pressure has come close to it, as in the native loop.
    friction_factor
        The friction factor learnt in earlier launches at this oil temperature, if any: the torque loop's
        friction law starts from it instead of the design's.
    friction_slope
        The friction factor's slope with slip learnt there (1/(rad/s)), if any.
    output_inertia
        The clutch output's inertia measured in earlier launches (kg m^2), if any (else the design's).
    hold_margin
        How far (Pa) below the kiss point the hold keeps the plates: learnt in earlier launches at this oil
        temperature whose waiting vehicle was pushed too hard
        (:meth:`wetclutch.launch.adaptation.Adaptation.hold_margin`), 0 if none. With a margin, a learnt kiss point
        is kept where the launch would otherwise set it aside, as in the native loop.
    """

    def __init__(self, record: np.ndarray, kiss_Pa: float, friction_factor: float | None = None,
                 friction_slope: float | None = None, output_inertia: float | None = None,
                 hold_margin: float = 0.0) -> None:
        if not 0.0 <= hold_margin <= adaptation.MARGIN_MAX:
            raise WetclutchError(f"hold_margin must be in 0..{adaptation.MARGIN_MAX:g} Pa (got {hold_margin:g})")
        self.record = np.asarray(record, dtype=float)
        self.dt = float(self.record[control.DT])
        self.state = control.initial_state(kiss_Pa, kiss_Pa != self.record[control.P_KISS], friction_factor,
                                           friction_slope, control.start_inertia(self.record, output_inertia),
                                           margin=hold_margin, inertia_measured=output_inertia is not None)

    @classmethod
    def of(cls, d: design.Design, dt: float = 1e-3) -> Controller:
        """The controller of design ``d`` (:func:`wetclutch.launch.design.design`, or a controller file's),
        sampled every ``dt`` s, starting from the design's kiss point."""
        return cls(design.record(d, dt), d.settings["p_kiss"])

    def step(self, measured: Mapping[str, float], t_ref: float) -> float:
        """One sample: the measured channels by name (:data:`wetclutch.launch.controller.MEASURED`) and the
        request -> the valve input (V), to be held until the next sample."""
        meas = np.array([float(measured[c]) for c in control.MEASURED])
        if not (np.all(np.isfinite(meas)) and np.isfinite(t_ref)):
            raise WetclutchError("controller inputs must be finite")
        return float(control.step(self.record, self.state, meas, float(t_ref)))
