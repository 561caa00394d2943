"""The highest pressure the valve gives: the supply pressure, from a saturated top of the static pressure.

The valve regulates the clutch pressure to its magnet's force until its stem opens the supply port fully; above
that input the pressure no longer follows the command. It then stands at the supply pressure less the flow's losses
(the seal leakage's through the feed, on the rig's valve test the test restriction's share) or, where the relief
valve cracks lower, at the relief pressure (:mod:`wetclutch.physics.actuator`). A staircase whose highest steps give
the same pressure shows that top. It gives ``hydraulics.p_supply`` through the model: the supply pressure at which
the prior's valve, driven as the run drove it (configuration, input mode, the highest command, the run's oil
temperature), settles at the measured top. The relief valve cracks no lower than that top: where the prior's does,
it is raised to the supply pressure (the relief cracking at the supply pressure, as on the built-in rig).

A single plateau at full input does not show saturation: in cold oil the valve still regulates there (the static
pressure rises with oil temperature), so a step to the top of the range is not taken for the supply.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..params import Params
from ..plant import clutch
from .estimate import BAR, Estimate, source, weighted_mean
from .static import Plateau

#: the highest two commands of a group count as one saturated top where their pressures differ by at most this
#: share of the top (the pressure sensor's noise over a plateau is a thousandth of it)
FLAT_SHARE = 0.02
#: ... and the rise per unit command between them is at most this share of the mean rise per unit command from the
#: group's lowest plateau to its top: a valve still regulating keeps its gain
FLAT_GAIN_SHARE = 0.2
#: plateaus at oil temperatures within this many C are one group (the valve's static curve moves with temperature)
TEMP_BIN_C = 5.0
#: the model's top must meet the measured one to this share for the supply pressure to count as found
SOLVE_TOL = 1e-3


@dataclass(frozen=True)
class Top:
    """The saturated top of one group of plateaus (one configuration, input mode and oil temperature)."""

    points: tuple[Plateau, ...]  # the group's rising plateaus, by command
    saturated: bool
    why: str  # why not saturated ("" if it is)

    @property
    def top(self) -> Plateau:
        return self.points[-1]


def tops(points: Sequence[Plateau]) -> list[Top]:
    """The groups of rising plateaus (first and up: a falling staircase lags by the valve's hysteresis) with two
    commands or more, and whether each shows a saturated top."""
    groups: dict[tuple[str, str, float], list[Plateau]] = {}
    for q in points:
        if q.direction in ("first", "up"):
            key = (q.rec.config, q.rec.input_mode, round(q.rec.oil_temp_C / TEMP_BIN_C))
            groups.setdefault(key, []).append(q)
    out = []
    for group in groups.values():
        by_u: dict[float, Plateau] = {}
        for q in sorted(group, key=lambda q: q.u):
            by_u[round(q.u, 6)] = q  # one plateau per command: the last run's
        pts = tuple(by_u.values())
        if len(pts) < 2:
            continue
        a, b, low = pts[-2], pts[-1], pts[0]
        rise = b.p - a.p
        mean_gain = (b.p - low.p) / (b.u - low.u)
        unit = "V" if b.rec.input_mode == "dc" else "duty"
        where = f"{b.rec.config} {b.rec.input_mode}, {b.rec.oil_temp_C:.0f} C"
        if not b.p - low.p > 0.2 * b.p:
            why = f"the pressure hardly rises over the commands ({where})"
        elif abs(rise) > FLAT_SHARE * b.p or rise / (b.u - a.u) > FLAT_GAIN_SHARE * mean_gain:
            why = (f"the highest command still raises the pressure ({where}: {b.p / BAR:.2f} bar at {b.u:g} {unit}, "
                   f"{a.p / BAR:.2f} bar at {a.u:g} {unit}): the valve is not wide open there")
        else:
            why = ""
        out.append(Top(pts, not why, why))
    return out


def top_pressure(prior: Params, p_supply: float, top: Plateau) -> float:
    """The model's static pressure (Pa) at the top plateau's command, configuration, input mode and oil temperature,
    with the supply pressure ``p_supply`` (the relief valve cracking no lower)."""
    h = prior.hydraulics.model_copy(update={"p_supply": p_supply, "p_relief": max(prior.hydraulics.p_relief, p_supply)})
    plant = prior.model_copy(update={"hydraulics": h})
    return clutch.static_pressure(plant, top.u, pwm=top.rec.input_mode == "pwm", config=top.rec.config,
                                  temp_C=top.rec.oil_temp_C)


def solve_supply(prior: Params, top: Plateau) -> float | None:
    """The supply pressure (Pa) at which the model's top (:func:`top_pressure`) is the measured one, by the secant
    method from the prior's; None where it does not meet it within :data:`SOLVE_TOL` (the prior's valve does not
    open fully at that command, say)."""
    x0 = prior.hydraulics.p_supply
    f0 = top_pressure(prior, x0, top) - top.p
    x1 = x0 * top.p / (f0 + top.p) if f0 + top.p > 0.0 else top.p
    for _ in range(8):
        f1 = top_pressure(prior, x1, top) - top.p
        if abs(f1) <= SOLVE_TOL * top.p:
            return float(x1)
        if f1 == f0:
            return None
        x0, f0, x1 = x1, f1, x1 - f1 * (x1 - x0) / (f1 - f0)
        if not x1 > 0.0:
            return None
    return None


def supply_pressure(points: Sequence[Plateau], prior: Params) -> tuple[Estimate | None, str]:
    """``hydraulics.p_supply`` from the saturated tops of the plateaus (several: their inverse-variance mean), or
    None and why not (empty where no group of plateaus has two commands)."""
    found, why = [], []
    for g in tops(points):
        if not g.saturated:
            why.append(g.why)
            continue
        ps = solve_supply(prior, g.top)
        if ps is None:
            why.append(f"the prior's valve does not settle at the measured top of {g.top.p / BAR:.2f} bar "
                       f"({g.top.rec.config} {g.top.rec.input_mode} at {g.top.u:g}) with any supply pressure")
            continue
        found.append((ps, g))
    if not found:
        return None, "; ".join(why)
    values = np.array([ps for ps, _ in found])
    # the model maps the top to the supply at about one to one: the plateau's own error carries over
    ses = np.array([max(g.top.se, 1.0) for _, g in found])
    m, se = weighted_mean(values, ses)
    return Estimate(m, se, "Pa (the supply pressure at which the model's valve, wide open, gives the measured top)",
                    [source(q.rec, q.t0, q.t1) for _, g in found for q in g.points[-2:]],
                    {"top_Pa": [float(g.top.p) for _, g in found], "command": [g.top.u for _, g in found],
                     "config": [g.top.rec.config for _, g in found],
                     "input_mode": [g.top.rec.input_mode for _, g in found],
                     "oil_temp_C": [g.top.rec.oil_temp_C for _, g in found]}), ""
