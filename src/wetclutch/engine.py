"""Compiled hybrid integrator for rotating bodies joined by clutches, gears and springs.

This is the numerical core: numba-compiled pure functions over flat arrays. The
Python-facing description of a network lives in :mod:`wetclutch.network`.

Sign conventions (as in Modelica ``Mechanics.Rotational``): every element joins
a flange ``a`` to a flange ``b`` (body indices; ``-1`` is the ground).

* clutch / brake: slip ``w_a - w_b``; the element's torque ``T`` acts on ``b``
  and ``-T`` on ``a``. Sliding: ``T = cap * mu(|slip|) * sign(slip)``. Locked:
  ``T`` is a constraint torque, bounded by ``peak * cap * mu(0)``.
* gear (``in`` = a, ``out`` = b): ``w_out = ratio * w_in``; its torque ``lam``
  acts on ``out``, and ``-ratio * c * lam`` on ``in`` with ``c = 1/eta`` when
  power flows in -> out (``lam * w_out > 0``) and ``c = eta`` when it flows back,
  so losses never create power.
* spring-damper: deflection ``phi' = w_a - w_b``; torque ``k phi + d (w_a - w_b)``
  on ``b``, its negative on ``a``.

Stick/slip is exact mode switching: in every interval between events the modes
are fixed and the ODE is smooth; locked clutches and gears are acceleration
constraints solved together with the bodies in one small linear (KKT) system.
Events (slip through zero, constraint torque beyond the static capacity,
capacity through zero, gear power-flow reversal) are located on the
Dormand-Prince dense output, and the modes are re-decided there by
:func:`_settle`. Integration is Dormand-Prince 5(4) with step-size control.

State vector ``x``: body speeds (nb), spring deflections (ns), then energy
accumulators: dissipation of each clutch (nc), drag, damper and gear losses,
and the work of the torque sources.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from . import actuator as act_
from .signals import CONST, EXTERNAL, RAMP, SINE, STEP, TABLE

# error_model='numpy': IEEE division semantics, no Python zero-division checks in hot loops.
# _nrt=False: the core allocates nothing (all buffers live in the Workspace), so numba's
# reference counting is pure overhead; it cost about 60 % of a right-hand-side evaluation.
# fastmath: FMA contraction only; reassociation and signed-zero freedom changed the
# actuator's flows (a pressure stuck at zero), and events rely on inf.
_FAST = {"contract"}
_jit = njit(cache=True, error_model="numpy", _nrt=False, fastmath=_FAST)
_jit_inline = njit(cache=True, error_model="numpy", inline="always", _nrt=False, fastmath=_FAST)

FREE, LOCKED, UNDECIDED = 0, 2, 99  # clutch modes; +1 / -1 are sliding forward / backward
_NO_MODE = -99  # in Workspace.fact: no constraint factors made yet
STUCK = 3  # gear held at standstill (+3 / -3: sign of the held output torque); +1 / -1: power flowing forward / back

# status codes returned by the core
OK, ERR_SINGULAR, ERR_ZENO, ERR_OUTPUT = 0, 1, 2, 3

N_ENERGY_EXTRA = 4  # drag, damper, gear, source work


class NetArrays(NamedTuple):
    """Flat, compiled description of a network (see :class:`wetclutch.network.Network`)."""

    J: np.ndarray  # (nb,) inertias, kg m^2 (0 allowed if rigidly tied to an inertia)
    drag: np.ndarray  # (nb,) quadratic drag coefficients, N m s^2
    cl_a: np.ndarray  # (nc,) int
    cl_b: np.ndarray  # (nc,) int, -1 = ground (brake)
    cl_sig: np.ndarray  # (nc,) int signal index of the capacity
    cl_peak: np.ndarray  # (nc,) static / sliding capacity ratio
    cl_poly: np.ndarray  # (nc, P) capacity multiplier polynomial in |slip|, highest power first
    gr_in: np.ndarray  # (ng,) int
    gr_out: np.ndarray  # (ng,) int
    gr_ratio: np.ndarray  # (ng,) w_out / w_in
    gr_eta: np.ndarray  # (ng,) efficiency
    sp_a: np.ndarray  # (ns,) int
    sp_b: np.ndarray  # (ns,) int, -1 = ground
    sp_k: np.ndarray  # (ns,) N m / rad
    sp_d: np.ndarray  # (ns,) N m s / rad
    src_body: np.ndarray  # (nsrc,) int
    src_sig: np.ndarray  # (nsrc,) int
    sig: np.ndarray  # (nsig, ROW) compiled signals
    tab: np.ndarray  # (2, ntab) table samples
    bps: np.ndarray  # sorted breakpoint times
    act: np.ndarray  # flat actuator record (see wetclutch.actuator), empty without one


# ---------------------------------------------------------------- signals


@_jit_inline
def signal_value(k, t, left, sig, tab, ext):
    """Value of compiled signal ``k`` at ``t``; ``left`` takes the left limit at a jump."""
    kind = int(sig[k, 0])
    if kind == CONST:
        return sig[k, 1]
    if kind == STEP:
        t0 = sig[k, 1]
        if t > t0 or (t == t0 and not left):
            return sig[k, 3]
        return sig[k, 2]
    if kind == RAMP:
        t0 = sig[k, 1]
        dur = sig[k, 2]
        if t <= t0:
            return sig[k, 3]
        if t >= t0 + dur:
            return sig[k, 4]
        return sig[k, 3] + (sig[k, 4] - sig[k, 3]) * (t - t0) / dur
    if kind == SINE:
        return sig[k, 1] + sig[k, 2] * np.sin(2.0 * np.pi * sig[k, 3] * t + sig[k, 4])
    if kind == TABLE:
        i0 = int(sig[k, 1])
        n = int(sig[k, 2])
        if t <= tab[0, i0]:
            return tab[1, i0]
        if t >= tab[0, i0 + n - 1]:
            return tab[1, i0 + n - 1]
        lo = i0
        hi = i0 + n - 1
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if tab[0, mid] <= t:
                lo = mid
            else:
                hi = mid
        f = (t - tab[0, lo]) / (tab[0, hi] - tab[0, lo])
        return tab[1, lo] + f * (tab[1, hi] - tab[1, lo])
    if kind == EXTERNAL:
        return ext[int(sig[k, 1])]
    return 0.0


@_jit_inline
def _copy(dst, src):
    # an explicit loop: slice assignment may allocate a temporary, which needs NRT
    for i in range(src.shape[0]):
        dst[i] = src[i]


@_jit_inline
def _poly(c, row, s):
    v = 0.0
    for j in range(c.shape[1]):
        v = v * s + c[row, j]
    return v


# ---------------------------------------------------------------- linear algebra


@_jit_inline
def _lu_factor(A, piv, n):
    """LU-factor ``A[:n,:n]`` in place with partial pivoting; False if singular."""
    for col in range(n):
        p = col
        best = abs(A[col, col])
        for r in range(col + 1, n):
            v = abs(A[r, col])
            if v > best:
                best = v
                p = r
        if best < 1e-300:
            return False
        piv[col] = p
        if p != col:
            for c in range(n):
                tmp = A[col, c]
                A[col, c] = A[p, c]
                A[p, c] = tmp
        inv = 1.0 / A[col, col]
        for r in range(col + 1, n):
            A[r, col] *= inv
            f = A[r, col]
            if f != 0.0:
                for c in range(col + 1, n):
                    A[r, c] -= f * A[col, c]
    return True


@_jit_inline
def _lu_solve(A, piv, b, n):
    """Solve with the factors of :func:`_lu_factor`; the result replaces ``b``."""
    for col in range(n):
        p = piv[col]
        if p != col:
            tmp = b[col]
            b[col] = b[p]
            b[p] = tmp
    for r in range(1, n):
        acc = b[r]
        for c in range(r):
            acc -= A[r, c] * b[c]
        b[r] = acc
    for r in range(n - 1, -1, -1):
        acc = b[r]
        for c in range(r + 1, n):
            acc -= A[r, c] * b[c]
        b[r] = acc / A[r, r]


# ---------------------------------------------------------------- right-hand side


@_jit_inline
def _capacity(j, t, left, x, net, ext):
    """Torque capacity factor of clutch ``j``: its signal, or the actuator's normal force."""
    if net.act.shape[0] > 0 and j == int(net.act[act_.CLUTCH]):
        f_n = act_.normal_force(x[int(net.act[act_.STATE]) + 1], net.act)
        return f_n * act_.friction_factor(f_n, net.act)
    return signal_value(net.cl_sig[j], t, left, net.sig, net.tab, ext)


