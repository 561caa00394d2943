"""The plant FMU's slave: :class:`wetclutch.fmi.plant.Plant` behind the FMI 2.0 co-simulation interface.

This file is the script that ``pythonfmu`` packs into the FMU; the FMU's ``resources``
hold ``params.toml`` (the parameters it was exported with, the parameters' start values)
and ``options.json`` (the input mode). At run time it needs a Python with ``wetclutch``
installed (see the README).

Variables: the parameters by their dotted names (``driveline.ratio`` ...; a list
parameter element-wise, ``friction.mu_slip_poly[0]`` ...), fixed after initialisation;
inputs ``u`` (V, or duty with ``pwm``), ``road_load`` (N m), ``oil_temp_C`` (C); outputs
of :data:`wetclutch.fmi.plant.OUTPUTS` (``locked`` a Boolean).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any
from xml.etree.ElementTree import Element, SubElement

from pythonfmu import Boolean, Fmi2Causality, Fmi2Slave, Fmi2Variability, Real

from wetclutch import params as params_mod
from wetclutch.fmi.plant import OUTPUTS, Plant


def parameter_values(resources: str | None) -> tuple[dict[str, Any], dict[str, Any]]:
    """(parameter values by dotted name, options) from the FMU's resources (defaults without them)."""
    folder = Path(resources) if resources else None
    toml = folder / "params.toml" if folder else None
    p = params_mod.load(toml if toml and toml.is_file() else None)
    opts_file = folder / "options.json" if folder else None
    opts = json.loads(opts_file.read_text()) if opts_file and opts_file.is_file() else {}
    return {path: value for path, value, *_ in params_mod.describe(p)}, opts


def register_parameters(slave: Fmi2Slave, values: dict[str, Any]) -> dict[str, float]:
    """Register every parameter (list parameters element-wise) as a fixed FMU parameter; returns the store."""
    store: dict[str, float] = {}
    for path, unit, desc in [(p, u, d) for p, _, u, d in params_mod.describe(params_mod.Params())]:
        value = values[path]
        names = [(f"{path}[{i}]", v) for i, v in enumerate(value)] if isinstance(value, list) else [(path, value)]
        for name, v in names:
            store[name] = float(v)
            slave.register_variable(Real(name, causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed,
                                         description=f"{desc} [{unit}]", getter=lambda n=name: store[n],
                                         setter=lambda x, n=name: store.__setitem__(n, float(x))), nested=False)
    return store


def with_initial_unknowns(root: Element) -> Element:
    """``root`` (a model description) with its outputs listed as initial unknowns, as FMI 2.0 asks of outputs
    whose initial value is calculated (``pythonfmu`` lists them only as outputs)."""
    structure = root.find("ModelStructure")
    outputs = structure.find("Outputs") if structure is not None else None
    if outputs is not None and structure.find("InitialUnknowns") is None:
        initial = SubElement(structure, "InitialUnknowns")
        for unknown in outputs.findall("Unknown"):
            SubElement(initial, "Unknown", attrib={"index": unknown.get("index")})
    return root


def parameter_overrides(store: dict[str, float]) -> dict[str, Any]:
    """The store of :func:`register_parameters` as dotted-path overrides (list parameters joined)."""
    out: dict[str, Any] = {}
    for name, v in store.items():
        if name.endswith("]"):
            path, i = name[:-1].split("[")
            out.setdefault(path, []).append((int(i), v))
        else:
            out[name] = v
    return {k: [x for _, x in sorted(v)] if isinstance(v, list) else v for k, v in out.items()}


class WetclutchPlant(Fmi2Slave):
    """The wet clutch on its rig: valve, actuator, clutch and driveline."""

    author = "wetclutch"
    description = "Hydraulically actuated wet multi-plate clutch in a flywheel driveline (wetclutch)"

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        values, opts = parameter_values(self.resources)
        self._store = register_parameters(self, values)
        self.pwm = bool(opts.get("pwm", False))
        self.register_variable(Boolean("pwm", causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed,
                                       description="valve input is a PWM duty cycle (else a DC voltage)"))
        self.u = 0.0 if self.pwm else 0.2
        self.road_load = float(values["engage.T_load"])
        self.oil_temp_C = float(values["rig.oil_temp_C"])
        for name, desc in (("u", "valve input [V, or duty cycle 0..1 with pwm]"), ("road_load", "road load [N m]"),
                           ("oil_temp_C", "oil temperature [C]")):
            self.register_variable(Real(name, causality=Fmi2Causality.input, variability=Fmi2Variability.continuous,
                                        description=desc))
        self._out = {k: 0.0 for k in OUTPUTS}
        for name, (unit, desc) in OUTPUTS.items():
            kind = Boolean if name == "locked" else Real
            conv = bool if name == "locked" else float
            self.register_variable(kind(name, causality=Fmi2Causality.output,
                                        variability=Fmi2Variability.discrete if name == "locked"
                                        else Fmi2Variability.continuous, description=f"{desc} [{unit}]",
                                        getter=lambda n=name, c=conv: c(self._out[n])))
        self._plant: Plant | None = None
        self._t0 = 0.0

    def to_xml(self, model_options: dict[str, str] | None = None) -> Element:
        return with_initial_unknowns(super().to_xml(model_options or {}))

    def setup_experiment(self, start_time: float, stop_time: float | None, tolerance: float | None) -> None:
        self._t0 = float(start_time)

    def exit_initialization_mode(self) -> None:
        p = params_mod.load(None, parameter_overrides(self._store))
        self._plant = Plant(p, pwm=self.pwm, oil_temp_C=self.oil_temp_C)
        self._out = self._plant.outputs()

    def do_step(self, current_time: float, step_size: float) -> bool:
        assert self._plant is not None
        self._plant.set_inputs(float(self.u), float(self.road_load), float(self.oil_temp_C))
        self._plant.step(current_time + step_size - self._t0)
        self._out = self._plant.outputs()
        return True
