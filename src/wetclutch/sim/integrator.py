"""The hybrid integrator: Dormand-Prince steps between events, exact mode switching at them.

In every interval between events the modes are fixed and the ODE is smooth. Events
(slip through zero, constraint torque beyond the static capacity, capacity through zero,
gear power-flow reversal, the valve amplifier leaving its regulating range, the coil current
turning, along whose monotone path the magnet's play is a map) are located on the dense output
by the Illinois method; a slip that dips through zero and back within one
step is caught at its least value; the
state is taken on the violated side of the root and the modes are re-decided there
(:func:`wetclutch.sim.modes.settle`). Time events (steps and ramp corners of the
signals, PWM edges) end a step exactly; the modes are re-decided with the right limit.
Steps are chosen by Hairer's PI step-size control.

:func:`advance` is the entry point; its helpers each do one named thing and take the
workspace whole.
"""

from __future__ import annotations

import numpy as np

from ..physics import actuator as act_
from . import signals
from .compiled import jit, jit_inline
from .dopri import C, component, dense, error_norm, stage, weights
from .modes import forget, input_modes, settle, stale
from .rhs import copy, events, rhs, rhs_call, static_limit
from .workspace import (ERR_SINGULAR, ERR_ZENO, FS_AMP, FS_AMP_G, FS_H, FS_LOCKS, FS_LOG_ERR, FS_PISTON, FS_PLAY_CUR,
                        FS_PLAY_DIR, FS_PLAY_G, FS_PLAY_TAU, FS_PWM_H, FS_PWM_NEXT, FS_PWM_START, FS_T, GRIP, GRIP_MAX,
                        IS_EVENTS, IS_LAST_EVENT, IS_N_LOG, IS_N_OUT, IS_REJECTED, IS_SETTLE, IS_STEPS, IS_SWITCHES,
                        IS_TURNS, LOCK_FIRST, LOCK_LAST, LOCKED, OK, SETTLE_ALL, SETTLE_INPUT, UNDECIDED, fs_grip)


@jit_inline
def _eval_at(theta_t, t_old, h, y_old, ws, net, ext):
    """State and event functions at ``theta_t`` inside the last step (fixed modes): the right-hand side's torques
    (its accelerations and pressure rate are not needed)."""
    dense(y_old, ws.K, h, (theta_t - t_old) / h, ws.y_tmp, ws.bw)
    rhs_call(theta_t, ws.y_tmp, net, ext, ws, ws.dx, ws.aux_new, bool(False), bool(False))
    events(ws.y_tmp, ws.aux_new, net, ws.clm, ws.grm, ws.g_new, ws.fstate)


@jit_inline
def _event_value(e, theta_t, t_old, h, y_old, ws, net, ext):
    """Event function ``e`` at ``theta_t`` inside the last step (fixed modes). A sliding clutch's slip through zero
    is a function of the state alone, which the dense output gives, and the valve amplifier's one of the coil
    current and the input; every other event needs the right-hand side's torques. Either way the value is the
    one :func:`_eval_at` gives. One call site, in :func:`_root`."""
    j = _sliding(e, ws, net)
    if j >= 0:
        return ws.clm[j] * _slip_at((theta_t - t_old) / h, j, y_old, h, ws, net)
    a = net.act
    if a.shape[0] > 0 and e == ws.g_old.shape[0] - 1:
        # the actuator's (the last event function): the coil current, the pressure and the input (and the PWM level)
        weights((theta_t - t_old) / h, ws.bw)
        cur = component(y_old, ws.K, h, ws.bw, int(a[act_.STATE]) + act_.CURRENT)
        p = component(y_old, ws.K, h, ws.bw, int(a[act_.STATE]) + act_.PRESSURE)
        u = signals.value(int(a[act_.U_SIG]), theta_t, False, net.sig, net.tab, ext)
        return act_.event(cur, p, u, ext, a, ws.fstate[FS_AMP], ws.fstate[FS_PISTON], ws.fstate[FS_PLAY_DIR])
    _eval_at(theta_t, t_old, h, y_old, ws, net, ext)
    return ws.g_new[e]