@_jit_inline
def _rhs(t, left, x, net, ext, clm, grm, dx, aux, A, z, piv, sol, G, refactor, full=True):
    """Derivatives ``dx`` and element torques ``aux`` for fixed modes; False if singular.

    The constraint matrix depends on the modes only, so it is factored when
    ``refactor`` is set and the columns of its inverse that multiply the body
    torques are kept in ``G`` (solved one at a time in the scratch vector
    ``sol``); every other call is then a small matrix-vector product over
    contiguous rows of ``G`` instead of a triangular solve.

    ``aux`` layout: clutch torques (nc) | capacity signals (nc) | gear output
    torques (ng) | spring torques (ns) | gear input torques (ng).

    With ``full`` False only ``aux`` is needed (an output row): the accelerations
    and the actuator's pressure derivative are then skipped.
    """
    nb = net.J.shape[0]
    ns = net.sp_k.shape[0]
    nc = net.cl_a.shape[0]
    ng = net.gr_in.shape[0]
    e0 = nb + ns
    p_drag = 0.0
    for k in range(nb):
        tau = net.drag[k] * x[k] * abs(x[k])
        z[k] = -tau
        p_drag += tau * x[k]
    p_src = 0.0
    for j in range(net.src_body.shape[0]):
        tau = signal_value(net.src_sig[j], t, left, net.sig, net.tab, ext)
        bdy = net.src_body[j]
        z[bdy] += tau
        p_src += tau * x[bdy]
    p_damp = 0.0
    for j in range(ns):
        a = net.sp_a[j]
        b = net.sp_b[j]
        dw = x[a] - (x[b] if b >= 0 else 0.0)
        tau = net.sp_k[j] * x[nb + j] + net.sp_d[j] * dw
        z[a] -= tau
        if b >= 0:
            z[b] += tau
        dx[nb + j] = dw
        p_damp += net.sp_d[j] * dw * dw
        aux[2 * nc + ng + j] = tau
    if net.act.shape[0] > 0:
        u = signal_value(int(net.act[act_.U_SIG]), t, left, net.sig, net.tab, ext)
        f_stem, _ = act_.evaluate(x, net.act, u, ext, dx, full)
        stem = int(net.act[act_.STEM_BODY])
        z[stem] += f_stem
        p_src += f_stem * x[stem]
    nlock = 0
    for j in range(nc):
        a = net.cl_a[j]
        b = net.cl_b[j]
        slip = x[a] - (x[b] if b >= 0 else 0.0)
        cap = _capacity(j, t, left, x, net, ext)
        aux[nc + j] = cap
        m = clm[j]
        if m == LOCKED:
            nlock += 1
            dx[e0 + j] = 0.0
        elif m == FREE or cap <= 0.0:
            aux[j] = 0.0
            dx[e0 + j] = 0.0
        else:
            # the friction polynomial holds over the measured slip range; never negative
            tau = m * cap * max(_poly(net.cl_poly, j, abs(slip)), 0.0)
            z[a] -= tau
            if b >= 0:
                z[b] += tau
            aux[j] = tau
            dx[e0 + j] = tau * slip
    n = nb + nlock + ng
    for g in range(ng):
        if abs(grm[g]) == STUCK:
            n += 1
    if refactor:
        for r in range(n):
            for c in range(n):
                A[r, c] = 0.0
        for k in range(nb):
            A[k, k] = net.J[k]
        col = nb
        for j in range(nc):
            if clm[j] == LOCKED:
                a = net.cl_a[j]
                b = net.cl_b[j]
                A[a, col] += 1.0
                A[col, a] = 1.0
                if b >= 0:
                    A[b, col] -= 1.0
                    A[col, b] = -1.0
                col += 1
        for g in range(ng):
            i_in = net.gr_in[g]
            i_out = net.gr_out[g]
            if abs(grm[g]) == STUCK:
                # both flanges held; the two torques are free within the friction bounds
                A[i_out, col] -= 1.0
                A[col, i_out] = 1.0
                A[i_in, col + 1] -= 1.0
                A[col + 1, i_in] = 1.0
                col += 2
                continue
            c = 1.0 / net.gr_eta[g] if grm[g] > 0 else net.gr_eta[g]
            A[i_out, col] -= 1.0
            A[i_in, col] += net.gr_ratio[g] * c
            A[col, i_out] = 1.0
            A[col, i_in] = -net.gr_ratio[g]
            col += 1
        if not _lu_factor(A, piv, n):
            return False
        for c in range(nb):
            for r in range(n):
                sol[r] = 0.0
            sol[c] = 1.0
            _lu_solve(A, piv, sol, n)
            for r in range(n):
                G[r, c] = sol[r]
    # accelerations into dx, constraint torques into z[nb:n] (the right-hand side is zero there)
    for r in range(0 if full else nb, n):
        acc = 0.0
        for c in range(nb):
            acc += G[r, c] * z[c]
        if r < nb:
            dx[r] = acc
        else:
            z[r] = acc
    col = nb
    for j in range(nc):
        if clm[j] == LOCKED:
            aux[j] = z[col]
            col += 1
    p_gear = 0.0
    for g in range(ng):
        lam = z[col]
        aux[2 * nc + g] = lam
        if abs(grm[g]) == STUCK:
            aux[2 * nc + ng + ns + g] = z[col + 1]
            col += 2
            continue
        c = 1.0 / net.gr_eta[g] if grm[g] > 0 else net.gr_eta[g]
        p_gear += lam * x[net.gr_out[g]] * (c - 1.0)
        aux[2 * nc + ng + ns + g] = -net.gr_ratio[g] * c * lam
        col += 1
    dx[e0 + nc] = p_drag
    dx[e0 + nc + 1] = p_damp
    dx[e0 + nc + 2] = p_gear
    dx[e0 + nc + 3] = p_src
    return True


