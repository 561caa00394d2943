"""Mode decisions at events and breakpoints: which clutches lock, slide or are free, which gears stick.

At an event the modes are re-decided from the state (:func:`settle`): a clutch at zero
slip is tried locked, the locked clutch most beyond its static capacity is released in
the direction of its constraint torque, lossy gears are set by the direction of power flow
and stick at standstill while their friction bounds hold (an ideal gear has no modes), and a
lossy gear whose constraint the locks beside it already hold carries no torque (:func:`_evaluate`). Newly locked pairs are
projected onto their inertia-weighted common speed; a moving ratio is put back within its
limits (an event leaves it a rounding beyond) and its gear's speeds onto ``w_out = r w_in``
(the integrator keeps that constraint at the acceleration level, where a moving ratio lets
it drift by the local error).
"""

from __future__ import annotations

import numpy as np

from ..physics import actuator as act_
from . import signals
from .compiled import jit, jit_inline
from .rhs import LIM_MAX, LIM_MIN, capacity, hold_margins, rate_command, ratio, rhs_call, slip, static_limit
from .workspace import (FREE, FS_AMP, FS_PISTON, FS_PLAY_CUR, FS_PLAY_DIR, FS_PLAY_G, FS_PLAY_TAU, IDLE, IS_BAD_BODY,
                        IS_REDUNDANT, LOCKED, NO_MODE, STUCK, aux_offsets, fs_grip, fs_ratio)


@jit_inline
def stale(fact, clm, grm):
    """Whether the constraint factors (``A``, ``G``) were made for other modes than ``clm``, ``grm``.

    The constraint matrix depends on the modes only, so a restart that keeps them (an input
    sample of a closed loop, a breakpoint) reuses its factors. ``fact`` records the modes of
    the factors and is updated here: the caller refactors when this returns True. Its last slot says whether
    factors were made at all: a network without clutches and gears has no modes to tell, and its factors (the
    inverse inertias alone) must still be made once.
    """
    nc = clm.shape[0]
    is_stale = False
    made = fact.shape[0] - 1
    if fact[made] != 0:
        is_stale = True
        fact[made] = 0
    for j in range(nc):
        if fact[j] != clm[j]:
            is_stale = True
            fact[j] = clm[j]
    for k in range(grm.shape[0]):
        if fact[nc + k] != grm[k]:
            is_stale = True
            fact[nc + k] = grm[k]
    # not the literal False it starts as: a compiled callee would get a copy for that type too
    return bool(is_stale)


@jit_inline
def forget(fact):
    # factors that failed are no factors
    for i in range(fact.shape[0]):
        fact[i] = NO_MODE


@jit_inline
def _first_guess(t, x, net, ext, clm, grm):
    """Modes from the state alone: clutches by capacity and slip, lossy gears stuck at standstill (an ideal gear
    has no modes: its constraint is the same whichever way power flows, and it has no friction to stick with)."""
    nc = net.cl_a.shape[0]
    ng = net.gr_in.shape[0]
    t_right = t + 1e-9 * max(1.0, abs(t))
    for j in range(nc):
        a = net.cl_a[j]
        b = net.cl_b[j]
        # the capacity at t and just after it, through one call site (each is a copy to compile)
        cap = -np.inf
        for side in range(2):
            cap = max(cap, capacity(j, t if side == 0 else t_right, False, x, net, ext))
        s = slip(x, net, j)
        scale = max(1.0, abs(x[a]), abs(x[b]) if b >= 0 else 0.0)
        if net.cl_oneway[j] != 0:
            # a one-way clutch is never free: b overruns a, or it is locked
            clm[j] = -1 if s < -1e-8 * scale else LOCKED
        elif cap <= 0.0:
            clm[j] = FREE
        elif abs(s) <= 1e-8 * scale:
            clm[j] = LOCKED
        else:
            clm[j] = 1 if s > 0.0 else -1
    # "at standstill" relative to the speeds in the network (rad/s scale of the run)
    w_scale = 1.0
    for k in range(net.J.shape[0]):
        w_scale = max(w_scale, abs(x[k]))
    for k in range(ng):
        i_in = net.gr_in[k]
        o = net.gr_out[k]
        if net.gr_eta[k] == 1.0:
            grm[k] = 1
        elif abs(x[o]) <= 1e-8 * w_scale and abs(x[i_in]) <= 1e-8 * w_scale:
            grm[k] = STUCK
        elif abs(grm[k]) == STUCK:
            grm[k] = 1


