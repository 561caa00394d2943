"""Design of the launch controllers: their settings, and the records the compiled controllers run on.

A design is made on a nominal parameter set (the plant as the controller believes it is):
the kiss point is its contact pressure, the friction law its ``mu(slip)`` and knee, the
feedforward map the inverse of its static pressure-vs-input curve over oil temperature
(each point a constant-input run of the model), and the input range the rig's DC range.
:func:`record` turns a design into the flat record of :mod:`wetclutch.launch.controller`.
"""

from __future__ import annotations

import functools
import json
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from ..errors import WetclutchError
from ..params import Params
from ..physics import actuator
from ..plant import clutch
from ..rig.experiments import INPUT_RANGE
from . import controller

CONTROLLERS = controller.CONTROLLERS


@dataclass(frozen=True)
class LaunchGains:
    """Settings of the ``launch`` controller (SI; pressures in Pa, gains per Pa or per N m).

    Attributes
    ----------
    hold_offset : float
        Hold the pressure this far above the kiss point while waiting, Pa.
    fill_exit, fill_exit_cold : float
        End the full-input fill this far below the kiss point, Pa, with oil at
        85 C and at 20 C (linear in between).
    hold_rate : float
        Rate at which the pressure set point then approaches the hold pressure, Pa/s.
    kp_p, ki_p : float
        Pressure PI once the torque is requested: V/Pa and V/(Pa s).
    kp_hold, ki_hold : float
        Pressure PI while holding at the kiss point (and while a request waits for
        the fill), V/Pa and V/(Pa s): gentler than after the request, since a
        faster integrator there winds the valve open against the stroking piston
        and slams the pressure up at contact.
    hold_lead : float
        While approaching the hold, the set point stays at most this far above
        the measured pressure, Pa.
    req_lead : float
        A request that comes before the fill is complete asks for this much
        above the hold pressure, Pa, until the filtered pressure reaches the
        hold: the torque is wanted now, so the valve may open further than in
        the gentle hold approach (a slam at contact only brings the torque on).
    dip, dip_time : float
        After the fill, the input drops this far (V) below the hold input for
        this long (s), to bring the magnet onto its rising hysteresis branch.
    kp_t, ki_t : float
        Torque loop on the pressure target: proportional (-) and integral (1/s)
        gains on the torque error, scaled by the nominal pressure per N m.
    tau_ref : float
        Time constant of the first-order prefilter on the torque request, s.
    tau_theta : float
        Time constant of the friction estimate (measured over nominal torque), s.
    theta0 : float
        Friction factor assumed until it is measured: on the high side of the
        spread, so that a grippy unit does not overshoot before the estimate
        catches up (a slippery one is a little slower instead). 1.4 rather than
        1.2: with the pressure now rising without staircases, the first rise
        reaches the plates faster than the estimate (10 ms) settles, and at low
        CVT ratios (high torque gain onto the axle) the overshoot then set the
        robustness failures.
    dither_amp, dither_hz : float
        Square-wave dither on the valve input (V, Hz) against stem stick-slip,
        before the request and while the fill completes: smaller than the
        magnet's play, which swallows it, since near the overlap a wide dither
        pumps oil in (inflow from the supply is far stronger than drain flow).
    dither_amp_torque, dither_hz_torque : float
        The dither once the clutch is filled and torque is requested (V, Hz):
        wider than the magnet's play (about 0.225 V of input), so that the iron
        follows the mean coil current and neither the play nor the stem
        friction can stall the pressure in steps.
    ff_shift_torque : float
        Fraction of the design valve's play (``I_hyst / g_current``, V) taken
        off the feedforward under the wide dither: the map was measured on the
        rising hysteresis branch, the dithered magnet works on the centre line.
    """

    hold_offset: float = 0.05e5
    fill_exit: float = 0.1e5
    fill_exit_cold: float = 0.05e5
    hold_rate: float = 1.0e5
    # 0.15e-5: the valve passes less pressure per volt in cooler oil (its feedback chamber), so a
    # stiffer pressure loop keeps the 41 C response within the robustness band of the 85 C one
    kp_p: float = 0.15e-5
    ki_p: float = 5.0e-5
    kp_t: float = 0.0
    ki_t: float = 8.0
    tau_ref: float = 0.03
    tau_theta: float = 0.01
    theta0: float = 1.4
    dither_amp: float = 0.05
    kp_hold: float = 0.05e-5
    ki_hold: float = 2.0e-5
    dither_amp_torque: float = 0.3
    dither_hz_torque: float = 125.0
    ff_shift_torque: float = 1.0
    req_lead: float = 0.2e5
    dip: float = 0.5
    hold_lead: float = 0.01e5
    dip_time: float = 0.015
    dither_hz: float = 125.0