@_jit_inline
def _slip(x, net, j):
    b = net.cl_b[j]
    return x[net.cl_a[j]] - (x[b] if b >= 0 else 0.0)


@_jit_inline
def _hold_margins(aux, net, grm, k):
    """A stuck gear holds while the input torque, seen at the output (``q``), has the
    sign ``s`` of the held torque and ``eta |lam| <= |q| <= |lam| / eta``."""
    nc = net.cl_a.shape[0]
    ng = net.gr_in.shape[0]
    ns = net.sp_k.shape[0]
    lam = aux[2 * nc + k]
    q = -aux[2 * nc + ng + ns + k] / net.gr_ratio[k]
    sg = 1.0 if grm[k] > 0 else -1.0
    return sg * (q - net.gr_eta[k] * lam), sg * (lam / net.gr_eta[k] - q)


@_jit_inline
def _events(x, dx, aux, net, clm, grm, g):
    """Event functions: each is >= 0 while the current modes are valid."""
    nc = net.cl_a.shape[0]
    for j in range(nc):
        cap = aux[nc + j]
        m = clm[j]
        if m == LOCKED:
            g[2 * j] = net.cl_peak[j] * cap * _poly(net.cl_poly, j, 0.0) - abs(aux[j])
            g[2 * j + 1] = cap
        elif m == FREE:
            g[2 * j] = -cap
            g[2 * j + 1] = 1.0
        else:
            g[2 * j] = m * _slip(x, net, j)
            g[2 * j + 1] = cap
    ng = net.gr_in.shape[0]
    for k in range(ng):
        lam = aux[2 * nc + k]
        if abs(grm[k]) == STUCK:
            g[2 * nc + 2 * k], g[2 * nc + 2 * k + 1] = _hold_margins(aux, net, grm, k)
        else:
            g[2 * nc + 2 * k] = grm[k] * lam * x[net.gr_out[k]]
            g[2 * nc + 2 * k + 1] = 1.0


