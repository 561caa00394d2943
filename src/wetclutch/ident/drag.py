"""The open plates' oil drag: the axle torque of a clutch run before its first command change.

With the plates apart, the only torque that crosses the clutch is the oil's viscous drag, ``d(T) slip``; through the
CVT (forward power flow, ratio ``i``, efficiency ``eta``) the axle carries ``eta / i`` of it. Before a run's first
command change the valve holds the clutch empty and the primary slips against the resting output, so the mean axle
torque over that stretch over the mean slip gives ``d`` at the run's oil temperature. The model's drag scales with
the oil's dynamic viscosity (:func:`wetclutch.physics.oil.drag_at`: ``drag_20C mu(T) / mu(20 C)``), so each run's
value divided by that factor is the same ``friction.drag_20C``, and runs at different temperatures combine.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..params import OIL_TEMP_RANGE_C
from ..physics import oil
from .estimate import Estimate, aligned, inflation, source, weighted_mean
from .friction import SLIP_MIN
from .recordings import Recording, command_changes

#: the longest stretch before the first command change that is averaged, s: in a longer one the primary slows
#: (the drag brakes it) and an axle held by the vehicle's brake need not follow the drag's fall
WINDOW_S = 2.0
#: the shortest stretch that counts, s (the axle torque's noise is some ten times the drag of warm oil per sample)
MIN_WINDOW_S = 0.2
#: the clutch pressure over the stretch must stay below this share of the contact pressure: plates apart
OPEN_SHARE = 0.8
#: the standard error of ``drag_20C`` above which it stays at the prior (not resolved by the runs)
REL_SE_MAX = 0.25


@dataclass(frozen=True)
class OpenDrag:
    """The oil drag of one clutch run with its plates apart."""

    rec: Recording
    value: float  # N m s at the run's oil temperature
    se: float
    factor: float  # the oil's viscosity at the run's temperature over that at 20 C
    slip: float  # mean slip over the stretch, rad/s
    t0: float
    t1: float


def viscosity_factor(temp_C: float) -> float:
    """The model's drag at ``temp_C`` over its drag at 20 C (:func:`wetclutch.physics.oil.drag_at`), the temperature
    held within the oil temperatures a run may give."""
    return float(oil.drag_at(1.0, float(np.clip(temp_C, *OIL_TEMP_RANGE_C))))


def open_drag(rec: Recording, ratio: float, eta: float, p_contact: float) -> OpenDrag | None:
    """The drag coefficient (N m s) of one clutch run from the stretch before its first command change.

    None where the run is no clutch run, that stretch is shorter than :data:`MIN_WINDOW_S`, the primary does not
    slip by :data:`~wetclutch.ident.friction.SLIP_MIN` throughout, or the pressure comes near the contact pressure
    ``p_contact`` (Pa; plates that may touch carry more than drag). The last :data:`WINDOW_S` before the change are
    averaged; the standard error is the torque's over the stretch, widened for correlated samples.
    """
    if rec.config != "clutch" or not {"T_r", "omega_p", "omega_1"} <= rec.data.keys():
        return None
    d = aligned(rec)
    t = rec.t
    changes = command_changes(t, rec.data["u"])
    end = int(changes[0]) if changes.size else t.size
    w = np.flatnonzero((t >= t[end - 1] - WINDOW_S) & (np.arange(t.size) < end))
    if w.size < 2 or t[w[-1]] - t[w[0]] < MIN_WINDOW_S:
        return None
    slip = d["omega_p"][w] - d["omega_1"][w]
    if not np.min(slip) > SLIP_MIN or not np.median(d["p_clutch"][w]) < OPEN_SHARE * p_contact:
        return None
    torque = d["T_r"][w]
    mean = float(np.mean(torque))
    se = float(np.std(torque) / np.sqrt(torque.size) * np.sqrt(inflation(torque - mean)))
    to_clutch = ratio / eta / float(np.mean(slip))
    return OpenDrag(rec, mean * to_clutch, se * to_clutch, viscosity_factor(rec.oil_temp_C), float(np.mean(slip)),
                    float(t[w[0]]), float(t[w[-1]]))


def per_run(drags: Sequence[OpenDrag]) -> Estimate:
    """The runs' drags at their oil temperatures (``oil_drag_Nms``), in file order."""
    return Estimate([d.value for d in drags], [d.se for d in drags], "N m s (one value per run, in file order)",
                    [source(d.rec, d.t0, d.t1) for d in drags],
                    {"oil_temp_C": [d.rec.oil_temp_C for d in drags], "slip_rad_s": [d.slip for d in drags]})


def drag_20C(drags: Sequence[OpenDrag]) -> Estimate:
    """``friction.drag_20C``: the runs' drags referred to 20 C through the oil's viscosity, inverse-variance
    weighted (cold runs, whose drag stands higher above the torque sensor's noise, weigh most)."""
    values = np.array([d.value / d.factor for d in drags])
    ses = np.array([d.se / d.factor for d in drags])
    m, se = weighted_mean(values, ses)
    return Estimate(m, se, "N m s at 20 C (each run's drag over its oil's viscosity relative to 20 C)",
                    [source(d.rec, d.t0, d.t1) for d in drags],
                    {"per_run_at_20C": [float(v) for v in values], "viscosity_factor": [d.factor for d in drags]})