@jit_inline
def _play_on(ws, net):
    """At a step's end or a located event (``ws.x`` there): the magnet's magnetisation, which the step kept at its
    start, into its state slot as the play's map of the current gives it, and the play's flow moved on to here."""
    a = net.act
    if a.shape[0] == 0 or a[act_.I_HYST] <= 0.0:
        return
    k = int(a[act_.STATE])
    f = ws.fstate
    cur = ws.x[k + act_.CURRENT]
    ws.x[k + act_.MAGNETISATION], f[FS_PLAY_TAU], f[FS_PLAY_G] = act_.play_step(
        cur, ws.x[k + act_.MAGNETISATION], a, f[FS_PLAY_CUR], f[FS_PLAY_DIR], f[FS_PLAY_TAU], f[FS_PLAY_G])
    f[FS_PLAY_CUR] = cur


@jit_inline
def _emit(t, y, known, ws, net, ext, out_t, out_x, out_aux, out_mode):
    """Write one output row (state, element torques, clutch modes) at time ``t``; with ``known`` the torques of
    ``y`` are the ones in ``ws.aux`` (the current step's start), else they are evaluated."""
    i = ws.istate[IS_N_OUT]
    if i >= out_t.shape[0]:
        return
    aux = ws.aux
    if not known:
        rhs_call(t, y, net, ext, ws, ws.dx, ws.aux_new, bool(False), bool(False))
        aux = ws.aux_new
    out_t[i] = t
    copy(out_x[i], y)
    a = net.act
    if a.shape[0] > 0 and a[act_.I_HYST] > 0.0:
        # the step holds the magnetisation at its start: the row's is the play's map of the row's current
        k = int(a[act_.STATE])
        f = ws.fstate
        out_x[i, k + act_.MAGNETISATION] = act_.magnetisation(y[k + act_.CURRENT], y[k + act_.MAGNETISATION], a,
                                                              f[FS_PLAY_CUR], f[FS_PLAY_DIR], f[FS_PLAY_TAU],
                                                              f[FS_PLAY_G])
    copy(out_aux[i], aux)
    for j in range(ws.clm.shape[0]):
        out_mode[i, j] = ws.clm[j]
    ws.istate[IS_N_OUT] = i + 1


@jit
def _log_modes(t, before, ws):
    """Count and log the clutches' mode changes at ``t``; keep each clutch's first and last lock time."""
    for j in range(ws.clm.shape[0]):
        if ws.clm[j] != before[j] and before[j] != UNDECIDED:
            n = ws.istate[IS_N_LOG]
            if n < ws.evlog.shape[0]:
                ws.evlog[n, 0] = t
                ws.evlog[n, 1] = j
                ws.evlog[n, 2] = ws.clm[j]
            ws.istate[IS_N_LOG] = n + 1
            ws.istate[IS_SWITCHES] += 1
            if ws.clm[j] == LOCKED:
                # kept apart from the log, which may be full
                if ws.fstate[FS_LOCKS + 2 * j + LOCK_FIRST] < 0.0:
                    ws.fstate[FS_LOCKS + 2 * j + LOCK_FIRST] = t
                ws.fstate[FS_LOCKS + 2 * j + LOCK_LAST] = t


@jit_inline
def _first_stage(t, ws, net, ext, fresh):
    """Evaluate the first stage at the restart's state (``fresh``: ``ws.dx`` and ``ws.aux`` are not yet the decided
    modes' own) and the event functions there."""
    if fresh and not rhs_call(t, ws.x, net, ext, ws, ws.dx, ws.aux, stale(ws.fact, ws.clm, ws.grm), bool(True)):
        forget(ws.fact)
        return False
    copy(ws.K[0], ws.dx)
    events(ws.x, ws.aux, net, ws.clm, ws.grm, ws.g_old, ws.fstate)
    ws.istate[IS_SETTLE] = 0
    return True