# ---------------------------------------------------------------- mode decisions


@_jit_inline
def _stale(fact, clm, grm):
    """Whether the constraint factors (``A``, ``G``) were made for other modes than ``clm``, ``grm``.

    The constraint matrix depends on the modes only, so a restart that keeps them (an input
    sample of a closed loop, a breakpoint) reuses its factors. ``fact`` records the modes of
    the factors and is updated here: the caller refactors when this returns True.
    """
    nc = clm.shape[0]
    stale = False
    for j in range(nc):
        if fact[j] != clm[j]:
            stale = True
            fact[j] = clm[j]
    for k in range(grm.shape[0]):
        if fact[nc + k] != grm[k]:
            stale = True
            fact[nc + k] = grm[k]
    return stale


@_jit_inline
def _forget(fact):
    # factors that failed are no factors
    for i in range(fact.shape[0]):
        fact[i] = _NO_MODE


@_jit
def _settle(t, x, net, ext, clm, grm, dx, aux, A, z, piv, sol, G, released, fact):
    """Decide consistent modes at an event or breakpoint; project newly locked speeds.

    ``released`` (nc + ng) is scratch space. Returns False if the system is singular.
    """
    nc = net.cl_a.shape[0]
    ng = net.gr_in.shape[0]
    t_right = t + 1e-9 * max(1.0, abs(t))
    for j in range(nc):
        a = net.cl_a[j]
        b = net.cl_b[j]
        cap = max(_capacity(j, t, False, x, net, ext), _capacity(j, t_right, False, x, net, ext))
        slip = _slip(x, net, j)
        scale = max(1.0, abs(x[a]), abs(x[b]) if b >= 0 else 0.0)
        if cap <= 0.0:
            clm[j] = FREE
        elif abs(slip) <= 1e-8 * scale:
            clm[j] = LOCKED
        else:
            clm[j] = 1 if slip > 0.0 else -1
    ns = net.sp_k.shape[0]
    # "at standstill" relative to the speeds in the network (rad/s scale of the run)
    w_scale = 1.0
    for k in range(net.J.shape[0]):
        w_scale = max(w_scale, abs(x[k]))
    for k in range(ng):
        i_in = net.gr_in[k]
        o = net.gr_out[k]
        if abs(x[o]) <= 1e-8 * w_scale and abs(x[i_in]) <= 1e-8 * w_scale:
            grm[k] = STUCK
        elif abs(grm[k]) == STUCK:
            grm[k] = 1
    # a clutch or gear released in this settle must not be re-locked (no cycling)
    released[:] = 0
    for _ in range(4 * (nc + ng) + 4):
        for k in range(ng):
            if abs(grm[k]) == STUCK:
                x[net.gr_in[k]] = 0.0
                x[net.gr_out[k]] = 0.0
        # project locked pairs onto equal speeds, weighted by inertia
        for j in range(nc):
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
        if not _rhs(t, False, x, net, ext, clm, grm, dx, aux, A, z, piv, sol, G, _stale(fact, clm, grm)):
            _forget(fact)
            return False
        changed = False
        for k in range(ng):
            o = net.gr_out[k]
            lam = aux[2 * nc + k]
            if abs(grm[k]) == STUCK:
                q = -aux[2 * nc + ng + ns + k] / net.gr_ratio[k]
                ref = lam if lam != 0.0 else q
                grm[k] = -STUCK if ref < 0.0 else STUCK
                m_in, m_out = _hold_margins(aux, net, grm, k)
                if m_in < 0.0:
                    grm[k] = -1  # the output side overcomes the input: power flows back
                elif m_out < 0.0:
                    grm[k] = 1  # the input side drives the output
                else:
                    continue
                released[nc + k] = 1
                changed = True
                break
            p = lam * (x[o] if x[o] != 0.0 else dx[o])
            if grm[k] * p < 0.0 and not (released[nc + k] != 0 and x[o] == 0.0):
                grm[k] = -grm[k]
                changed = True
        if changed:
            continue
        # release the locked clutch most beyond its static capacity; the test is
        # the event function itself, so a clutch kept locked starts with g >= 0
        worst = -1
        worst_excess = 0.0
        for j in range(nc):
            if clm[j] == LOCKED:
                lim = net.cl_peak[j] * aux[nc + j] * _poly(net.cl_poly, j, 0.0)
                if lim - abs(aux[j]) < 0.0:
                    excess = abs(aux[j]) / lim if lim > 0.0 else np.inf
                    if excess > worst_excess:
                        worst_excess = excess
                        worst = j
        if worst >= 0:
            clm[worst] = 1 if aux[worst] > 0.0 else -1
            released[worst] = 1
            continue
        # a clutch sliding from zero slip must accelerate in its own direction
        for j in range(nc):
            m = clm[j]
            if (m == 1 or m == -1) and released[j] == 0:
                a = net.cl_a[j]
                b = net.cl_b[j]
                if _slip(x, net, j) * m <= 0.0:
                    rel = dx[a] - (dx[b] if b >= 0 else 0.0)
                    if rel * m < 0.0:
                        clm[j] = LOCKED
                        changed = True
        if not changed:
            break
    return True