@dataclass(frozen=True)
class PIGains:
    """Settings of the ``pi`` baseline: u = kp e + ki int(e), e = T_ref - T_r (V/N m, V/(N m s)).

    Tuned by hand on the nominal 100 N m launch as the fastest pair whose slip phase
    does not settle into a limit cycle (kp 0.01 and ki 0.15 did); whatever the gains,
    the integrator winds up while the clutch fills, so the torque overshoots when the
    plates close.
    """

    kp: float = 0.001
    ki: float = 0.05


#: oil temperatures (C) and input voltages (V) at which the feedforward map is tabulated
MAP_TEMPS = np.array([20.0, 40.0, 60.0, 80.0, 100.0])
MAP_VOLTS = np.linspace(0.2, 5.0, 17)
MAP_PRESSURES = np.linspace(0.0, 8e5, 33)


def static_map(params, temps: np.ndarray = MAP_TEMPS, volts: np.ndarray = MAP_VOLTS) -> np.ndarray:
    """Static clutch pressure (Pa) vs DC input, shape (len(temps), len(volts)), from the model.

    Each point is a constant-input run of the clutch configuration, averaged over
    its last second (:func:`wetclutch.plant.clutch.static_pressure`).
    """
    return np.array([[clutch.static_pressure(params, float(v), temp_C=float(temp), t_end=3.0, dt_out=1e-2)
                      for v in volts] for temp in temps])


def inverse_map(p_static: np.ndarray, volts: np.ndarray = MAP_VOLTS, pressures: np.ndarray = MAP_PRESSURES) -> np.ndarray:
    """Input voltage for each target pressure, shape (n_temps, len(pressures)): the feedforward table.

    The static curve is made non-decreasing first (a flat stretch, e.g. below
    the prestress, maps to its lowest input); pressures beyond the reachable
    range map to the range's ends.
    """
    table = np.zeros((p_static.shape[0], pressures.size))
    for i, row in enumerate(p_static):
        mono = np.maximum.accumulate(row) + 1e-9 * np.arange(row.size)  # strictly increasing for interp
        table[i] = np.interp(pressures, mono, volts)
    return table


def design_params(rig: Params) -> Params:
    """What the controller is designed on by default: the default rig at the rig's CVT ratio.

    The transmission controller commands the ratio, so it knows it; everything
    else (friction, fill, efficiency, stiffness, temperature) it must cope with.
    """
    d = Params()
    d.driveline.ratio = rig.driveline.ratio
    return d


def _feedforward(params: Params) -> np.ndarray:
    # keyed on the sections the static pressure map depends on, so that designs
    # differing only in the driveline share one table
    key = json.dumps({k: params.model_dump()[k] for k in ("valve", "hydraulics", "friction")}, sort_keys=True)
    return _feedforward_table(key)


@functools.lru_cache(maxsize=8)
def _feedforward_table(key: str) -> np.ndarray:
    params = Params.model_validate(json.loads(key))
    return inverse_map(static_map(params))


def record(name: str, params: Params, gains: Any = None, dt: float = 1e-3) -> np.ndarray:
    """The controller's flat record, designed on the nominal parameter set ``params``."""
    if name not in CONTROLLERS:
        raise WetclutchError(f"unknown controller '{name}' (choose from {', '.join(CONTROLLERS)})")
    u_range = INPUT_RANGE["dc"]
    if name == "pi":
        g = gains or PIGains()
        return controller.pack_pi(g.kp, g.ki, dt, u_range)
    g = gains or LaunchGains()
    f = params.friction
    poly = np.trim_zeros(np.asarray(f.mu_slip_poly, dtype=float), "f") * f.mu_scale
    if poly.size > controller.N_MU:
        # the controller's friction law is quadratic (the study's fit); dropping terms would be silent
        raise WetclutchError(f"friction.mu_slip_poly: the launch controller takes at most a quadratic, "
                             f"got {poly.size} coefficients")
    h, d = params.hydraulics, params.driveline
    settings = {**asdict(g), "p_kiss": actuator.contact_pressure(params), "a_p": h.A_p, "ratio": d.ratio,
                "eta": d.eta, "f_knee": f.F_knee, "p_max": min(h.p_supply, h.p_relief),
                "dither_half": round(0.5 / (g.dither_hz * dt)), "dither_half_torque": round(0.5 / (g.dither_hz_torque * dt)),
                "dip_n": round(g.dip_time / dt),
                "ff_shift": g.ff_shift_torque * params.valve.I_hyst / params.valve.g_current}
    return controller.pack_launch(settings, poly, MAP_TEMPS, MAP_PRESSURES, _feedforward(params), dt, u_range)
