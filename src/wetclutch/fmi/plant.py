"""The clutch on the rig as a stepped model: inputs held over a step, outputs at its end.

:class:`Plant` is what the plant FMU runs (:mod:`wetclutch.fmi.plant_fmu`), usable
without it. It is the network of :func:`wetclutch.plant.clutch.build` (driveline, valve,
actuator) with three inputs that a caller sets between steps: the valve input ``u``
(V, or duty with ``pwm``), the road load on the secondary (the brake's capacity, N m)
and the oil temperature (C). The engine is advanced step by step exactly as the
closed launch loop of :mod:`wetclutch.launch.loop` advances it (the same tolerances,
the modes re-decided after each input change), so the same inputs give the same run.

A change of oil temperature re-packs the temperature-dependent coefficients (viscosity
of the feed line and leakage, bulk modulus, open-plate drag) and carries the state over.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..errors import SimulationError, WetclutchError
from ..params import Params, check_oil_temp
from ..launch import loop as launch_loop
from ..plant import clutch
from ..rig.experiments import INPUT_RANGE
from ..sim.integrator import advance
from ..sim.network import failure, outputs
from ..sim.rhs import rhs_call
from ..sim.signals import External
from ..sim.workspace import FS_T, IS_N_OUT, IS_SETTLE, LOCKED, OK, SETTLE_ALL, aux_offsets, new_workspace

#: external input slots of the network
U_SLOT, LOAD_SLOT = 0, 1
#: the engine's tolerances, those of the closed launch loop
RTOL, ATOL = launch_loop.RTOL, launch_loop.ATOL
#: outputs, their units and descriptions
OUTPUTS = {
    "p_clutch": ("Pa", "clutch pressure"),
    "T_c": ("N m", "clutch torque (primary to clutch output)"),
    "T_r": ("N m", "axle torque right of the CVT"),
    "omega_p": ("rad/s", "primary flywheel speed"),
    "omega_1": ("rad/s", "clutch output / CVT input speed"),
    "omega_r": ("rad/s", "CVT output speed"),
    "omega_s": ("rad/s", "secondary flywheel speed"),
    "locked": ("-", "1 while the clutch is locked (stuck), else 0"),
}


@njit(cache=True, error_model="numpy")
def _element_torques(t, net, ext, ws, dx, aux):
    """Element torques of the current state (the workspace's modes and constraint factors)."""
    return rhs_call(t, ws.x, net, ext, ws, dx, aux, bool(False), bool(False))


@dataclass(frozen=True)
class _Layout:
    pressure: int
    bodies: dict[str, int]
    clutch: int
    clutch_aux: int
    axle_aux: int
    drag_spring: int


class Plant:
    """The clutch on the rig, advanced one communication step at a time.

    Parameters
    ----------
    params
        The plant's parameters.
    pwm
        The valve input is a PWM duty cycle (0..1) instead of a DC voltage (V).
    oil_temp_C
        Initial oil temperature (default ``params.rig.oil_temp_C``).
    """

    def __init__(self, params: Params, pwm: bool = False, oil_temp_C: float | None = None) -> None:
        self.params = params
        self.pwm = bool(pwm)
        self.oil_temp_C = params.rig.oil_temp_C if oil_temp_C is None else check_oil_temp(float(oil_temp_C), "oil_temp_C")
        rn = self._build(self.oil_temp_C)
        self.network = rn.network
        self.net, x0, self.ext = rn.network.compile()
        self.ext[U_SLOT] = INPUT_RANGE["pwm" if self.pwm else "dc"][0]
        self.ext[LOAD_SLOT] = params.engage.T_load
        self.ws = new_workspace(self.net, x0)
        self._atol = rn.atol(ATOL)
        net = rn.network
        nc, ng, ns = len(net.clutches), len(net.gears), len(net.springs)
        off = aux_offsets.py_func(nc, ng, ns)
        ci = next(i for i, c in enumerate(net.clutches) if c.name == "clutch")
        si = {s.name: i for i, s in enumerate(net.springs)}
        self._lay = _Layout(pressure=rn.i_pressure, bodies={b.name: i for i, b in enumerate(net.bodies)}, clutch=ci,
                            clutch_aux=off[0] + ci, axle_aux=off[3] + si["axle"], drag_spring=si["oil_drag"])
        self._out = outputs(1, x0.size, self.ws.aux.size, nc)
        self._dx = np.zeros(x0.size)
        self._aux = np.zeros(self.ws.aux.size)
        self._settled = False

    def _build(self, temp: float) -> clutch.RigNetwork:
        rn = clutch.build(self.params, External(U_SLOT), pwm=self.pwm, config="clutch", temp_C=temp)
        brake = next(c for c in rn.network.clutches if c.name == "brake")
        brake.capacity = External(LOAD_SLOT, self.params.engage.T_load)
        return rn

    @property
    def time(self) -> float:
        """The model's time, s."""
        return float(self.ws.fstate[FS_T])

    def set_inputs(self, u: float, road_load: float, oil_temp_C: float) -> None:
        """Inputs held over the next step: valve input (V or duty; saturated to the rig's range, 0.2..5 V or
        0..1), road load (N m, >= 0), oil temperature (C)."""
        lo, hi = INPUT_RANGE["pwm" if self.pwm else "dc"]
        if not np.isfinite(u):
            raise WetclutchError(f"u must be finite (got {u})")
        if not (np.isfinite(road_load) and road_load >= 0.0):
            raise WetclutchError(f"road_load must be >= 0 N m (got {road_load})")
        if oil_temp_C != self.oil_temp_C:
            self._retemper(check_oil_temp(float(oil_temp_C), "oil_temp_C"))
        self.ext[U_SLOT] = min(max(u, lo), hi)  # the amplifier saturates
        self.ext[LOAD_SLOT] = road_load

    def _retemper(self, temp: float) -> None:
        net2, _, _ = self._build(temp).network.compile()
        self.net.act[:] = net2.act
        self.net.sp_d[self._lay.drag_spring] = net2.sp_d[self._lay.drag_spring]
        self.oil_temp_C = temp
        self._settled = False

    def step(self, t_stop: float) -> None:
        """Advance to ``t_stop`` with the inputs held (the modes re-decided first, as after any input change)."""
        t = self.time
        if not t_stop > t:
            raise WetclutchError(f"step must end after the model's time {t:g} s (got {t_stop:g} s)")
        # the road load moves a force at once: every mode, not the valve's alone
        self.ws.istate[IS_SETTLE] = SETTLE_ALL
        self.ws.istate[IS_N_OUT] = 0
        status = advance(self.net, self.ext, self.ws, float(t_stop), float(t_stop - t), t, RTOL, self._atol, np.inf,
                         *self._out)
        if status != OK:
            raise SimulationError(f"plant step to {t_stop:g} s failed: {failure(self.network, self.ws, status)}")

    def outputs(self) -> dict[str, float]:
        """The outputs (:data:`OUTPUTS`) at the model's time."""
        x, lay = self.ws.x, self._lay
        _element_torques(self.time, self.net, self.ext, self.ws, self._dx, self._aux)
        out = {"p_clutch": x[lay.pressure], "T_c": self._aux[lay.clutch_aux], "T_r": self._aux[lay.axle_aux]}
        for name, body in (("omega_p", "p"), ("omega_1", "1"), ("omega_r", "r"), ("omega_s", "s")):
            out[name] = x[lay.bodies[body]]
        out["locked"] = float(self.ws.clm[lay.clutch] == LOCKED)
        return {k: float(v) for k, v in out.items()}