# ---------------------------------------------------------------- Dormand-Prince 5(4)

_C = np.array([0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0])
_A = np.array(
    [
        [0.0, 0.0, 0.0, 0.0, 0.0],
        [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0],
        [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0],
        [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0],
        [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0],
        [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0],
    ]
)
_B = np.array([35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0])
_E = np.array(
    [-71.0 / 57600.0, 0.0, 71.0 / 16695.0, -71.0 / 1920.0, 17253.0 / 339200.0, -22.0 / 525.0, 1.0 / 40.0]
)
# Shampine's 4th-order continuous extension (as in scipy's RK45)
_P = np.array(
    [
        [1.0, -8048581381.0 / 2820520608.0, 8663915743.0 / 2820520608.0, -12715105075.0 / 11282082432.0],
        [0.0, 0.0, 0.0, 0.0],
        [0.0, 131558114200.0 / 32700410799.0, -68118460800.0 / 10900136933.0, 87487479700.0 / 32700410799.0],
        [0.0, -1754552775.0 / 470086768.0, 14199869525.0 / 1410260304.0, -10690763975.0 / 1880347072.0],
        [0.0, 127303824393.0 / 49829197408.0, -318862633887.0 / 49829197408.0, 701980252875.0 / 199316789632.0],
        [0.0, -282668133.0 / 205662961.0, 2019193451.0 / 616988883.0, -1453857185.0 / 822651844.0],
        [0.0, 40617522.0 / 29380423.0, -110615467.0 / 29380423.0, 69997945.0 / 29380423.0],
    ]
)


# the tableau as scalars: numba folds them into the code, and each stage becomes one
# straight vectorisable loop instead of a loop over stages inside a loop over states
(_A10,) = _A[1, :1]
_A20, _A21 = _A[2, :2]
_A30, _A31, _A32 = _A[3, :3]
_A40, _A41, _A42, _A43 = _A[4, :4]
_A50, _A51, _A52, _A53, _A54 = _A[5, :5]
_B0, _B1, _B2, _B3, _B4, _B5 = _B
_E0, _E1, _E2, _E3, _E4, _E5, _E6 = _E


@_jit_inline
def _stage(y0, K, h, s, out):
    """State at stage ``s`` (1..5) of a Dormand-Prince step; ``s == 6`` is the 5th-order solution."""
    n = y0.shape[0]
    if s == 1:
        for i in range(n):
            out[i] = y0[i] + h * (_A10 * K[0, i])
    elif s == 2:
        for i in range(n):
            out[i] = y0[i] + h * (_A20 * K[0, i] + _A21 * K[1, i])
    elif s == 3:
        for i in range(n):
            out[i] = y0[i] + h * (_A30 * K[0, i] + _A31 * K[1, i] + _A32 * K[2, i])
    elif s == 4:
        for i in range(n):
            out[i] = y0[i] + h * (_A40 * K[0, i] + _A41 * K[1, i] + _A42 * K[2, i] + _A43 * K[3, i])
    elif s == 5:
        for i in range(n):
            out[i] = y0[i] + h * (_A50 * K[0, i] + _A51 * K[1, i] + _A52 * K[2, i] + _A53 * K[3, i] + _A54 * K[4, i])
    else:
        for i in range(n):
            out[i] = y0[i] + h * (_B0 * K[0, i] + _B2 * K[2, i] + _B3 * K[3, i] + _B4 * K[4, i] + _B5 * K[5, i])


