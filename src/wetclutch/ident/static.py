"""Static pressure versus command: the plateaus of step-like runs, the static gain curve and the hysteresis."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .estimate import BAR, Estimate, inflation, source
from .recordings import Recording, command_changes

SETTLE = 0.8  # s: shortest constant command that counts as a static plateau
BROADBAND = ("noise", "multisine", "chirp")
#: static gain entries: (configuration, input mode, polynomial order)
GAIN_GROUPS = {
    "valve_gain_poly": ("valve-only", "pwm", 1),
    "clutch_gain_poly_bar_per_V": ("clutch", "dc", 2),
    "clutch_gain_poly_bar_per_duty": ("clutch", "pwm", 2),
    "valve_gain_poly_bar_per_V": ("valve-only", "dc", 2),
}


@dataclass(frozen=True)
class Plateau:
    """A stretch of constant command and the settled pressure at its end."""

    rec: Recording
    u: float
    p: float  # Pa
    se: float  # Pa
    direction: str  # "first", "up" or "down"
    t0: float
    t1: float


def plateaus(rec: Recording) -> list[Plateau]:
    """Static pressures on the constant-command stretches (at least :data:`SETTLE` long) of a step-like run."""
    if rec.experiment in BROADBAND:
        return []
    t, u, p = rec.t, rec.data["u"], rec.data["p_clutch"]
    edges = np.concatenate([[0], command_changes(t, u), [t.size]])
    out: list[Plateau] = []
    prev_u = None
    for a, b in zip(edges[:-1], edges[1:]):
        # settle past the ramp of the change, then average the last 40 %
        level = float(np.median(u[a:b]))
        if t[b - 1] - t[a] >= SETTLE:
            k = a + int(0.6 * (b - a))
            seg = p[k:b]
            se = float(np.std(seg) / np.sqrt(seg.size) * np.sqrt(inflation(seg - seg.mean())))
            direction = "first" if prev_u is None else ("up" if level > prev_u else "down")
            out.append(Plateau(rec, level, float(seg.mean()), se, direction, float(t[k]), float(t[b - 1])))
        prev_u = level
    return out


def static_gain(points: Sequence[Plateau], order: int) -> Estimate | None:
    """Polynomial of static pressure (bar) versus command over plateaus, mid-range only.

    Left out: plateaus below 0.2 bar (the pressure sensor is too insensitive there,
    the study's figure) and a saturated top, where several commands give the same pressure
    (within 3 %) as the highest (the valve wide open).
    """
    p = np.array([q.p for q in points]) / BAR
    u = np.array([q.u for q in points])
    if p.size == 0:
        return None
    top = p >= 0.97 * p.max()
    keep = (p > 0.2) & ~(top if np.unique(np.round(u[top], 6)).size > 1 else np.zeros_like(top))
    order = min(order, np.unique(np.round(u[keep], 6)).size - 1)
    if order < 1:
        return None
    se = np.maximum(np.array([q.se for q in points])[keep] / BAR, 1e-4)
    coef, cov = np.polyfit(u[keep], p[keep], order, w=1.0 / se, cov="unscaled") if keep.sum() > order + 1 else (
        np.polyfit(u[keep], p[keep], order), np.full((order + 1, order + 1), np.nan))
    resid = p[keep] - np.polyval(coef, u[keep])
    # the plateaus' own noise understates the scatter about a smooth curve: scale by the fit's chi^2 if larger
    dof = keep.sum() - order - 1
    if dof > 0:
        cov = cov * max(1.0, float(np.sum((resid / se) ** 2)) / dof)
    return Estimate([float(c) for c in coef], [float(s) for s in np.sqrt(np.diag(cov))], "bar per command^k",
                    [source(q.rec, q.t0, q.t1) for q in np.array(points, dtype=object)[keep]],
                    {"order": int(order), "points": [[float(a), float(b)] for a, b in zip(u[keep], p[keep])],
                     "range_bar": [float(p.min()), float(p.max())]})


def up_down_pairs(points: Sequence[Plateau]) -> list[tuple[Plateau, Plateau]]:
    """The pairs (up, down) of plateaus of one recording at the same command."""
    up = [q for q in points if q.direction in ("up", "first")]
    down = [q for q in points if q.direction == "down"]
    span = max((q.u for q in points), default=0.0) - min((q.u for q in points), default=0.0)
    return [(a, b) for a in up for b in down if a.rec is b.rec and abs(a.u - b.u) <= 1e-3 * max(span, 1e-9)]


def hysteresis(points: Sequence[Plateau]) -> Estimate | None:
    """Largest and mean difference between up and down plateaus at the same command (bar)."""
    pairs = up_down_pairs(points)
    if not pairs:
        return None
    diff = np.array([(a.p - b.p) / BAR for a, b in pairs])
    ses = np.array([np.hypot(a.se, b.se) / BAR for a, b in pairs])
    k = int(np.argmax(np.abs(diff)))
    return Estimate(float(abs(diff[k])), float(ses[k]), "bar",
                    [source(a.rec, min(a.t0, b.t0), max(a.t1, b.t1)) for a, b in pairs],
                    {"mean_bar": float(np.mean(diff)), "at_command": float(pairs[k][0].u),
                     "pairs": [[float(a.u), float(a.p / BAR), float(b.p / BAR)] for a, b in pairs]})
