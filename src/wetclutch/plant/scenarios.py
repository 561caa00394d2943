"""Named simulation scenarios and :func:`simulate`, the main Python entry point.

Scenarios
---------
``engage``
    The study's standard run on the default rig: primary at ``omega_p0``,
    secondary at rest and held by the road load; the clutch capacity ramps from
    0 to ``engage.T_cap`` over ``engage.t_ramp`` from ``engage.t_start``; the run
    goes through synchronisation and the free oscillation after it (8 s).
``coupled-clutches``
    The Modelica Standard Library example ``Rotational.Examples.CoupledClutches``
    (its regression results are the reference the tests compare with): four unit inertias, three clutches,
    1.5 s, signals every 1 ms. It does not use the rig parameters.
"""

from __future__ import annotations

import numbers

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from ..physics import thermal
from ..plant import driveline
from ..errors import WetclutchError, check_instance, check_integer, check_number, kind_of
from ..sim.network import Network, Trajectory, integrate
from ..params import Params
from ..sim.signals import Ramp, Sine, Step

#: solver options accepted by :func:`simulate`
SOLVER_OPTIONS = ("dt_out", "rtol", "atol", "h_max")


@dataclass
class Result:
    """Outcome of :func:`simulate`.

    Attributes
    ----------
    scenario : name of the scenario
    signals : table of signals, one row per output time, SI units
    summary : figures of the run (JSON-serialisable)
    params : the parameter record used
    trajectory : the raw integrator output
    """

    scenario: str
    signals: pd.DataFrame
    summary: dict[str, Any]
    params: Params
    trajectory: Trajectory = field(repr=False)


@dataclass(frozen=True)
class Scenario:
    name: str
    t_end: float
    build: Callable[[Params], Network]
    frame: Callable[[Trajectory], pd.DataFrame]
    summary: Callable[[Trajectory], dict]
    description: str


def _engage(p: Params, plate_temp_C: float | None = None) -> Network:
    e = p.engage
    return driveline.build(p, Ramp(e.t_start, e.t_ramp, 0.0, e.T_cap), e.T_load, plate_temp_C=plate_temp_C)


def coupled_clutches_network() -> Network:
    """The MSL ``CoupledClutches`` example (see the reference README for the definition)."""
    net = Network()
    bodies = [net.body(f"J{i}", 1.0, w0=10.0 if i == 1 else 0.0) for i in range(1, 5)]
    mu_fn = 0.5 * 20.0  # mu * fn_max, geometry factor 1
    net.source("torque", bodies[0], Sine(10.0, 5.0))
    net.clutch("clutch1", bodies[0], bodies[1], Sine(mu_fn, 0.2, 1.57), peak=1.1)
    net.clutch("clutch2", bodies[1], bodies[2], Step(0.4, 0.0, mu_fn), peak=1.1)
    net.clutch("clutch3", bodies[2], bodies[3], Step(0.9, 0.0, mu_fn), peak=1.1)
    return net


def _cc_frame(tr: Trajectory) -> pd.DataFrame:
    cols: dict[str, np.ndarray] = {"time": tr.t}
    for i in range(1, 5):
        cols[f"J{i}_w"] = tr.speed(f"J{i}")
    for i in range(1, 4):
        cols[f"clutch{i}_tau"] = tr.clutch_torque(f"clutch{i}")
        cols[f"clutch{i}_locked"] = tr.locked(f"clutch{i}")
    return pd.DataFrame(cols)


def _cc_summary(tr: Trajectory) -> dict:
    names = {0: "free", 1: "forward", -1: "backward", 2: "locked"}
    return {
        "energy_residual": tr.energy_residual(),
        "mode_switches": tr.stats["mode_switches"],
        "steps": tr.stats["steps"],
        "events": [
            {"time": float(t), "clutch": tr.network.clutches[int(j)].name, "mode": names[int(m)]}
            for t, j, m in tr.events
        ],
    }