@_jit_inline
def _error_norm(y0, y1, K, h, rtol, atol, buf):
    """RMS of the embedded error estimate scaled by ``atol + rtol |y|``; ``buf`` is scratch.

    The squares go through ``buf`` so that the divisions run as one vector loop apart from
    the (ordered, hence serial) sum: 25 instead of 45 ns per step.
    """
    n = y0.shape[0]
    for i in range(n):
        e = _E0 * K[0, i] + _E2 * K[2, i] + _E3 * K[3, i] + _E4 * K[4, i] + _E5 * K[5, i] + _E6 * K[6, i]
        sc = atol + rtol * max(abs(y0[i]), abs(y1[i]))
        r = h * e / sc
        buf[i] = r * r
    acc = 0.0
    for i in range(n):
        acc += buf[i]
    return np.sqrt(acc / n)


@_jit_inline
def _dense(y0, K, h, theta, out, bw):
    nx = y0.shape[0]
    for s in range(7):
        th = theta
        v = 0.0
        for j in range(4):
            v += _P[s, j] * th
            th *= theta
        bw[s] = v
    for i in range(nx):
        acc = 0.0
        for s in range(7):
            acc += bw[s] * K[s, i]
        out[i] = y0[i] + h * acc


class Workspace(NamedTuple):
    """Preallocated buffers and the integrator's running state for one network."""

    x: np.ndarray  # current state
    clm: np.ndarray  # clutch modes
    grm: np.ndarray  # gear modes (+1 forward, -1 backward, +-STUCK held at standstill)
    fstate: np.ndarray  # [t, h, log of the previous accepted error, next PWM edge, PWM period start,
    #                      first step after the last PWM edge to level 0, to level 1 (0: none yet)]
    istate: np.ndarray  # [need_settle, n_out, n_steps, n_rejected, n_events, n_switches, n_evlog, last event fn]
    K: np.ndarray  # (7, nx) stages
    dx: np.ndarray
    aux: np.ndarray
    aux_new: np.ndarray
    g_old: np.ndarray
    g_new: np.ndarray
    A: np.ndarray  # LU factors of the constraint matrix for the current modes
    z: np.ndarray
    piv: np.ndarray
    sol: np.ndarray  # (nmat,) scratch: one column of the inverse constraint matrix
    G: np.ndarray  # (nmat, nb) torque-to-solution columns of the inverse constraint matrix
    y_new: np.ndarray
    y_tmp: np.ndarray
    bw: np.ndarray  # (7,) dense-output weights
    y_old: np.ndarray  # state at the start of the current step
    clm_before: np.ndarray  # clutch modes before a restart
    released: np.ndarray  # (nc + ng) scratch for _settle
    fact: np.ndarray  # (nc + ng) clutch and gear modes the factors in A, G were made for (see _stale)
    evlog: np.ndarray  # (max_events, 3): t, element index, new mode


@_jit
def _eval_at(theta_t, t_old, h, y_old, ws, net, ext):
    """State and event functions at ``theta_t`` inside the last step (fixed modes)."""
    _dense(y_old, ws.K, h, (theta_t - t_old) / h, ws.y_tmp, ws.bw)
    _rhs(theta_t, False, ws.y_tmp, net, ext, ws.clm, ws.grm, ws.dx, ws.aux_new, ws.A, ws.z, ws.piv, ws.sol, ws.G, False)
    _events(ws.y_tmp, ws.dx, ws.aux_new, net, ws.clm, ws.grm, ws.g_new)


@_jit_inline
def _emit(t, y, ws, net, ext, out_t, out_x, out_aux, out_mode):
    """Write one output row (state, element torques, clutch modes) at time ``t``."""
    i = ws.istate[1]
    if i >= out_t.shape[0]:
        return
    _rhs(t, False, y, net, ext, ws.clm, ws.grm, ws.dx, ws.aux_new, ws.A, ws.z, ws.piv, ws.sol, ws.G, False, False)
    out_t[i] = t
    _copy(out_x[i], y)
    _copy(out_aux[i], ws.aux_new)
    for j in range(ws.clm.shape[0]):
        out_mode[i, j] = ws.clm[j]
    ws.istate[1] = i + 1


@_jit
def _log_modes(t, before, ws):
    for j in range(ws.clm.shape[0]):
        if ws.clm[j] != before[j] and before[j] != UNDECIDED:
            n = ws.istate[6]
            if n < ws.evlog.shape[0]:
                ws.evlog[n, 0] = t
                ws.evlog[n, 1] = j
                ws.evlog[n, 2] = ws.clm[j]
            ws.istate[6] = n + 1
            ws.istate[5] += 1


