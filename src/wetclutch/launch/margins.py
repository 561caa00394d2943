"""Stability margins of the controllers' torque loops over the ranges, from the linearised plant.

At an operating point (a plant and an oil temperature) the valve-hydraulics path from input
voltage to axle torque is linearised as a first-order-plus-dead-time model
``G(s) = K e^(-theta s) / (tau s + 1)``, fitted to the plant's torque step through the
design's own feedforward map (:func:`wetclutch.launch.design.torque_step`); the dead time
enters as a third-order Pade approximant.

Baseline
    With the PI ``C(s) = kp + ki / s`` the loop ``L = C G`` gives gain and phase margins
    (python-control's ``stability_margins``).

Launch controller
    The feedforward asks for the pressure that the nominal friction law, scaled by the
    estimated friction factor ``theta``, says gives the request. Linearised about the
    operating point, in quantities relative to it (pressure above the kiss point ``q``, axle
    torque ``y``, friction factor ``x``): the estimate is ``x = (m - q) F(s)`` (measured torque over
    the model's at the measured pressure, low-passed, with a share ``c`` of its lag behind a drift
    added back from its rate, :data:`~wetclutch.launch.controller.THETA_TREND_SHARE`),

        F(s) = ((1 + c) tau_theta s + 1) / (tau_theta s + 1)^2,

    the set point
    ``q_set = -x - ki_t y / s``, the pressure ``q = G_p q_set`` (``G_p = G / K``) and the axle
    torque ``y = G_dl q``. The measured torque ``m`` is the clutch's as the estimate sees it: the axle's
    plus the clutch output's share ``J_1 w_1'`` with the ``J_1`` it takes, ``J_e``, its rate low-passed
    (time constant ``tau_w``, :data:`~wetclutch.launch.controller.TAU_W1_RATE`):
    ``m = G_m q``, ``G_m = G_dl + (J_e / J_1) (1 - G_dl) / (tau_w s + 1)``. Broken at the set point, the loop is

        L(s) = G_p(s) [ (G_m(s) - 1) F(s) + ki_t G_dl(s) / s ]

    At low frequency ``G_dl = 1``: the estimate is open loop there and only the torque
    integrator acts. Near the driveline's resonance ``G_dl - 1`` is as large as its peak, and
    a fast estimate (small ``tau_theta``, or much of its lag added back) closes a loop through
    it unless the estimate's ``J_e`` takes it out: that is what makes a heavy clutch output oscillate.
    ``J_e`` is the design's, or the clutch's own where the launch measures it within
    (:func:`estimate_inertia`). ``G_dl`` is the clutch output (CVT
    input) inertia seen through the ratio, ``J_a = J_1 / i^2``, on the axle spring and damper
    against the far heavier vehicle,

        G_dl(s) = (d_a s + k_a) / (J_a s^2 + (d_a + c_f) s + k_a),    c_f = F_n mu'(slip) / i^2

    where ``c_f`` is the friction curve's damping at the request's normal force and the launch's
    initial slip (negative where ``mu`` falls with slip: a source of judder).

The launch loop leaves out the estimate's limits (it waits for the plates to press, and its
value is bounded; its slowing and its trend's fading while the clutch output swings back),
the pressure loop's own feedback and the sensors' filters; it is conservative there. At ten
times the default clutch output and a ratio of 0.4, with a fast estimate (``tau_theta`` 5 ms):
told the output's whole inertia, a gain margin of 1.0, told 60 % of it 0.63; the default design
(50 ms) has 1.9. The simulated launches with the fast estimate ring, told all or part of the
inertia, by some 5 % of their torque, and the default's stay below 3 % (the tests show these):
where the margin is gone the ring stays bounded. Where a loop has several phase crossovers, the
smallest gain margin is the one given.

Over the corner plants of the ranges this says what a design guarantees where real clutches
drift: the smallest margins and where they occur.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import control
import numpy as np

from ..errors import WetclutchError
from ..params import Params
from . import ranges as ranges_mod
from .controller import TAU_W1_RATE, THETA_TREND_SHARE, inertia_taken
from .design import Design, fill_times, torque_step


@dataclass(frozen=True)
class Margins:
    """Gain margin (factor, inf if unbounded), phase margin (deg) and the linear model they hold for."""

    gain: float
    phase_deg: float
    K_Nm_per_V: float
    tau_s: float
    theta_s: float


def margins(design: Design, plant: Params, temp_C: float) -> Margins:
    """Margins of ``design``'s PI loop (a baseline design) on ``plant`` at oil temperature ``temp_C``."""
    if design.kind != "baseline":
        raise WetclutchError("PI loop margins are computed for the baseline (launch_margins for the launch design)")
    s = design.settings
    k, tau, theta = torque_step(plant, design.input_V, design.fill_s, s["hold_offset"], s["dip"], s["dip_time"],
                                temp_C)
    gm, pm = pi_margins(k, tau, theta, s["kp"], s["ki"])
    return Margins(gm, pm, k, tau, theta)