SCENARIOS: dict[str, Scenario] = {
    "engage": Scenario(
        "engage", 8.0, _engage, driveline.frame, driveline.summary, "clutch capacity ramp, through synchronisation"
    ),
    "coupled-clutches": Scenario(
        "coupled-clutches",
        1.5,
        lambda p: coupled_clutches_network(),
        _cc_frame,
        _cc_summary,
        "Modelica CoupledClutches benchmark",
    ),
}


def simulate(scenario: str, params: Params | None = None, t_end: float | None = None, **options: float) -> Result:
    """Run a named scenario.

    Parameters
    ----------
    scenario
        ``"engage"`` or ``"coupled-clutches"``.
    params
        Parameter record (defaults of the study's rig if None).
    t_end
        End time, s (the scenario's default if None).
    **options
        Solver options: ``dt_out`` (output interval, s, default 1e-3), ``rtol``
        (1e-8), ``atol`` (1e-10), ``h_max`` (largest step, s).

    Examples
    --------
    >>> from wetclutch import simulate
    >>> r = simulate("engage")
    >>> 2.0 < r.summary["t_sync"] < 5.0
    True
    """
    if not isinstance(scenario, str):
        raise WetclutchError(f"scenario must be a scenario's name ({', '.join(SCENARIOS)}), not {kind_of(scenario)}")
    if scenario not in SCENARIOS:
        raise WetclutchError(f"unknown scenario '{scenario}' (choose from {', '.join(SCENARIOS)})")
    unknown = set(options) - set(SOLVER_OPTIONS)
    if unknown:
        raise WetclutchError(f"unknown option '{sorted(unknown)[0]}' (choose from {', '.join(SOLVER_OPTIONS)})")
    if params is not None and not isinstance(params, Params):
        raise WetclutchError(f"params must be a parameter set (wetclutch.load_params(...)), not {type(params).__name__}")
    sc = SCENARIOS[scenario]
    given = {"t_end": sc.t_end if t_end is None else t_end, **options}
    for name, value in given.items():
        # atol may be one per state; a string or an array elsewhere would reach the compiled core and fail there,
        # after its compilation, as a typing error
        if name != "atol":
            if isinstance(value, bool) or not isinstance(value, numbers.Real):
                raise WetclutchError(f"{name} must be a number (got {value!r})")
            given[name] = float(value)
    p = params if params is not None else Params()
    try:
        tr = integrate(sc.build(p), **given)
    except ValueError as e:  # the engine's check of a tolerance, step or time
        raise WetclutchError(str(e)) from None
    return Result(sc.name, sc.frame(tr), sc.summary(tr), p, tr)


def launch_sequence(params: Params | None = None, n: int = 10, pause: float = 10.0) -> pd.DataFrame:
    """``n`` ``engage`` launches in a row, ``pause`` seconds apart: the clutch pack's heat carries over.

    Between two launches nothing slips, so the plates cool towards the oil temperature with
    the pack's time constant ``C / h`` (:func:`wetclutch.physics.thermal.closed_form` with no
    slip power); each launch starts at the temperature the previous one left. One row per
    launch: plate temperature at its start, peak and end (C), and the clutch's slip energy (J).
    """
    if params is not None:
        check_instance(params, Params, "params", "a parameter set (wetclutch.load_params(...)) or None")
    if check_integer(n, "n") < 1:
        raise WetclutchError(f"n must be >= 1 launch (got {n})")
    if not 0.0 <= check_number(pause, "pause", "s") < np.inf:
        raise WetclutchError(f"pause must be a finite time >= 0 s (got {pause!r})")
    p = params if params is not None else Params()
    t_plate = p.rig.oil_temp_C
    rows = []
    for k in range(n):
        s = driveline.summary(integrate(_engage(p, t_plate), SCENARIOS["engage"].t_end))
        rows.append({"launch": k + 1, "T_plate_start": t_plate, "T_plate_peak": s["T_plate_peak"],
                     "T_plate_end": s["T_plate_end"], "E_clutch": s["E_clutch"]})
        # the pause: no slip, the plates cool from where this launch left them
        t_plate = float(thermal.closed_form(pause, 0.0, thermal.pack(p, p.rig.oil_temp_C, s["T_plate_end"])))
    return pd.DataFrame(rows)
