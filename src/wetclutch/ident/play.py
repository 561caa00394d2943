"""The magnet's play from the valve's up and down staircases.

The valve's magnetic hysteresis, a play of half-width ``I_hyst`` between the coil current and
the magnetising current (:mod:`wetclutch.physics.actuator`), parts the static pressures of a
staircase run up from those run down at the same command. The model parts them more the wider
its play, the other valve parameters the prior's. ``I_hyst`` is found where the model, driven by
the recording's own command at its oil temperature, parts the recording's pairs of plateaus (up
and down at equal command) by as much on average as the recording does: a root of one monotone
function of one variable (Brent's method on a bracket grown from the prior's value). Its standard
error is the pairs' mean difference's over the model's slope there.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.optimize import brentq

from ..params import Params
from ..plant import clutch
from ..sim.signals import Table
from .estimate import Estimate, source
from .recordings import Recording, command_changes
from .static import Plateau, up_down_pairs

#: the widest play the search tries (A): a separation the model cannot reach below it is not a play
I_MAX = 0.5
#: the half-width's resolution (A)
I_TOL = 1e-4


def command(rec: Recording) -> Table:
    """The recording's piecewise constant command as a signal from time 0: each change a 1 ms ramp, as the rig's
    DAQ makes it."""
    t, u = rec.t, rec.data["u"]
    edges = command_changes(t, u)
    bounds = np.concatenate([[0], edges, [t.size]])
    levels = [float(np.median(u[a:b])) for a, b in zip(bounds[:-1], bounds[1:])]
    tt, vv = [0.0], [levels[0]]
    for e, before, after in zip(edges, levels[:-1], levels[1:]):
        tt += [float(t[e - 1]), float(t[e - 1]) + 1e-3]
        vv += [before, after]
    return Table(np.array(tt), np.array(vv), kinks_are_breakpoints=True)


def _separation(prior: Params, i_hyst: float, rec: Recording, u: Table,
                pairs: Sequence[tuple[Plateau, Plateau]]) -> float:
    """The model's mean of down minus up (Pa) over the pairs' windows, driven by the recording's command ``u``, with a
    play of half-width ``i_hyst``."""
    p = prior.model_copy(update={"valve": prior.valve.model_copy(update={"I_hyst": i_hyst})})
    rn, tr = clutch.run(p, u, float(rec.t[-1]), pwm=rec.input_mode == "pwm", config=rec.config,
                        temp_C=rec.oil_temp_C)
    pk = tr.x[:, rn.i_pressure]

    def level(q: Plateau) -> float:
        return float(np.mean(pk[(tr.t >= q.t0) & (tr.t <= q.t1)]))

    return float(np.mean([level(b) - level(a) for a, b in pairs]))


def play_half_width(points: Sequence[Plateau], prior: Params) -> Estimate | None:
    """``I_hyst`` (A) from the up and down plateaus of valve-only staircases (:func:`wetclutch.ident.static.plateaus`),
    or None without pairs of equal command or where no play up to :data:`I_MAX` parts the model's as much."""
    by_rec: dict[int, list[tuple[Plateau, Plateau]]] = {}
    for a, b in up_down_pairs(points):
        by_rec.setdefault(id(a.rec), []).append((a, b))
    if not by_rec:
        return None
    pairs = max(by_rec.values(), key=len)  # the recording with the most pairs
    rec = pairs[0][0].rec
    measured = float(np.mean([b.p - a.p for a, b in pairs]))
    se = float(np.sqrt(np.sum([a.se**2 + b.se**2 for a, b in pairs])) / len(pairs))
    u = command(rec)

    def gap(i: float) -> float:
        return _separation(prior, i, rec, u, pairs) - measured

    lo, g_lo = 0.0, gap(0.0)
    if g_lo >= 0.0:
        # the model without a play parts the plateaus as much already: no play to resolve, its error unknown
        return _estimate(0.0, se, float("nan"), rec, pairs, measured)
    hi = max(prior.valve.I_hyst, 10.0 * I_TOL)
    g_hi = gap(hi)
    while g_hi < 0.0:
        if hi >= I_MAX:
            return None
        lo, g_lo, hi = hi, g_hi, min(2.0 * hi, I_MAX)
        g_hi = gap(hi)
    i_hyst = float(brentq(gap, lo, hi, xtol=I_TOL))
    slope = (g_hi - g_lo) / (hi - lo)  # Pa per A
    return _estimate(i_hyst, se, slope, rec, pairs, measured)


def _estimate(i_hyst: float, se: float, slope: float, rec: Recording, pairs: Sequence[tuple[Plateau, Plateau]],
              measured: float) -> Estimate:
    return Estimate(i_hyst, se / slope if slope > 0.0 else float("nan"), "A",
                    [source(rec, min(a.t0 for a, _ in pairs), max(b.t1 for _, b in pairs))],
                    {"mean_down_minus_up_bar": measured / 1e5, "pairs": len(pairs)})