def pi_margins(k: float, tau: float, theta: float, kp: float, ki: float) -> tuple[float, float]:
    """Gain margin (factor) and phase margin (deg) of ``(kp + ki/s) K e^(-theta s) / (tau s + 1)``."""
    num, den = control.pade(max(theta, 1e-4), 3)
    g = control.tf([k], [tau, 1.0]) * control.tf(num, den)
    c = control.tf([kp, ki], [1.0, 0.0])
    gm, pm, *_ = control.stability_margins(c * g)
    gm = float(gm) if gm is not None and np.isfinite(gm) else float("inf")
    return gm, float(pm)


def _finite(x: float | None) -> float:
    return float(x) if x is not None and np.isfinite(x) else float("inf")


def driveline(plant: Params, t_ref: float) -> control.TransferFunction:
    """``G_dl``: axle torque over the clutch torque seen at the axle, DC gain 1 (module docstring)."""
    d, f = plant.driveline, plant.friction
    coef = f.curve()
    slip = d.omega_p0
    mu = max(float(np.polyval(coef, slip)), 1e-4)
    dmu = float(np.polyval(np.polyder(coef), slip))
    f_n = t_ref * d.ratio / d.eta / mu
    j_a = d.J_1 / d.ratio**2
    c_f = f_n * dmu / d.ratio**2
    return control.tf([d.d_a, d.k_a], [j_a, d.d_a + c_f, d.k_a])


@dataclass(frozen=True)
class LaunchMargins:
    """The launch controller's loop at one operating point: margins and what sets them."""

    gain: float  # factor, inf if unbounded
    phase_deg: float
    resonance_hz: float  # the driveline's (clutch output on the axle) undamped frequency
    damping: float  # its damping ratio, friction's included (< 0: judder, the open loop is unstable)
    tau_s: float
    theta_s: float


def estimate_inertia(design_j_1: float, j_1: float) -> float:
    """The clutch output inertia (kg m^2) a launch's friction-factor estimate takes through its response, on a clutch
    output ``j_1`` and a design's ``design_j_1``: the design's, or ``j_1`` where the launch measures it within
    (:func:`~wetclutch.launch.controller.inertia_taken`, the fit taken as exact)."""
    return inertia_taken(j_1, design_j_1)


def _valve_step(design: Design, plant: Params, temp_C: float, fill: np.ndarray) -> tuple[float, float]:
    """``(tau, theta)`` of the pressure path: the step of :func:`torque_step` after a timed fill (the launch design
    fills by pressure, not by time; the baseline's fill times of the design plant stand in)."""
    s = design.settings
    _, tau, theta = torque_step(plant, design.input_V, fill, s["hold_offset"], s["dip"], s["dip_time"], temp_C)
    return tau, theta


