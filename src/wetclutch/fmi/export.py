"""Building the FMUs: the plant (:mod:`~wetclutch.fmi.plant_fmu`) and a launch controller
(:mod:`~wetclutch.fmi.controller_fmu`) as FMI 2.0 co-simulation FMUs made with ``pythonfmu``.

Each FMU holds its slave script, the ``pythonfmu`` runtime and what it was exported with
(``params.toml``, or the controller's designed record), and runs on a machine whose
Python has ``wetclutch`` installed. The file appears whole or not at all.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path

from .. import params as params_mod
from ..errors import WetclutchError
from ..launch.design import Design
from ..params import Params
from ..launch.controller import CS_KISS
from .controller import Controller

HERE = Path(__file__).resolve().parent


def _build(script: str, resources: dict[str, str], out: str | Path) -> Path:
    from pythonfmu.builder import FmuBuilder

    out = Path(out)
    if out.suffix != ".fmu":
        raise WetclutchError(f"--out must name a .fmu file (got '{out}')")
    if out.is_dir():
        raise WetclutchError(f"--out '{out}' is a directory")
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise WetclutchError(f"--out: directory '{parent}' does not exist")
    with tempfile.TemporaryDirectory(prefix=".fmu-", dir=parent) as tmp:
        d = Path(tmp)
        shutil.copy2(HERE / script, d / script)
        files = []
        for name, text in resources.items():
            (d / name).write_text(text)
            files.append(d / name)
        built = FmuBuilder.build_FMU(d / script, dest=d / out.name, project_files=files)
        os.replace(built, out)
    return out


def export_plant(params: Params, out: str | Path, pwm: bool = False) -> Path:
    """Write the plant FMU with ``params`` as its parameters' start values; ``pwm``: the input is a duty cycle."""
    return _build("plant_fmu.py", {"params.toml": params_mod.to_toml(params),
                                   "options.json": json.dumps({"pwm": bool(pwm)})}, out)


#: the sample time of an exported controller, s
DEFAULT_DT_S = 1e-3


def export_controller(d: Design, out: str | Path, dt: float = DEFAULT_DT_S) -> Path:
    """Write the FMU of the controller of design ``d`` (a kind designed on a plant, or a controller file's)."""
    if not 1e-4 <= dt <= 1e-2:
        raise WetclutchError(f"--dt must be in 0.0001..0.01 s (got {dt:g})")
    ctrl = Controller.of(d, dt)
    spec = {"kind": d.kind, "dt": dt, "record": ctrl.record.tolist(), "kiss_Pa": float(ctrl.state[CS_KISS])}
    return _build("controller_fmu.py", {"controller.json": json.dumps(spec)}, out)