@jit
def _restart(ws, net, ext):
    """Re-decide modes at the current time and refresh the first stage."""
    t = ws.fstate[FS_T]
    copy(ws.clm_before, ws.clm)
    decided = settle(t, net, ext, ws)
    if decided < 0:
        return False
    _log_modes(t, ws.clm_before, ws)
    # the mode decision's last evaluation is the first stage, unless it ended on a change
    return _first_stage(t, ws, net, ext, decided == 0)


@jit
def _restart_input(ws, net, ext):
    """Re-decide after a jump of the valve's input alone (:data:`~wetclutch.sim.workspace.SETTLE_INPUT`): the
    amplifier's mode and the coil current's direction; then refresh the first stage.

    :func:`advance` ends on the first stage, element torques and event functions of its last state, and of them
    the input moves only the coil current's rate and the actuator's event function: the coil's inductance keeps
    its current, hence the magnetisation (the play's map restarts where the step left it) and every force. Those
    two are evaluated again; a whole right-hand side here was some 5 % of a closed-loop launch."""
    t = ws.fstate[FS_T]
    a = net.act
    if a.shape[0] == 0:
        return _first_stage(t, ws, net, ext, True)
    input_modes(t, net, ext, ws)
    f = ws.fstate
    u = signals.value(int(a[act_.U_SIG]), t, False, net.sig, net.tab, ext)
    f[FS_AMP_G] = act_.evaluate(ws.x, a, u, ext, ws.K[0], False, f[FS_AMP], f[FS_PISTON], f[FS_PLAY_CUR],
                                f[FS_PLAY_DIR], f[FS_PLAY_TAU], f[FS_PLAY_G])[2]
    ws.g_old[ws.g_old.shape[0] - 1] = f[FS_AMP_G]
    ws.istate[IS_SETTLE] = 0
    return True


@jit
def _pwm_edge(t, ws, net, ext):
    """At a PWM edge (or the start): switch the coil drive level and schedule the next edge.

    The duty cycle is the actuator input, sampled at the start of each period.
    Returns the new level (0 or 1) and proposes the first step after it: the one that
    followed the last edge to that level (``fstate[FS_PWM_H + level]``; see :func:`advance`),
    since the periods repeat nearly alike and the step before the edge knows nothing of the jump.
    """
    a = net.act
    lvl = int(a[act_.PWM_EXT])
    period = 1.0 / a[act_.PWM_FREQ]
    if ext[lvl] > 0.5 and t < ws.fstate[FS_PWM_START] + period - 1e-12 * max(1.0, t):
        ext[lvl] = 0.0  # falling edge inside the period
        ws.fstate[FS_PWM_NEXT] = ws.fstate[FS_PWM_START] + period
    else:
        ws.fstate[FS_PWM_START] = t
        duty = signals.value(int(a[act_.U_SIG]), t, False, net.sig, net.tab, ext)
        if duty <= 0.0:
            ext[lvl] = 0.0
            ws.fstate[FS_PWM_NEXT] = t + period
        elif duty >= 1.0:
            ext[lvl] = 1.0
            ws.fstate[FS_PWM_NEXT] = t + period
        else:
            ext[lvl] = 1.0
            ws.fstate[FS_PWM_NEXT] = t + duty * period
    level = 1 if ext[lvl] > 0.5 else 0
    if ws.fstate[FS_PWM_H + level] > 0.0:
        ws.fstate[FS_H] = ws.fstate[FS_PWM_H + level]
    return level


@jit_inline
def _time_event(t, hit_bp, hit_pwm, bp_i, after_edge, ws, net, ext):
    """Pass the breakpoint or PWM edge at ``t``: the next breakpoint's index, the PWM level the next step
    follows (-1: none), and False if the modes cannot be decided there."""
    if hit_bp:
        bp_i += 1
    if hit_pwm:
        after_edge = _pwm_edge(t, ws, net, ext)
    return bp_i, after_edge, _restart(ws, net, ext)


