"""Torque onset after a command step: the dead time and the contact pressure (kiss point)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..rig.onset import first_crossing
from .estimate import aligned, robust_std
from .recordings import Recording, command_changes


@dataclass(frozen=True)
class Onset:
    """Torque onset after a rising command step of one clutch run."""

    rec: Recording
    t_command: float
    dead_time: float
    dead_time_se: float
    p_contact: float
    p_contact_se: float
    level: float  # command after the step
    baseline: float  # T_r before the onset (oil drag through the CVT), N m
    noise: float  # T_r noise, N m
    slip0: float  # slip before the onset, rad/s


def onset(rec: Recording) -> Onset | None:
    """Dead time (command step to torque onset) and contact pressure of a clutch step run.

    The torque onset is where ``T_r`` (delay-compensated) first rises 8 noise
    standard deviations above its level before the step. After the plates touch
    the pressure jumps within a few milliseconds (the piston stops, the oil
    volume is stiff), so the pressure at the onset is the end of the slow stroke
    phase: a straight line fitted to the pressure from 60 ms to 5 ms before the
    onset (clear of the jump) and evaluated at the onset. This avoids reading the pressure on its steep flank,
    where one sample of jitter would be worth tenths of a bar.
    """
    if rec.config != "clutch" or rec.experiment != "step":
        return None
    d = aligned(rec)
    t, u, p, T = rec.t, d["u"], d["p_clutch"], d["T_r"]
    changes = command_changes(t, u)
    if changes.size == 0 or u[changes[0]] <= u[changes[0] - 1]:
        return None
    k_cmd = int(changes[0])
    pre = (t > t[k_cmd] - 0.5) & (t < t[k_cmd])
    if np.count_nonzero(pre) < 20:
        return None
    base, noise = float(np.median(T[pre])), max(robust_std(T[pre]), 1e-3)
    crossing = first_crossing(t, T - base, 8.0 * noise, start=k_cmd)
    if crossing is None:
        return None
    t_on, k_on, _ = crossing
    dt = rec.dt
    # the stroke line: 60 ms to 5 ms before the (interpolated) onset, clear of the jump
    w = (t > t_on - 0.06) & (t < t_on - 0.005) & (t > t[k_cmd])
    if np.count_nonzero(w) < 10:
        return None
    coef, cov = np.polyfit(t[w] - t_on, p[w], 1, cov=True)
    p_c, p_c_se = float(coef[1]), float(np.sqrt(cov[1, 1]))
    slope_T = (T[k_on] - T[k_on - 1]) / dt
    t_se = float(np.hypot(dt / np.sqrt(12.0), noise / max(slope_T, 1e-9)))
    slip = d["omega_p"] - d["omega_1"]
    level = float(u[min(k_cmd + 5, t.size - 1)])
    return Onset(rec, float(t[k_cmd]), t_on - float(t[k_cmd]), t_se, p_c, p_c_se, level, base, noise,
                 float(np.median(slip[pre])))
