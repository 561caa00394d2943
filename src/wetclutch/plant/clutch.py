"""The whole clutch on the rig: driveline + valve stem + hydraulic actuator, from parameters.

Two configurations, as in the study:

``clutch``
    The valve drives the clutch piston; the clutch capacity comes from the
    pressure (``F_n``) and the friction law; the driveline of
    :mod:`wetclutch.plant.driveline` runs from 150 rad/s with the secondary at rest.
``valve-only``
    The study's valve test: the clutch is replaced by a downstream restriction
    passing :data:`wetclutch.physics.actuator.VALVE_TEST_FLOW` at the supply pressure (continuous flow instead of a
    dead-end volume); there is no driveline. The valve sits on the test bench's
    pump directly: the clutch installation's feed line and feed restriction
    (``hydraulics.line_*``, ``hydraulics.feed_orifice``), which could not pass 32 l/min
    at 8 bar, are not part of this test, nor are the clutch's seal rings (no seal leakage).

The oil temperature is a parameter of the experiment (``rig.oil_temp_C``); the
oil's viscosity (supply line loss, leakage, open-clutch drag), density and bulk
modulus follow from :mod:`wetclutch.physics.oil`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..params import Params
from ..physics import actuator as A
from ..physics import oil
from ..physics.actuator import CONFIGS
from ..sim.network import GROUND, Network, Trajectory, integrate
from ..sim.signals import Const, Signal
from . import driveline

#: the valve stem's body and its spring (to the housing, with the stem's damping) in the rig network
STEM, STEM_SPRING = "stem", "stem_spring"


@dataclass(frozen=True)
class RigNetwork:
    """A rig network and where its measured quantities live in the state vector."""

    network: Network
    config: str
    temp_C: float

    @property
    def i_current(self) -> int:
        return self.network.actuator_state + A.CURRENT

    @property
    def i_pressure(self) -> int:
        return self.network.actuator_state + A.PRESSURE

    def atol(self, atol: float) -> np.ndarray:
        """Absolute tolerances per state for the engine: ``atol`` on every state but the valve stem's speed.

        The stem's speed swings through zero with every reversal of the stem, where an absolute tolerance
        made for positions would ask for sub-nm/s accuracy and a step of some 0.1 ms. Its error matters only
        through the stem's position, which a speed error ``dv`` moves by ``dv / r`` at most, ``r`` the
        stem's fastest rate (``d / m`` or ``sqrt(c / m)``, whichever is larger): the speed gets
        ``atol * r``, which integrates the position to ``atol``.
        """
        net = self.network
        tol = np.full(net.n_state, float(atol))
        i = [b.name for b in net.bodies].index(STEM)
        m = net.bodies[i].J
        sp = next(s for s in net.springs if s.name == STEM_SPRING)
        tol[i] = atol * max(sp.d / m, np.sqrt(sp.k / m))
        return tol


def build(params: Params, u: Signal | float, *, pwm: bool = False, config: str = "clutch", temp_C: float | None = None,
          plate_temp_C: float | None = None, ratio_rate: Signal | None = None) -> RigNetwork:
    """The rig network driven by input ``u`` (V in DC mode, duty in PWM mode); the clutch's plates start at
    ``plate_temp_C`` (the oil's if None); with ``ratio_rate`` (1/s) the CVT's ratio moves
    (:func:`wetclutch.plant.driveline.build`)."""
    if config not in CONFIGS:
        raise ValueError(f"config must be one of {CONFIGS}")
    temp = params.rig.oil_temp_C if temp_C is None else float(temp_C)
    v = params.valve
    if config == "clutch":
        f = params.friction
        net = driveline.build(params, 0.0, temp_C=temp, plate_temp_C=plate_temp_C, ratio_rate=ratio_rate)
        ci = 0  # the driveline's clutch
        net.clutches[ci].mu_poly = tuple(f.curve())
        # cold oil drags the open plates: viscous torque proportional to viscosity
        net.spring("oil_drag", 0, 1, 0.0, oil.drag_at(f.drag_20C, temp))
    else:
        net = Network()
        ci = -1
    stem = net.body(STEM, v.m_stem)
    spring = net.spring(STEM_SPRING, stem, GROUND, v.c_stem, v.d_stem)
    net.brake("stem_friction", stem, Const(v.F_friction))
    net.actuator(stem, spring, ci, u, A.pack(params, temp, config), pwm=pwm, pwm_freq=v.pwm_freq)
    return RigNetwork(net, config, temp)


def run(params: Params, u: Signal | float, t_end: float, *, pwm: bool = False, config: str = "clutch",
        temp_C: float | None = None, dt_out: float = 1e-3, rtol: float | None = None,
        atol: float | None = None) -> tuple[RigNetwork, Trajectory]:
    """The rig network driven by ``u`` (:func:`build`) integrated from rest to ``t_end``.

    ``rtol``: the engine's relative tolerance (None: its default); ``atol``: the absolute tolerance of every state
    but the valve stem's speed (:meth:`RigNetwork.atol`; None: the engine's default for every state)."""
    rn = build(params, u, pwm=pwm, config=config, temp_C=temp_C)
    tol: dict[str, Any] = {} if rtol is None else {"rtol": rtol}
    if atol is not None:
        tol["atol"] = rn.atol(atol)
    return rn, integrate(rn.network, t_end, dt_out=dt_out, **tol)


def static_pressure(params: Params, u: Signal | float, *, pwm: bool = False, config: str = "clutch",
                    temp_C: float | None = None, t_end: float = 3.0, window: float = 1.0,
                    dt_out: float = 1e-3) -> float:
    """Static clutch pressure (Pa) for input ``u``: the mean over the last ``window`` s of a run to ``t_end``.

    Averaged rather than sampled, because a DC-driven valve hunts a little by stem
    stick-slip and a PWM-driven one ripples.
    """
    rn, tr = run(params, u, t_end, pwm=pwm, config=config, temp_C=temp_C, dt_out=dt_out)
    return float(np.mean(tr.x[tr.t >= t_end - window, rn.i_pressure]))