@jit_inline
def _step_limit(t, t_stop, h_max, bp_i, pwm, ws, net):
    """The next step: ``(h, at_lim, hit_bp, hit_pwm)``, cut to end on the next breakpoint, PWM edge or ``t_stop``."""
    h = min(ws.fstate[FS_H], h_max)
    t_lim = t_stop
    hit_bp = False
    if bp_i < net.bps.shape[0] and net.bps[bp_i] <= t_lim:
        t_lim = net.bps[bp_i]
        hit_bp = True
    hit_pwm = False
    if pwm and ws.fstate[FS_PWM_NEXT] <= t_lim:
        hit_pwm = True
        if ws.fstate[FS_PWM_NEXT] < t_lim:
            t_lim = ws.fstate[FS_PWM_NEXT]
            hit_bp = False
    if t + h >= t_lim - 1e-12 * max(1.0, abs(t_lim)):
        return t_lim - t, True, hit_bp, hit_pwm, t_lim
    return h, False, hit_bp, hit_pwm, t_lim


@jit_inline
def _slide_end(e, ws, net):
    """The clutch (one-way clutches included) whose slip through zero is event ``e`` while it slides (-1: ``e`` is
    another event)."""
    j = e // 2
    if e < 2 * net.cl_a.shape[0] and e % 2 == 0 and (ws.clm[j] == 1 or ws.clm[j] == -1):
        return j
    return -1


@jit_inline
def _sliding(e, ws, net):
    """As :func:`_slide_end`, but not a one-way clutch (whose slip stays on one side)."""
    j = _slide_end(e, ws, net)
    return j if j >= 0 and net.cl_oneway[j] == 0 else -1


@jit_inline
def _dip(e, t, h, y_old, ws, net):
    """A sliding clutch whose slip falls towards zero at a step's start and rises at its end has its least slip
    inside: if that dips through zero, the slip crossed zero and back within the step (a valve stem that
    stops for an instant), which the event functions' signs at the step's ends do not show. Returns the
    time of the least ``m * slip`` on the dense output and its value (``inf``, 1: no dip)."""
    j = _sliding(e, ws, net)
    if j < 0:
        return np.inf, 1.0
    m = ws.clm[j]
    a = net.cl_a[j]
    b = net.cl_b[j]
    d0 = ws.K[0, a] - (ws.K[0, b] if b >= 0 else 0.0)
    d1 = ws.K[6, a] - (ws.K[6, b] if b >= 0 else 0.0)
    if not (m * d0 < 0.0 and m * d1 > 0.0):
        return np.inf, 1.0
    # golden-section search for the least slip on the dense output (its slip is smooth within the step)
    lo = 0.0
    hi = 1.0
    r = 0.6180339887498949
    g_best = np.inf
    th_best = 0.5
    for _ in range(30):
        th1 = hi - r * (hi - lo)
        th2 = lo + r * (hi - lo)
        g1 = m * _slip_at(th1, j, y_old, h, ws, net)
        g2 = m * _slip_at(th2, j, y_old, h, ws, net)
        if g1 < g_best:
            g_best, th_best = g1, th1
        if g2 < g_best:
            g_best, th_best = g2, th2
        if g_best < 0.0:
            break
        if g1 < g2:
            hi = th2
        else:
            lo = th1
    return t + th_best * h, g_best


@jit_inline
def _slip_at(theta, j, y_old, h, ws, net):
    """Clutch ``j``'s slip on the last step's dense output at ``theta`` (its two speeds only)."""
    weights(theta, ws.bw)
    b = net.cl_b[j]
    w_b = component(y_old, ws.K, h, ws.bw, b) if b >= 0 else 0.0
    return component(y_old, ws.K, h, ws.bw, net.cl_a[j]) - w_b


@jit_inline
def _locate_event(t, t_new, h, y_old, ws, net, ext):
    """The earliest event in ``(t, t_new]`` and its event function (``inf``, -1: none).

    Brackets ``[ta, tb]`` with ``g(ta) >= 0 > g(tb)``, refined by the Illinois method to
    1e-13 s on the dense output. A sliding clutch's slip that dips through zero and back within
    the step is bracketed at its least value (:func:`_dip`).
    """
    t_ev = np.inf
    e_ev = -1
    for e in range(ws.g_old.shape[0]):
        if ws.g_old[e] < 0.0:
            continue
        tb = t_new
        gb = ws.g_new[e]
        if gb >= 0.0:
            tb, gb = _dip(e, t, h, y_old, ws, net)
            if gb >= 0.0:
                continue
        tb = _root(e, ws.g_old[e], tb, gb, t_ev, t, h, y_old, ws, net, ext)
        if tb == np.inf:
            continue
        t_ev = tb
        e_ev = e
    return t_ev, e_ev