@jit_inline
def _project(x, net, clm, grm):
    """Stuck gears to standstill, locked pairs onto their inertia-weighted common speed, moving ratios
    within their limits and their gears' speeds onto the ratio."""
    for k in range(net.gr_in.shape[0]):
        if abs(grm[k]) == STUCK:
            x[net.gr_in[k]] = 0.0
            x[net.gr_out[k]] = 0.0
    for j in range(net.cl_a.shape[0]):
        if clm[j] == LOCKED:
            a = net.cl_a[j]
            b = net.cl_b[j]
            if b < 0:
                x[a] = 0.0
            else:
                ja = net.J[a]
                jb = net.J[b]
                if ja + jb > 0.0:
                    w = (ja * x[a] + jb * x[b]) / (ja + jb)
                else:
                    w = 0.5 * (x[a] + x[b])
                x[a] = w
                x[b] = w
    for k in range(net.gr_in.shape[0]):
        i = net.gr_state[k]
        if i >= 0:
            x[i] = min(max(x[i], net.gr_lim[k, LIM_MIN]), net.gr_lim[k, LIM_MAX])
            if abs(grm[k]) != STUCK:
                _onto_ratio(x, net, k, x[i])


@jit_inline
def _hold_ratios(t, x, net, ext, fstate):
    """A moving ratio at a limit with its command pushing beyond is held there (a mode that lasts until the
    command turns back, an event); the others move."""
    ng = net.gr_in.shape[0]
    o = fs_ratio(net.cl_a.shape[0]) + ng
    for k in range(ng):
        i = net.gr_state[k]
        if i < 0:
            continue
        rate = rate_command(t, False, net, ext, k)
        if rate < 0.0 and x[i] <= net.gr_lim[k, LIM_MIN]:
            fstate[o + k] = -1.0
        elif rate > 0.0 and x[i] >= net.gr_lim[k, LIM_MAX]:
            fstate[o + k] = 1.0
        else:
            fstate[o + k] = 0.0


@jit_inline
def _onto_ratio(x, net, k, r):
    """Gear ``k``'s speeds onto ``w_out = r w_in`` by the least change of kinetic energy (a massless side moves
    alone)."""
    i_in = net.gr_in[k]
    o = net.gr_out[k]
    e = x[o] - r * x[i_in]
    den = net.J[i_in] + r * r * net.J[o]
    if den > 0.0:
        x[i_in] += r * net.J[o] * e / den
        x[o] -= net.J[i_in] * e / den
    else:
        x[o] -= e


@jit_inline
def _gear_modes(x, dx, aux, net, grm, released, redundant):
    """Release a stuck gear whose bounds fail, or turn a gear whose power flows the other way; True if one changed.

    A gear released from standstill keeps the direction its bounds gave while it is still at rest (no cycling),
    unless it was one of redundant locks (``redundant``): its share of their least-norm distribution, hence the
    direction its bounds give, is one of many, and the power flow, once the motion is decided, sets it."""
    nc = net.cl_a.shape[0]
    ng = net.gr_in.shape[0]
    _, _, o_gear_out, _, o_gear_in = aux_offsets(nc, ng, net.sp_k.shape[0])
    changed = False
    for k in range(ng):
        if net.gr_eta[k] == 1.0 or abs(grm[k]) == IDLE:
            # no modes (an ideal gear), or no torque (an idle one: the locks beside it decide)
            continue
        o = net.gr_out[k]
        lam = aux[o_gear_out + k]
        if abs(grm[k]) == STUCK:
            q = -aux[o_gear_in + k] / ratio(x, net, k)
            ref = lam if lam != 0.0 else q
            grm[k] = -STUCK if ref < 0.0 else STUCK
            m_in, m_out = hold_margins(aux, x, net, grm, k)
            if m_in < 0.0:
                grm[k] = -1  # the output side overcomes the input: power flows back
            elif m_out < 0.0:
                grm[k] = 1  # the input side drives the output
            else:
                continue
            released[nc + k] = 0 if redundant else 1
            return True
        p = lam * (x[o] if x[o] != 0.0 else dx[o])
        if grm[k] * p < 0.0 and not (released[nc + k] != 0 and x[o] == 0.0):
            grm[k] = -grm[k]
            changed = True
    return changed


