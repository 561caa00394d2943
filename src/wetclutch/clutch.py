"""The whole clutch on the rig: driveline + valve stem + hydraulic actuator, from parameters.

Two configurations, as in the study:

``clutch``
    The valve drives the clutch piston; the clutch capacity comes from the
    pressure (``F_n``) and the friction law; the driveline of
    :mod:`wetclutch.driveline` runs from 150 rad/s with the secondary at rest.
``valve-only``
    The study's valve test: the clutch is replaced by a downstream restriction
    passing ``VALVE_TEST_FLOW`` at the supply pressure (continuous flow instead of a
    dead-end volume); there is no driveline. The valve sits on the test bench's
    pump directly: the clutch installation's feed line and feed restriction
    (``hydraulics.line_*``, ``hydraulics.feed_orifice``), which could not pass 32 l/min
    at 8 bar, are not part of this test, nor are the clutch's seal rings (no seal leakage).

The oil temperature is a parameter of the experiment (``rig.oil_temp_C``); the
oil's viscosity (supply line loss, leakage, open-clutch drag), density and bulk
modulus follow from :mod:`wetclutch.oil`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import actuator as A
from . import driveline, oil
from .network import GROUND, Network
from .params import Params
from .signals import Const, Signal

CONFIGS = ("clutch", "valve-only")
#: the study's valve test restriction passes 32 l/min; here at the supply pressure
VALVE_TEST_FLOW = 32.0 / 60000.0


def p_contact(params: Params) -> float:
    """Pressure at which the plates touch (Pa): prestress plus the reset spring over the stroke."""
    h = params.hydraulics
    return h.p_prestress + h.k_reset * h.x_contact / h.A_p


def actuator_record(params: Params, temp_C: float, config: str = "clutch") -> np.ndarray:
    """Physical actuator parameters at oil temperature ``temp_C`` in the flat layout of :mod:`wetclutch.actuator`."""
    v, h = params.valve, params.hydraulics
    mu = oil.dynamic_viscosity(temp_C)
    r = np.zeros(A.N_ACT)
    r[A.V_SUP], r[A.R_COIL], r[A.L_COIL], r[A.R_FW] = v.V_supply, v.R_coil, v.L_coil, v.R_freewheel
    r[A.K_AMP], r[A.G_CURRENT] = v.amp_gain, v.g_current
    r[A.K_F1], r[A.K_F2], r[A.F_PRE], r[A.A_FB] = v.k_F1, v.k_F2, v.F_preload, v.A_fb
    r[A.I_HYST], r[A.I_SAT] = v.I_hyst, v.I_sat
    r[A.OVERLAP], r[A.X_PORT], r[A.CDW] = v.overlap, v.x_port, v.C_d * v.port_width
    # Merritt's steady flow force, jet angle 69 degrees
    r[A.K_FLOW] = v.flow_force * 2.0 * v.C_d * v.port_width * np.cos(np.radians(69.0))
    r[A.RHO] = oil.density(temp_C)
    r[A.P_SUP] = h.p_supply
    # Hagen-Poiseuille: laminar loss of the clutch's feed line, proportional to viscosity
    line = h.line_length if config == "clutch" else 0.0
    r[A.R_LINE] = 128.0 * mu * line / (np.pi * h.line_diameter**4)
    r[A.V0] = h.V0
    r[A.K_OIL], r[A.AIR] = oil.bulk_modulus(temp_C, air_fraction=0.0), h.air_fraction
    r[A.G_LEAK] = h.leak_85C * oil.dynamic_viscosity(85.0) / mu
    r[A.K_SEAL] = h.seal_orifice
    r[A.P_RELIEF], r[A.G_RELIEF] = h.p_relief, h.relief_conductance
    r[A.F_KNEE] = params.friction.F_knee
    if config == "clutch":
        r[A.A_P], r[A.K_RESET], r[A.X_CONTACT] = h.A_p, h.k_reset, h.x_contact
        r[A.P_PRE], r[A.P_CONTACT] = h.p_prestress, p_contact(params)
        r[A.K_RESTRICT] = h.leak_orifice
        r[A.A_FEED] = v.C_d * h.feed_orifice * np.sqrt(2.0 / r[A.RHO])
    else:
        # no piston: the volume is the hose to the restriction
        r[A.A_P], r[A.K_RESET], r[A.X_CONTACT] = 0.0, 1.0, 0.0
        r[A.P_PRE] = r[A.P_CONTACT] = np.inf
        r[A.K_RESTRICT] = VALVE_TEST_FLOW / np.sqrt(h.p_supply)
        r[A.G_LEAK] = r[A.K_SEAL] = 0.0  # no clutch, so no seal rings to leak
    return r


@dataclass(frozen=True)
class RigNetwork:
    """A rig network and where its measured quantities live in the state vector."""

    network: Network
    config: str
    temp_C: float

    @property
    def i_current(self) -> int:
        return self.network.actuator_state

    @property
    def i_pressure(self) -> int:
        return self.network.actuator_state + 1


def build(params: Params, u: Signal | float, *, pwm: bool = False, config: str = "clutch", temp_C: float | None = None) -> RigNetwork:
    """The rig network driven by input ``u`` (V in DC mode, duty in PWM mode)."""
    if config not in CONFIGS:
        raise ValueError(f"config must be one of {CONFIGS}")
    temp = params.rig.oil_temp_C if temp_C is None else float(temp_C)
    v = params.valve
    if config == "clutch":
        f = params.friction
        net = driveline.build(params, 0.0)
        ci = 0  # the driveline's clutch
        net.clutches[ci].mu_poly = tuple(c * f.mu_scale for c in f.mu_slip_poly)
        # cold oil drags the open plates: viscous torque proportional to viscosity
        drag = f.drag_20C * oil.dynamic_viscosity(temp) / oil.dynamic_viscosity(20.0)
        net.spring("oil_drag", 0, 1, 0.0, drag)
    else:
        net = Network()
        ci = -1
    stem = net.body("stem", v.m_stem)
    spring = net.spring("stem_spring", stem, GROUND, v.c_stem, v.d_stem)
    net.brake("stem_friction", stem, Const(v.F_friction))
    net.actuator(stem, spring, ci, u, actuator_record(params, temp, config), pwm=pwm, pwm_freq=v.pwm_freq)
    return RigNetwork(net, config, temp)


def static_pressure(params: Params, u: Signal | float, *, pwm: bool = False, config: str = "clutch",
                    temp_C: float | None = None, t_end: float = 3.0, window: float = 1.0,
                    dt_out: float = 1e-3) -> float:
    """Static clutch pressure (Pa) for input ``u``: the mean over the last ``window`` s of a run to ``t_end``.

    Averaged rather than sampled, because a DC-driven valve hunts a little by stem
    stick-slip and a PWM-driven one ripples.
    """
    from .network import integrate

    rn = build(params, u, pwm=pwm, config=config, temp_C=temp_C)
    tr = integrate(rn.network, t_end, dt_out=dt_out)
    return float(np.mean(tr.x[tr.t >= t_end - window, rn.i_pressure]))