@jit
def _root(e, ga, tb, gb, t_ev, t, h, y_old, ws, net, ext):
    """Event ``e``'s root in ``[t, tb]`` (``g(t) = ga >= 0 > g(tb) = gb``) by the Illinois method, to 1e-13 s on
    the dense output; ``inf`` if an earlier event's root ``t_ev`` comes first (``e`` not yet below zero there).

    One real call per root with the evaluations inside, where a real call per evaluation passed the workspace and
    network records by value each time (some 80 ns, as much as an inlined right-hand side)."""
    ta = t
    cut = tb > t_ev  # the first evaluation: at the earlier root, which then ends the bracket
    if cut:
        tb = t_ev
    side = 0
    for _ in range(101 if cut else 100):
        if cut:
            tm = tb
        else:
            if tb - ta <= 1e-13 * max(1.0, abs(tb)):
                break
            tm = (ta * gb - tb * ga) / (gb - ga)
            if not (ta < tm < tb):
                tm = 0.5 * (ta + tb)
        gm = _event_value(e, tm, t, h, y_old, ws, net, ext)
        if cut:
            if gm >= 0.0:
                return np.inf
            cut = False
            gb = gm
            continue
        if gm >= 0.0:
            ta = tm
            ga = gm
            if side == -1:
                gb *= 0.5
            side = -1
        else:
            tb = tm
            gb = gm
            if side == 1:
                ga *= 0.5
            side = 1
    return tb


@jit_inline
def _emit_grid(t, t_seg, h, y_old, ws, net, ext, dt_out, t_out0, out_t, out_x, out_aux, out_mode):
    """Output rows at the grid times in ``[t, t_seg)`` from the step's dense output."""
    n_grid = out_t.shape[0]
    j = ws.istate[IS_N_OUT]
    while j < n_grid and t_out0 + j * dt_out < t_seg:
        tg = t_out0 + j * dt_out
        dense(y_old, ws.K, h, (tg - t) / h, ws.y_tmp, ws.bw)
        # a row at the step's start (every sample of a closed loop) has its torques already: those the step
        # began from
        _emit(tg, ws.y_tmp, tg == t, ws, net, ext, out_t, out_x, out_aux, out_mode)
        j = ws.istate[IS_N_OUT]


#: an event within this share of the time (at least 1 s) after the restart before it came at once; more than
#: MAX_SOON such events in a row creep on by picoseconds and end the run as Zeno behaviour
SOON = 1e-10
MAX_SOON = 10_000


@jit_inline
def _grazing(e_ev, soon, ws, net):
    """An event at once after a restart (the ``soon``-th in a row, :data:`SOON`): a clutch that slid off from
    zero slip and at once turned back, twice: its torque only grazed its capacity. The restart locks it; its
    grip margin keeps it locked until a real breakaway. A margin that does not hold it (the torque beyond the
    capacity by more than :data:`GRIP` as it turns back: a valve stem's drive at its peak) doubles with each
    further grazing in a row, up to :data:`GRIP_MAX`."""
    j = _slide_end(e_ev, ws, net) if soon >= 2 else -1
    if j >= 0:
        ws.fstate[fs_grip(net.cl_a.shape[0], net.gr_in.shape[0]) + j] = min(GRIP * 2.0 ** (soon - 2), GRIP_MAX)


#: a slide whose slip, from zero at its step's start, cannot have left this share of its speed's absolute tolerance
#: before it turned back is below the integration's resolution (:func:`_unresolved_slide`)
UNRESOLVED = 1e-3