@jit_inline
def _release_worst(aux, net, clm, released, fstate):
    """Release the locked clutch most beyond its static capacity (with its grip margin, ``fs_grip``, which
    a release clears); True if one was. The test is the event function itself, so a clutch kept locked
    starts with g >= 0.

    Of several locks on one body (a redundant set, whose torques are the least-norm
    distribution), the one released carries its sliding torque from then on and the others
    the rest: the set lets go only when no distribution keeps every lock within its limit.
    A one-way clutch is limited only in the direction in which b overruns a."""
    nc = net.cl_a.shape[0]
    o_grip = fs_grip(nc, net.gr_in.shape[0])
    worst = -1
    worst_excess = 0.0
    for j in range(nc):
        if clm[j] == LOCKED:
            if net.cl_oneway[j] != 0:
                lim = static_limit(net, j, max(aux[nc + j], 0.0), fstate[o_grip + j])
                over = -aux[j] - lim
            else:
                lim = static_limit(net, j, aux[nc + j], fstate[o_grip + j])
                over = abs(aux[j]) - lim
            if over > 0.0:
                excess = abs(aux[j]) / lim if lim > 0.0 else np.inf
                if excess > worst_excess:
                    worst_excess = excess
                    worst = j
    if worst < 0:
        return False
    clm[worst] = 1 if aux[worst] > 0.0 else -1
    released[worst] = 1
    fstate[o_grip + worst] = 0.0
    return True


@jit_inline
def _lock_backsliding(x, dx, net, clm, released):
    """A clutch sliding from zero slip must accelerate in its own direction, else it locks; True if one did."""
    changed = False
    for j in range(net.cl_a.shape[0]):
        m = clm[j]
        if (m == 1 or m == -1) and released[j] == 0:
            a = net.cl_a[j]
            b = net.cl_b[j]
            if slip(x, net, j) * m <= 0.0:
                rel = dx[a] - (dx[b] if b >= 0 else 0.0)
                if rel * m < 0.0:
                    clm[j] = LOCKED
                    changed = True
    return changed


@jit_inline
def _implied(G, x, net, k):
    """Whether gear ``k``'s constraint ``a_out = r a_in`` holds under the solution operator ``G`` whatever the
    body torques: the other constraints imply it."""
    nb = net.J.shape[0]
    r = ratio(x, net, k)
    i_in = net.gr_in[k]
    o = net.gr_out[k]
    g_max = 0.0
    for i in range(nb):
        for c in range(nb):
            g_max = max(g_max, abs(G[i, c]))
    for c in range(nb):
        if abs(G[o, c] - r * G[i_in, c]) > 1e-9 * g_max:
            return False
    return True


@jit_inline
def _evaluate(t, x, net, ext, ws):
    """The right-hand side of the modes being decided (into ``ws.dx``, ``ws.aux``); False if the motion is not
    determined.

    A lossy gear whose constraint the locks and gears beside it already hold (beside a locked clutch, or in
    parallel with another gear) leaves the motion open: its torque splits the load with them, and its loss,
    hence the acceleration, depends on the split. Of the splits within every element's limits the engine takes
    the one in which such gears carry no torque (:data:`~wetclutch.sim.workspace.IDLE`; :func:`_idle_redundant`).
    The locks then carry the load as without the gear; where that is more than a clutch holds, the clutch gives
    way (:func:`_release_worst`), the gear's constraint is its own again, and it carries what the clutch's
    sliding torque does not, with its loss. Idling is decided afresh at each evaluation here, so a gear that
    idled stands in once the locks beside it let go."""
    grm = ws.grm
    for k in range(grm.shape[0]):
        if abs(grm[k]) == IDLE:
            grm[k] = 1 if grm[k] > 0 else -1
    if rhs_call(t, x, net, ext, ws, ws.dx, ws.aux, stale(ws.fact, ws.clm, grm), bool(True)):
        return True
    forget(ws.fact)
    return _idle_redundant(t, x, net, ext, ws)


