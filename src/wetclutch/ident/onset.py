"""Torque onset after a command step: the dead time and the contact pressure (kiss point)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..rig.onset import first_crossing
from .estimate import aligned, robust_std
from .recordings import Recording, command_changes


#: samples of a stroke (command step to torque onset) below which its start is not estimated
MIN_STROKE_SAMPLES = 30


@dataclass(frozen=True)
class Onset:
    """Torque onset after a rising command step of one clutch run."""

    rec: Recording
    t_command: float
    dead_time: float
    dead_time_se: float
    p_contact: float
    p_contact_se: float
    p_start: float  # pressure at which the piston starts to stroke (the reset spring's prestress), Pa; NaN: not seen
    p_start_se: float
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
    where one sample of jitter would be worth tenths of a bar. The stroke's start (:func:`stroke_start`) gives
    the pressure at which the piston starts to move.
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
    p_s, p_s_se = stroke_start(t, p, k_cmd, t_on, p_c)
    return Onset(rec, float(t[k_cmd]), t_on - float(t[k_cmd]), t_se, p_c, p_c_se, p_s, p_s_se, level, base, noise,
                 float(np.median(slip[pre])))


def stroke_start(t: np.ndarray, p: np.ndarray, k_cmd: int, t_on: float, p_contact: float) -> tuple[float, float]:
    """Pressure (Pa) at which the piston starts to stroke after the command step at ``k_cmd``, and its standard
    error; NaN where the stroke is too short to show it.

    Before the piston moves, the inflow fills only the chamber's small dead volume and the pressure rises
    within milliseconds to the reset spring's prestress over the piston area; through the stroke it then
    ramps with the spring's deflection, slowly and nearly linearly, up to the contact pressure. A straight
    line through the middle half of the stroke (clear of that first rise and of the contact's jump) is
    followed back to the first rise's midpoint (the pressure halfway between its level before the step and
    the line): its value there is the start of the stroke. The midpoint of a rise of tenths of a bar within
    milliseconds is placed to a sample whatever the sensor's noise, where the first sample to reach the line
    itself would not be.
    """
    idx = np.flatnonzero((t > t[k_cmd]) & (t < t_on - 0.005))
    if idx.size < MIN_STROKE_SAMPLES:
        return float("nan"), float("nan")
    mid = idx[idx.size // 4:3 * idx.size // 4]
    coef, cov = np.polyfit(t[mid] - t[mid[0]], p[mid], 1, cov=True)
    line = np.polyval(coef, t[idx] - t[mid[0]])
    before = float(np.median(p[(t > t[k_cmd] - 0.05) & (t <= t[k_cmd])]))
    met = np.flatnonzero(p[idx] >= 0.5 * (before + line))
    if met.size == 0 or met[0] >= idx.size // 4:
        return float("nan"), float("nan")  # no quick rise onto a ramp: not a stroke this record shows
    k = int(met[0])
    value = float(line[k])
    if not 0.0 < value < p_contact or coef[0] <= 0.0:
        return float("nan"), float("nan")
    dt_k = t[idx[k]] - t[mid[0]]
    se = float(np.sqrt(cov[1, 1] + dt_k * dt_k * cov[0, 0] + 2.0 * dt_k * cov[0, 1]))
    # the rise's midpoint is placed to a sample, in which the ramp moves on
    return value, float(np.hypot(se, coef[0] * (t[1] - t[0])))