@jit_inline
def _unresolved_slide(e_ev, dt, y_old, atol, ws, net):
    """A sliding clutch whose slip is back through zero ``dt`` after its step began at zero slip, at a rate too
    small to have left :data:`UNRESOLVED` of its speed's tolerance: a clutch released at its static capacity
    while the torque on it was turning back (a valve stem at the peak of its drive). The dense output cannot
    resolve such a slide, and its zero comes too early, where the torque still exceeds the capacity: the restart
    releases the clutch again, by a tenth of a microsecond a time. The clutch is held there instead, with a grip
    margin of twice the excess the slide began with (its rate times its inertia, relative to its static capacity:
    some 1e-5 for a valve stem), which it keeps until a real breakaway. Returns False if the slide was another."""
    j = _sliding(e_ev, ws, net)
    if j < 0:
        return False
    a = net.cl_a[j]
    b = net.cl_b[j]
    s0 = y_old[a] - (y_old[b] if b >= 0 else 0.0)
    r0 = ws.K[0, a] - (ws.K[0, b] if b >= 0 else 0.0)
    if abs(s0) + abs(r0) * dt > UNRESOLVED * atol[a]:
        return False
    inertia = net.J[a] if b < 0 else net.J[a] * net.J[b] / max(net.J[a] + net.J[b], 1e-300)
    lim = static_limit(net, j, ws.aux[net.cl_a.shape[0] + j], 0.0)
    if not lim > 0.0:
        return False
    ws.fstate[fs_grip(net.cl_a.shape[0], net.gr_in.shape[0]) + j] = max(GRIP, 2.0 * inertia * abs(r0) / lim)
    return True


@jit_inline
def _next_step(h, log_err, at_lim, ws):
    """PI step-size control after an accepted step (Hairer's DOPRI5: steadier near the stability limit),
    in logarithms: one log and one exp per step instead of two powers. Returns the step's factor."""
    fac = max(0.1, min(5.0, np.exp(0.17 * log_err - 0.04 * ws.fstate[FS_LOG_ERR]) / 0.9))
    ws.fstate[FS_LOG_ERR] = max(log_err, np.log(1e-4))
    ws.fstate[FS_H] = h / fac if not at_lim else max(ws.fstate[FS_H], h)
    return fac