@jit
def _idle_redundant(t, x, net, ext, ws):
    """Idle the redundant lossy gears (see :func:`_evaluate`) in turn until the motion is determined, each kept idle
    only if the others imply its constraint; False if none does it.

    A real call, not inlined: it runs only where the modes leave the motion open, and compiled once it keeps its
    right-hand side's call sites out of :func:`settle`."""
    clm = ws.clm
    grm = ws.grm
    bad = ws.istate[IS_BAD_BODY]
    idled = False
    for k in range(grm.shape[0]):
        # only a lossy gear of constant ratio (a moving ratio's velocity term is its own constraint)
        if abs(grm[k]) != 1 or net.gr_eta[k] == 1.0 or net.gr_state[k] >= 0:
            continue
        grm[k] *= IDLE
        idled = True
        if rhs_call(t, x, net, ext, ws, ws.dx, ws.aux, stale(ws.fact, clm, grm), bool(True)):
            implied = True
            for i in range(grm.shape[0]):
                if abs(grm[i]) == IDLE and not _implied(ws.G, x, net, i):
                    implied = False
            if implied:
                return True
            # determined, but not by the locks beside it: this gear's constraint was its own
            forget(ws.fact)
            grm[k] = 1 if grm[k] > 0 else -1
        else:
            # still open: keep it idle and try the next one as well
            forget(ws.fact)
    if idled:
        for k in range(grm.shape[0]):
            if abs(grm[k]) == IDLE:
                grm[k] = 1 if grm[k] > 0 else -1
    ws.istate[IS_BAD_BODY] = bad
    return False


@jit_inline
def input_modes(t, net, ext, ws):
    """The valve amplifier's mode and the direction of its coil current (the magnet's play's flow from here on),
    from the state and the valve's input alone."""
    u = signals.value(int(net.act[act_.U_SIG]), t, False, net.sig, net.tab, ext)
    ws.fstate[FS_AMP] = act_.amplifier_mode(ws.x, net.act, u)
    (ws.fstate[FS_PLAY_DIR], ws.fstate[FS_PLAY_CUR], ws.fstate[FS_PLAY_TAU],
     ws.fstate[FS_PLAY_G]) = act_.play_start(ws.x, net.act, u, ext, ws.fstate[FS_AMP], ws.fstate[FS_PLAY_DIR])


@jit_inline
def settle(t, net, ext, ws):
    """Decide consistent modes at time ``t`` for the workspace's state; project newly locked speeds. The valve
    amplifier's mode and the direction of its coil current follow from the state and the input alone.

    Uses ``ws.x``, ``ws.clm``, ``ws.grm`` (updated), ``ws.dx``, ``ws.aux`` and the constraint
    buffers. Returns -1 if the system is singular, 1 if ``ws.dx`` and ``ws.aux`` are those of the
    decided modes at ``ws.x`` (the last evaluation confirmed them), 0 if they are not (the
    iterations ran out on a change).
    """
    x = ws.x
    clm = ws.clm
    grm = ws.grm
    released = ws.released
    nc = net.cl_a.shape[0]
    ng = net.gr_in.shape[0]
    _first_guess(t, x, net, ext, clm, grm)
    if net.act.shape[0] > 0:
        input_modes(t, net, ext, ws)
        ws.fstate[FS_PISTON] = act_.piston_mode(x[int(net.act[act_.STATE]) + act_.PRESSURE], net.act)
    # a clutch or gear released in this settle must not be re-locked (no cycling)
    released[:] = 0
    redundant = False
    for _ in range(4 * (nc + ng) + 4):
        _project(x, net, clm, grm)
        _hold_ratios(t, x, net, ext, ws.fstate)
        if not _evaluate(t, x, net, ext, ws):
            return -1
        redundant_now = ws.istate[IS_REDUNDANT] != 0
        redundant = redundant or redundant_now
        # redundant locks: the clutches and brakes give way (carry their sliding torque) before a stuck
        # gear, whose share of the least-norm distribution may lie outside its bounds while another
        # distribution keeps it inside; otherwise the gears are decided first. One call site of each
        # (each is a copy to compile).
        changed = False
        for phase in range(3):
            if phase == 1:
                if _gear_modes(x, ws.dx, ws.aux, net, grm, released, redundant_now):
                    if redundant:
                        # a gear at its bound changes the shares: a clutch that gave way may hold again
                        for j in range(nc):
                            released[j] = 0
                    changed = True
                    break
            elif (phase == 0) == redundant_now and _release_worst(ws.aux, net, clm, released, ws.fstate):
                changed = True
                break
        if changed:
            continue
        if not _lock_backsliding(x, ws.dx, net, clm, released):
            return 1
    return 0
