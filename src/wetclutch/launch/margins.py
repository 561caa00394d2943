"""Stability margins of the baseline's torque loop over the ranges, from the linearised plant.

At an operating point (a plant and an oil temperature) the valve-hydraulics-driveline path
from input voltage to axle torque is linearised as a first-order-plus-dead-time model
``G(s) = K e^(-theta s) / (tau s + 1)``, fitted to the plant's torque step through the
design's own feedforward map (:func:`wetclutch.launch.design.torque_step`); the dead time
enters as a third-order Pade approximant. With the PI ``C(s) = kp + ki / s`` the loop
``L = C G`` gives gain and phase margins (python-control's ``stability_margins``). Over the
corner plants of the ranges this says what the design guarantees where real clutches drift:
the smallest margins and where they occur.
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np

from ..errors import WetclutchError
from ..params import Params
from . import ranges as ranges_mod
from .design import Design, torque_step


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
        raise WetclutchError("loop margins are computed for the baseline's PI loop")
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


def over_corners(design: Design, plant: Params, rs: list[ranges_mod.Range]) -> list[dict]:
    """Margins at every corner of ``rs`` (conditions other than the oil temperature do not enter the linear loop)."""
    out = []
    base_temp = plant.rig.oil_temp_C
    for corner in ranges_mod.corners(rs):
        p, cond = ranges_mod.apply(rs, corner, plant)
        m = margins(design, p, cond.get("oil_temp_C", base_temp))
        out.append({"corner": corner, "gain_margin": m.gain, "phase_margin_deg": m.phase_deg,
                    "K_Nm_per_V": m.K_Nm_per_V, "tau_s": m.tau_s, "theta_s": m.theta_s})
    return out