@_jit
def _restart(ws, net, ext):
    """Re-decide modes at the current time and refresh the first stage."""
    t = ws.fstate[0]
    _copy(ws.clm_before, ws.clm)
    if not _settle(t, ws.x, net, ext, ws.clm, ws.grm, ws.dx, ws.aux, ws.A, ws.z, ws.piv, ws.sol, ws.G, ws.released,
                   ws.fact):
        return False
    _log_modes(t, ws.clm_before, ws)
    if not _rhs(t, False, ws.x, net, ext, ws.clm, ws.grm, ws.dx, ws.aux, ws.A, ws.z, ws.piv, ws.sol, ws.G,
                _stale(ws.fact, ws.clm, ws.grm)):
        _forget(ws.fact)
        return False
    _copy(ws.K[0], ws.dx)
    _events(ws.x, ws.dx, ws.aux, net, ws.clm, ws.grm, ws.g_old)
    ws.istate[0] = 0
    return True


@_jit
def _pwm_edge(t, ws, net, ext):
    """At a PWM edge (or the start): switch the coil drive level and schedule the next edge.

    The duty cycle is the actuator input, sampled at the start of each period.
    ``fstate[3]`` is the next edge, ``fstate[4]`` the start of the current period.
    Returns the new level (0 or 1) and proposes the first step after it: the one that
    followed the last edge to that level (``fstate[5 + level]``; see :func:`advance`), since
    the periods repeat nearly alike and the step before the edge knows nothing of the jump.
    """
    a = net.act
    lvl = int(a[act_.PWM_EXT])
    period = 1.0 / a[act_.PWM_FREQ]
    if ext[lvl] > 0.5 and t < ws.fstate[4] + period - 1e-12 * max(1.0, t):
        ext[lvl] = 0.0  # falling edge inside the period
        ws.fstate[3] = ws.fstate[4] + period
    else:
        ws.fstate[4] = t
        duty = signal_value(int(a[act_.U_SIG]), t, False, net.sig, net.tab, ext)
        if duty <= 0.0:
            ext[lvl] = 0.0
            ws.fstate[3] = t + period
        elif duty >= 1.0:
            ext[lvl] = 1.0
            ws.fstate[3] = t + period
        else:
            ext[lvl] = 1.0
            ws.fstate[3] = t + duty * period
    level = 1 if ext[lvl] > 0.5 else 0
    if ws.fstate[5 + level] > 0.0:
        ws.fstate[1] = ws.fstate[5 + level]
    return level


