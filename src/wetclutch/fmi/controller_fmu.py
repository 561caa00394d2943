"""The controller FMU's slave: :class:`wetclutch.fmi.controller.Controller` behind the FMI 2.0 co-simulation interface.

This file is the script that ``pythonfmu`` packs into the FMU; the FMU's ``resources``
hold ``controller.json``: the controller's kind and its designed record. At run time it
needs a Python with ``wetclutch`` installed (see the README).

Inputs: the measured channels ``p_clutch`` (Pa), ``T_r`` (N m), ``omega_p``, ``omega_1``,
``omega_r``, ``omega_s`` (rad/s), ``cvt_ratio`` (the CVT's present ratio ``w_r / w_1``; 0: unknown, the
design's is used), ``oil_temp`` (C) and the request ``t_ref`` (N m); output
``u``, the valve's DC input (V); parameters ``kiss_Pa``, the kiss point it starts from, and ``hold_margin_Pa``,
how far below it the hold keeps the plates (0 unless learnt in earlier launches).
Each step takes one controller sample: the step size must be the sample time (``dt``),
and the output after a step from ``t`` is the input to hold from ``t`` on (so a master
steps the controller before the plant, as the closed launch loop does; a master that
steps both at once adds one sample of delay).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any
from xml.etree.ElementTree import Element

from pythonfmu import DefaultExperiment, Fmi2Causality, Fmi2Slave, Fmi2Variability, Real, String

from wetclutch.fmi.controller import INPUTS, Controller
from wetclutch.fmi.plant_fmu import with_initial_unknowns

UNITS = {"p_clutch": "Pa", "T_r": "N m", "cvt_ratio": "-", "oil_temp": "C", "t_ref": "N m"}


class WetclutchController(Fmi2Slave):
    """The launch controller of wetclutch, designed on the exported parameter set."""

    author = "wetclutch"
    description = "Launch controller of a wet clutch (wetclutch), one sample per step"

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        spec = Path(self.resources or ".") / "controller.json"
        data = json.loads(spec.read_text()) if spec.is_file() else {"kind": "pi", "record": None}
        self.kind = str(data["kind"])
        self._record = data["record"]
        self.dt = float(data.get("dt", 1e-3))
        self.kiss_Pa = float(data.get("kiss_Pa", 0.0))
        self.hold_margin_Pa = 0.0
        # a master that takes the FMU's default step steps one sample at a time
        self.default_experiment = DefaultExperiment(start_time=0.0, step_size=self.dt)
        self.register_variable(String("kind", causality=Fmi2Causality.local, variability=Fmi2Variability.constant,
                                      description="controller kind (as designed)"))
        self.register_variable(Real("dt", causality=Fmi2Causality.local, variability=Fmi2Variability.constant,
                                    description="sample time, which the communication step must be [s]"))
        self.register_variable(Real("kiss_Pa", causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed,
                                    description="kiss point the controller starts from (the design's, or one learnt "
                                                "in earlier launches) [Pa]"))
        self.register_variable(Real("hold_margin_Pa", causality=Fmi2Causality.parameter,
                                    variability=Fmi2Variability.fixed,
                                    description="how far below the kiss point the hold keeps the plates, learnt in "
                                                "earlier launches whose waiting vehicle was pushed too hard [Pa]"))
        self._in = {name: 0.0 for name in INPUTS}
        for name in INPUTS:
            self.register_variable(Real(name, causality=Fmi2Causality.input, variability=Fmi2Variability.continuous,
                                        description=f"{name} [{UNITS.get(name, 'rad/s')}]",
                                        getter=lambda n=name: self._in[n],
                                        setter=lambda v, n=name: self._in.__setitem__(n, float(v))))
        self.u = 0.0
        self.register_variable(Real("u", causality=Fmi2Causality.output, variability=Fmi2Variability.discrete,
                                    description="valve DC input [V]"))
        self._ctrl: Controller | None = None

    def to_xml(self, model_options: dict[str, str] | None = None) -> Element:
        return with_initial_unknowns(super().to_xml(model_options or {}))

    def exit_initialization_mode(self) -> None:
        self._ctrl = Controller(self._record, self.kiss_Pa, hold_margin=self.hold_margin_Pa)

    def do_step(self, current_time: float, step_size: float) -> bool:
        assert self._ctrl is not None
        if abs(step_size - self._ctrl.dt) > 1e-9 * self._ctrl.dt:
            return False  # one step, one sample
        self.u = self._ctrl.step(self._in, self._in["t_ref"])
        return True