def launch_margins(design: Design, plant: Params, temp_C: float, t_ref: float,
                   valve: tuple[float, float] | None = None) -> LaunchMargins:
    """Margins of the launch ``design``'s torque loop (module docstring) on ``plant`` at ``temp_C`` and request
    ``t_ref``; ``valve`` = ``(tau, theta)`` of the pressure path if known (else fitted on ``plant``)."""
    if design.kind != "launch":
        raise WetclutchError("launch loop margins are computed for the launch design")
    s = design.settings
    tau, theta = valve if valve is not None else _valve_step(design, plant, temp_C, fill_times(design.plant))
    num, den = control.pade(max(theta, 1e-4), 3)
    g_p = control.tf([1.0], [tau, 1.0]) * control.tf(num, den)
    g_dl = driveline(plant, t_ref)
    j_a, c, k = (float(v) for v in g_dl.den[0][0])
    wn = float(np.sqrt(k / j_a))
    zeta = c / (2.0 * np.sqrt(k * j_a))
    one = control.tf([1.0], [1.0])
    tau_e = s["tau_theta"]
    estimate = control.tf([(1.0 + THETA_TREND_SHARE) * tau_e, 1.0], [tau_e**2, 2.0 * tau_e, 1.0])
    # the estimate's torque is the axle's plus the clutch output's share, J_1 w_1' (its rate low-passed): the
    # resonance's path into it shrinks by that share's part of the output's own
    share = estimate_inertia(s["j_1"], plant.driveline.J_1) / plant.driveline.J_1
    measured = g_dl + share * (one - g_dl) * control.tf([1.0], [TAU_W1_RATE, 1.0])
    loop = g_p * ((measured - one) * estimate + control.tf([s["ki_t"]], [1.0, 0.0]) * g_dl)
    if zeta <= 0.0:
        return LaunchMargins(0.0, -180.0, wn / (2 * np.pi), zeta, tau, theta)
    # the smallest gain margin over every phase crossover (the lead of the estimate's trend gives the loop more than
    # one); the phase margin nearest zero over the gain crossovers, as python-control picks it
    gms, pms, *_ = control.stability_margins(loop, returnall=True)
    gm = float(np.min(gms)) if len(gms) else np.inf
    pm = float(pms[np.argmin(np.abs(pms))]) if len(pms) else np.inf
    return LaunchMargins(_finite(gm), _finite(pm), wn / (2 * np.pi), zeta, tau, theta)


#: the ranges that enter the launch loop's linear model: the valve's (through the fitted step) and the driveline's
LAUNCH_LOOP_RANGES = ("stem_damping", "oil_temp", "output_inertia", "cvt_ratio", "friction_level", "friction_slope",
                      "request")


def launch_over_corners(design: Design, plant: Params, rs: list[ranges_mod.Range]) -> list[dict]:
    """Launch loop margins at every combination of the extremes of :data:`LAUNCH_LOOP_RANGES` present in ``rs``
    (the other ranges at their nominal values); the valve's step is fitted once per valve corner."""
    rs, _ = ranges_mod.fit(rs, plant)
    names = [r.name for r in rs if r.name in LAUNCH_LOOP_RANGES]
    loop_rs = [replace(r, corner=r.name in names) for r in rs]
    base = {"oil_temp_C": plant.rig.oil_temp_C, "t_ref": 100.0, "noise_scale": 1.0}
    nominal = ranges_mod.nominal(loop_rs, plant, base)
    valves: dict[tuple, tuple[float, float]] = {}
    fill = fill_times(design.plant)
    out = []
    for corner in ranges_mod.corners(loop_rs):
        p, cond = ranges_mod.apply(loop_rs, nominal | corner, plant)
        temp = cond.get("oil_temp_C", base["oil_temp_C"])
        key = (corner.get("stem_damping"), temp)
        if key not in valves:
            valves[key] = _valve_step(design, p, temp, fill)
        m = launch_margins(design, p, temp, cond.get("t_ref", base["t_ref"]), valves[key])
        out.append({"corner": corner, "gain_margin": m.gain, "phase_margin_deg": m.phase_deg,
                    "resonance_hz": m.resonance_hz, "damping": m.damping, "tau_s": m.tau_s, "theta_s": m.theta_s})
    return out


def over_corners(design: Design, plant: Params, rs: list[ranges_mod.Range]) -> list[dict]:
    """Margins at every corner of ``rs`` as it applies to ``plant`` (:func:`wetclutch.launch.ranges.fit`; conditions
    other than the oil temperature do not enter the linear loop)."""
    out = []
    base_temp = plant.rig.oil_temp_C
    rs, _ = ranges_mod.fit(rs, plant)
    for corner in ranges_mod.corners(rs):
        p, cond = ranges_mod.apply(rs, corner, plant)
        m = margins(design, p, cond.get("oil_temp_C", base_temp))
        out.append({"corner": corner, "gain_margin": m.gain, "phase_margin_deg": m.phase_deg,
                    "K_Nm_per_V": m.K_Nm_per_V, "tau_s": m.tau_s, "theta_s": m.theta_s})
    return out