@_jit
def advance(net, ext, ws, t_stop, dt_out, t_out0, rtol, atol, h_max, out_t, out_x, out_aux, out_mode):
    """Integrate from the workspace's time to ``t_stop``; write outputs on the grid.

    Output rows are written at ``t_out0 + j * dt_out`` for every grid time in
    ``[t, t_stop)``, and at ``t_stop`` itself when it lies on the grid and is the
    last grid time. Calling ``advance`` again continues where it stopped (after a
    caller has changed ``ext``, set ``ws.istate[0] = 1`` to re-decide modes).

    Returns a status code (``OK``, ``ERR_SINGULAR``, ``ERR_ZENO``).
    """
    n_grid = out_t.shape[0]
    y_old = ws.y_old
    t = ws.fstate[0]
    stalls = 0
    bp_i = np.searchsorted(net.bps, t, side="right")
    pwm = net.act.shape[0] > 0 and net.act[act_.MODE] == act_.PWM
    after_edge = -1  # level of the PWM edge the next accepted step follows (-1: none)
    if pwm and ws.fstate[3] == -np.inf:
        after_edge = _pwm_edge(t, ws, net, ext)
        ws.istate[0] = 1
    if ws.istate[0] != 0:
        if not _restart(ws, net, ext):
            return ERR_SINGULAR
    while t < t_stop:
        h = min(ws.fstate[1], h_max)
        t_lim = t_stop
        hit_bp = False
        if bp_i < net.bps.shape[0] and net.bps[bp_i] <= t_lim:
            t_lim = net.bps[bp_i]
            hit_bp = True
        hit_pwm = False
        if pwm and ws.fstate[3] <= t_lim:
            hit_pwm = True
            if ws.fstate[3] < t_lim:
                t_lim = ws.fstate[3]
                hit_bp = False
        if t + h >= t_lim - 1e-12 * max(1.0, abs(t_lim)):
            h = t_lim - t
            at_lim = True
        else:
            at_lim = False
        if h <= 0.0:
            # a breakpoint or PWM edge at the current time
            if hit_bp or hit_pwm:
                if hit_bp:
                    bp_i += 1
                if hit_pwm:
                    after_edge = _pwm_edge(t, ws, net, ext)
                if not _restart(ws, net, ext):
                    return ERR_SINGULAR
                continue
            break
        _copy(y_old, ws.x)
        for s in range(1, 6):
            _stage(y_old, ws.K, h, s, ws.y_tmp)
            if not _rhs(t + _C[s] * h, True, ws.y_tmp, net, ext, ws.clm, ws.grm, ws.K[s], ws.aux_new, ws.A, ws.z, ws.piv, ws.sol, ws.G, False):
                return ERR_SINGULAR
        _stage(y_old, ws.K, h, 6, ws.y_new)
        t_new = t_lim if at_lim else t + h
        if not _rhs(t_new, True, ws.y_new, net, ext, ws.clm, ws.grm, ws.K[6], ws.aux_new, ws.A, ws.z, ws.piv, ws.sol, ws.G, False):
            return ERR_SINGULAR
        err = _error_norm(y_old, ws.y_new, ws.K, h, rtol, atol, ws.y_tmp)  # y_tmp (stage 5) is free again
        # PI step control (Hairer's DOPRI5): steadier near the stability limit
        # in logarithms: one log and one exp per step instead of two powers
        log_err = np.log(err + 1e-30)
        if err > 1.0:
            ws.fstate[1] = h / min(5.0, np.exp(0.17 * log_err) / 0.9)
            ws.istate[3] += 1
            continue
        ws.istate[2] += 1
        _events(ws.y_new, ws.K[6], ws.aux_new, net, ws.clm, ws.grm, ws.g_new)
        # earliest event in (t, t_new]: bracket [ta, tb] with g(ta) >= 0 > g(tb)
        t_ev = np.inf
        e_ev = -1
        ng_ev = ws.g_old.shape[0]
        for e in range(ng_ev):
            if ws.g_old[e] >= 0.0 and ws.g_new[e] < 0.0:
                ta = t
                ga = ws.g_old[e]
                tb = t_new if t_ev == np.inf else t_ev
                if tb < t_new:
                    _eval_at(tb, t, h, y_old, ws, net, ext)
                    gb = ws.g_new[e]
                    if gb >= 0.0:
                        continue
                else:
                    gb = ws.g_new[e]
                side = 0
                for _ in range(100):
                    if tb - ta <= 1e-13 * max(1.0, abs(tb)):
                        break
                    tm = (ta * gb - tb * ga) / (gb - ga)
                    if not (ta < tm < tb):
                        tm = 0.5 * (ta + tb)
                    _eval_at(tm, t, h, y_old, ws, net, ext)
                    gm = ws.g_new[e]
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
                t_ev = tb
                e_ev = e
        # emit grid points in [t, end of this step)
        t_seg = t_new if t_ev == np.inf else t_ev
        j = ws.istate[1]
        while j < n_grid and t_out0 + j * dt_out < t_seg:
            tg = t_out0 + j * dt_out
            _dense(y_old, ws.K, h, (tg - t) / h, ws.y_tmp, ws.bw)
            _emit(tg, ws.y_tmp, ws, net, ext, out_t, out_x, out_aux, out_mode)
            j = ws.istate[1]
        if t_ev != np.inf:
            _dense(y_old, ws.K, h, (t_ev - t) / h, ws.x, ws.bw)
            if t_ev - t <= 1e-12 * max(1.0, abs(t)):
                stalls += 1
                if stalls > 100:
                    return ERR_ZENO
            else:
                stalls = 0
            t = t_ev
            ws.fstate[0] = t
            ws.istate[4] += 1
            ws.istate[7] = e_ev
            if not _restart(ws, net, ext):
                return ERR_SINGULAR
            continue
        stalls = 0
        _copy(ws.x, ws.y_new)
        t = t_new
        ws.fstate[0] = t
        fac = max(0.1, min(5.0, np.exp(0.17 * log_err - 0.04 * ws.fstate[2]) / 0.9))
        ws.fstate[2] = max(log_err, np.log(1e-4))
        ws.fstate[1] = h / fac if not at_lim else max(ws.fstate[1], h)
        if after_edge >= 0:
            ws.fstate[5 + after_edge] = h / fac  # what this first step after the edge should have been
            after_edge = -1
        if at_lim and (hit_bp or hit_pwm):
            if hit_bp:
                bp_i += 1
            if hit_pwm:
                after_edge = _pwm_edge(t, ws, net, ext)
            if not _restart(ws, net, ext):
                return ERR_SINGULAR
        else:
            _copy(ws.K[0], ws.K[6])
            _copy(ws.g_old, ws.g_new)
            _copy(ws.aux, ws.aux_new)
    # the last grid point, when it falls on t_stop (earlier ones start the next call)
    j = ws.istate[1]
    if j == n_grid - 1 and abs(t_out0 + j * dt_out - t_stop) <= 1e-9 * max(1.0, dt_out):
        _emit(t_stop, ws.x, ws, net, ext, out_t, out_x, out_aux, out_mode)
    return OK