@jit
def advance(net, ext, ws, t_stop, dt_out, t_out0, rtol, atol, h_max, out_t, out_x, out_aux, out_mode):
    """Integrate from the workspace's time to ``t_stop``; write outputs on the grid.

    Output rows are written at ``t_out0 + j * dt_out`` for every grid time in
    ``[t, t_stop)``, and at ``t_stop`` itself when it lies on the grid and is the
    last grid time. Calling ``advance`` again continues where it stopped (after a
    caller has changed ``ext``, set ``ws.istate[IS_SETTLE]`` to ``SETTLE_ALL`` to re-decide modes, or to
    ``SETTLE_INPUT`` where only the valve's input changed).

    ``atol`` holds one absolute tolerance per state.

    Returns a status code (``OK``, ``ERR_SINGULAR``, ``ERR_ZENO``).
    """
    n_grid = out_t.shape[0]
    y_old = ws.y_old
    t = ws.fstate[FS_T]
    stalls = 0
    soon = 0
    bp_i = np.searchsorted(net.bps, t, side="right")
    pwm = net.act.shape[0] > 0 and net.act[act_.MODE] == act_.PWM
    after_edge = -1  # level of the PWM edge the next accepted step follows (-1: none)
    if pwm and ws.fstate[FS_PWM_NEXT] == -np.inf:
        after_edge = _pwm_edge(t, ws, net, ext)
        ws.istate[IS_SETTLE] = SETTLE_ALL
    if ws.istate[IS_SETTLE] == SETTLE_INPUT:
        if not _restart_input(ws, net, ext):
            return ERR_SINGULAR
    elif ws.istate[IS_SETTLE] != 0:
        if not _restart(ws, net, ext):
            return ERR_SINGULAR
    while t < t_stop:
        h, at_lim, hit_bp, hit_pwm, t_lim = _step_limit(t, t_stop, h_max, bp_i, pwm, ws, net)
        if h <= 0.0:
            # a breakpoint or PWM edge at the current time
            if hit_bp or hit_pwm:
                bp_i, after_edge, ok = _time_event(t, hit_bp, hit_pwm, bp_i, after_edge, ws, net, ext)
                if not ok:
                    return ERR_SINGULAR
                continue
            break
        copy(y_old, ws.x)
        t_new = t_lim if at_lim else t + h
        # the stages into ws.K and the 5th-order solution into ws.y_new, through one inlined right-hand side
        # (each call site would be a copy of it to compile)
        for s in range(1, 7):
            y = ws.y_tmp if s < 6 else ws.y_new
            stage(y_old, ws.K, h, s, y)
            if not rhs(t + C[s] * h if s < 6 else t_new, True, y, net, ext, ws, ws.K[s], ws.aux_new, False):
                return ERR_SINGULAR
        err = error_norm(y_old, ws.y_new, ws.K, h, rtol, atol, ws.y_tmp)  # y_tmp (stage 5) is free again
        log_err = np.log(err + 1e-30)
        if err > 1.0:
            ws.fstate[FS_H] = h / min(5.0, np.exp(0.17 * log_err) / 0.9)
            ws.istate[IS_REJECTED] += 1
            continue
        ws.istate[IS_STEPS] += 1
        events(ws.y_new, ws.aux_new, net, ws.clm, ws.grm, ws.g_new, ws.fstate)
        t_ev, e_ev = _locate_event(t, t_new, h, y_old, ws, net, ext)
        _emit_grid(t, t_new if t_ev == np.inf else t_ev, h, y_old, ws, net, ext, dt_out, t_out0,
                   out_t, out_x, out_aux, out_mode)
        if t_ev != np.inf:
            dense(y_old, ws.K, h, (t_ev - t) / h, ws.x, ws.bw)
            _play_on(ws, net)
            scale = max(1.0, abs(t))
            if t_ev - t <= SOON * scale:
                # the event came at once after the restart before it (progress within a thousand times the
                # locator's resolution); at the locator's resolution itself it stalls
                soon += 1
                stalls = stalls + 1 if t_ev - t <= 1e-12 * scale else 0
                if stalls > 100 or soon > MAX_SOON:
                    return ERR_ZENO
                _grazing(e_ev, soon, ws, net)
            elif _unresolved_slide(e_ev, t_ev - t, y_old, atol, ws, net):
                soon += 1
                if soon > MAX_SOON:
                    return ERR_ZENO
            else:
                stalls = 0
                soon = 0
            t = t_ev
            ws.fstate[FS_T] = t
            ws.istate[IS_EVENTS] += 1
            ws.istate[IS_LAST_EVENT] = e_ev
            direction = ws.fstate[FS_PLAY_DIR]
            if not _restart(ws, net, ext):
                return ERR_SINGULAR
            if ws.fstate[FS_PLAY_DIR] != direction:
                ws.istate[IS_TURNS] += 1
            continue
        stalls = 0
        soon = 0
        copy(ws.x, ws.y_new)
        _play_on(ws, net)
        t = t_new
        ws.fstate[FS_T] = t
        fac = _next_step(h, log_err, at_lim, ws)
        if after_edge >= 0:
            ws.fstate[FS_PWM_H + after_edge] = h / fac  # what this first step after the edge should have been
            after_edge = -1
        if at_lim and (hit_bp or hit_pwm):
            bp_i, after_edge, ok = _time_event(t, hit_bp, hit_pwm, bp_i, after_edge, ws, net, ext)
            if not ok:
                return ERR_SINGULAR
        else:
            copy(ws.K[0], ws.K[6])
            copy(ws.g_old, ws.g_new)
            copy(ws.aux, ws.aux_new)
    # the last grid point, when it falls on t_stop (earlier ones start the next call)
    j = ws.istate[IS_N_OUT]
    if j == n_grid - 1 and abs(t_out0 + j * dt_out - t_stop) <= 1e-9 * max(1.0, dt_out):
        _emit(t_stop, ws.x, False, ws, net, ext, out_t, out_x, out_aux, out_mode)
    return OK
