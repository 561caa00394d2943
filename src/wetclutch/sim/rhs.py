"""The right-hand side of a network for fixed modes, and the event functions that end those modes.

Sign conventions (as in Modelica ``Mechanics.Rotational``): every element joins a flange
``a`` to a flange ``b`` (body indices; ``-1`` is the ground).

* clutch / brake: slip ``w_a - w_b``; the element's torque ``T`` acts on ``b`` and ``-T``
  on ``a``. Sliding: ``T = cap * mu(|slip|) * sign(slip)``. Locked: ``T`` is a constraint
  torque, bounded by ``peak * cap * mu(0)``.
* gear (``in`` = a, ``out`` = b): ``w_out = ratio * w_in``; its torque ``lam`` acts on
  ``out``, and ``-ratio * c * lam`` on ``in`` with ``c = 1/eta`` when power flows in -> out
  (``lam * w_out > 0``) and ``c = eta`` when it flows back, so losses never create power.
  A moving ratio (a CVT shifting) is a state ``r`` with ``r' = rate(t)``, the commanded
  rate held within the gear's rate limit; reaching a ratio limit is an event, after which
  it is held there (a mode) until the command turns back. Its constraint differentiates
  to ``a_out - r a_in = r' w_in``: the row gets that velocity term. The ideal gear still
  does no work of its own (power in equals power out for ``eta = 1``, whatever ``r'``), so
  the energy account is unchanged.
* spring-damper: deflection ``phi' = w_a - w_b``; torque ``k phi + d (w_a - w_b)`` on
  ``b``, its negative on ``a``.

Locked clutches and gears are acceleration constraints, solved together with the bodies
in one small linear (KKT) system ``[M B; G 0] [a; lam] = [f; v]`` (``v``: the velocity terms
of moving ratios, else 0). Its matrix depends on the modes and the ratios only, so it is
factored when they change and the columns of its inverse that multiply the body torques
(and the velocity terms) are kept: every other evaluation is a small matrix-vector
product. The columns of the last few mode combinations are kept too (:func:`factors`): a
clutch that sticks and slips by turns, such as the valve stem under a dithered input, comes
back to modes whose system was solved before.
"""

from __future__ import annotations

from ..physics import actuator as act_
from ..physics import thermal as th_
from . import signals
from .compiled import jit, jit_inline
from .linalg import lu_factor, lu_solve, svd_jacobi
from .workspace import (E_DAMPER, E_DRAG, E_GEAR, E_SOURCE, FACTOR_CACHE, FREE, FS_AMP, FS_AMP_G, FS_PISTON,
                        FS_PLAY_CUR, FS_PLAY_DIR, FS_PLAY_G, FS_PLAY_TAU, IDLE, IS_BAD_BODY, IS_CACHE_NEXT,
                        IS_REDUNDANT, LOCKED, STUCK, aux_offsets, fs_grip, fs_ratio)

# columns of NetArrays.gr_lim: a moving ratio's limits and its rate limit (1/s)
LIM_MIN, LIM_MAX, LIM_RATE = 0, 1, 2


@jit_inline
def copy(dst, src):
    # an explicit loop: slice assignment may allocate a temporary, which needs NRT
    for i in range(src.shape[0]):
        dst[i] = src[i]


@jit_inline
def poly(c, row, s):
    """Row ``row`` of the coefficient table ``c`` (highest power first) at ``s`` (Horner)."""
    v = 0.0
    for j in range(c.shape[1]):
        v = v * s + c[row, j]
    return v


@jit_inline
def capacity(j, t, left, x, net, ext):
    """Torque capacity factor of clutch ``j``: its signal, or the actuator's normal force; times the
    heated pack's friction factor."""
    if net.act.shape[0] > 0 and j == int(net.act[act_.CLUTCH]):
        f_n = act_.normal_force(x[int(net.act[act_.STATE]) + act_.PRESSURE], net.act)
        cap = f_n * act_.friction_factor(f_n, net.act)
    else:
        cap = signals.value(net.cl_sig[j], t, left, net.sig, net.tab, ext)
    if net.th.shape[0] > 0 and j == int(net.th[th_.CLUTCH]):
        cap *= th_.friction_factor(x, net.th)
    return cap


@jit_inline
def ratio(x, net, g):
    """The ratio ``w_out / w_in`` of gear ``g``: its state if it moves, else its constant."""
    k = net.gr_state[g]
    return net.gr_ratio[g] if k < 0 else x[k]


@jit_inline
def rate_command(t, left, net, ext, g):
    """Gear ``g``'s commanded ratio rate within its rate limit, 1/s."""
    lim = net.gr_lim[g, LIM_RATE]
    return min(max(signals.value(net.gr_rate_sig[g], t, left, net.sig, net.tab, ext), -lim), lim)


@jit_inline
def _ratio_rates(t, left, net, ext, dx, fstate):
    """The moving ratios' rates into ``dx``: the command within the rate limit, none while held at a limit
    (their commands into ``fstate`` for the event functions). True if the network has a moving ratio."""
    moving = False
    ng = net.gr_in.shape[0]
    o = fs_ratio(net.cl_a.shape[0]) + ng
    for g in range(ng):
        k = net.gr_state[g]
        if k < 0:
            continue
        moving = True
        rate = rate_command(t, left, net, ext, g)
        fstate[o + ng + g] = rate
        dx[k] = 0.0 if fstate[o + g] != 0.0 else rate
    return moving


@jit_inline
def _ratios_moved(x, net, fstate):
    """Whether a moving ratio differs from the one the constraint factors were made with."""
    o = fs_ratio(net.cl_a.shape[0])
    for g in range(net.gr_in.shape[0]):
        k = net.gr_state[g]
        if k >= 0 and x[k] != fstate[o + g]:
            return True
    return False


@jit_inline
def slip(x, net, j):
    b = net.cl_b[j]
    return x[net.cl_a[j]] - (x[b] if b >= 0 else 0.0)


@jit_inline
def spring_torque(net, j, x):
    """Torque of spring-damper ``j`` on its flange ``b`` and its deflection rate ``w_a - w_b``."""
    nb = net.J.shape[0]
    a = net.sp_a[j]
    b = net.sp_b[j]
    dw = x[a] - (x[b] if b >= 0 else 0.0)
    return net.sp_k[j] * x[nb + j] + net.sp_d[j] * dw, dw


@jit_inline
def _applied_torques(t, left, x, net, ext, dx, aux, z):
    """Drag, source and spring torques into ``z``, spring rates into ``dx``; their powers (drag, source, damper)."""
    nb = net.J.shape[0]
    nc = net.cl_a.shape[0]
    ng = net.gr_in.shape[0]
    ns = net.sp_k.shape[0]
    o_spring = aux_offsets(nc, ng, ns)[3]
    p_drag = 0.0
    for k in range(nb):
        tau = net.drag[k] * x[k] * abs(x[k])
        z[k] = -tau
        p_drag += tau * x[k]
    p_src = 0.0
    for j in range(net.src_body.shape[0]):
        tau = signals.value(net.src_sig[j], t, left, net.sig, net.tab, ext)
        bdy = net.src_body[j]
        z[bdy] += tau
        p_src += tau * x[bdy]
    p_damp = 0.0
    for j in range(ns):
        a = net.sp_a[j]
        b = net.sp_b[j]
        tau, dw = spring_torque(net, j, x)
        z[a] -= tau
        if b >= 0:
            z[b] += tau
        dx[nb + j] = dw
        p_damp += net.sp_d[j] * dw * dw
        aux[o_spring + j] = tau
    return p_drag, p_src, p_damp


@jit_inline
def _clutch_torques(t, left, x, net, ext, clm, dx, aux, z):
    """Sliding clutches' torques into ``z`` and ``aux``, capacities into ``aux``, their dissipation rates into
    ``dx``; the number of locked clutches."""
    nb = net.J.shape[0]
    ns = net.sp_k.shape[0]
    nc = net.cl_a.shape[0]
    e0 = nb + ns
    nlock = 0
    for j in range(nc):
        a = net.cl_a[j]
        b = net.cl_b[j]
        s = x[a] - (x[b] if b >= 0 else 0.0)
        cap = capacity(j, t, left, x, net, ext)
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
            tau = m * cap * max(poly(net.cl_poly, j, abs(s)), 0.0)
            z[a] -= tau
            if b >= 0:
                z[b] += tau
            aux[j] = tau
            dx[e0 + j] = tau * s
    return nlock


@jit_inline
def _build_constraints(net, x, clm, grm, A, o, n):
    """The constraint matrix of the current modes into rows ``o .. o + n`` of ``A``."""
    nb = net.J.shape[0]
    nc = net.cl_a.shape[0]
    ng = net.gr_in.shape[0]
    for r in range(n):
        for c in range(n):
            A[o + r, c] = 0.0
    for k in range(nb):
        A[o + k, k] = net.J[k]
    col = nb
    for j in range(nc):
        if clm[j] == LOCKED:
            a = net.cl_a[j]
            b = net.cl_b[j]
            A[o + a, col] += 1.0
            A[o + col, a] = 1.0
            if b >= 0:
                A[o + b, col] -= 1.0
                A[o + col, b] = -1.0
            col += 1
    for g in range(ng):
        i_in = net.gr_in[g]
        i_out = net.gr_out[g]
        if abs(grm[g]) == STUCK:
            # both flanges held; the two torques are free within the friction bounds
            A[o + i_out, col] -= 1.0
            A[o + col, i_out] = 1.0
            A[o + i_in, col + 1] -= 1.0
            A[o + col + 1, i_in] = 1.0
            col += 2
            continue
        if abs(grm[g]) == IDLE:
            # no torque (its row: lam = 0) and no constraint of its own: the locks beside it hold it
            A[o + col, col] = 1.0
            col += 1
            continue
        c = 1.0 / net.gr_eta[g] if grm[g] > 0 else net.gr_eta[g]
        r = ratio(x, net, g)
        A[o + i_out, col] -= 1.0
        A[o + i_in, col] += r * c
        A[o + col, i_out] = 1.0
        A[o + col, i_in] = -r
        col += 1


@jit_inline
def _gear_row(net, clm, grm, g):
    """The row of gear ``g``'s velocity constraint in the constraint matrix (-1: a stuck gear, whose rows hold
    its flanges at rest and have no velocity term, or an idle one, which has no constraint row)."""
    if abs(grm[g]) == STUCK or abs(grm[g]) == IDLE:
        return -1
    row = net.J.shape[0]
    for j in range(net.cl_a.shape[0]):
        if clm[j] == LOCKED:
            row += 1
    for k in range(g):
        row += 2 if abs(grm[k]) == STUCK else 1
    return row


@jit
def _factor_constraints(net, x, clm, grm, A, piv, sol, G, n, istate, fstate):
    """Build and LU-factor the constraint matrix of the current modes and ratios; keep the inverse's
    body-torque columns in ``G`` (and, with moving ratios, the gear rows' columns after them). A singular
    matrix (redundant locks) goes to :func:`_least_norm_constraints`. False if the motion is not
    determined (the body in ``istate[IS_BAD_BODY]``).

    Called, not inlined: it runs only when the modes or a ratio change, and inlined into every
    evaluation of the right-hand side it made the core's compilation several times slower."""
    nb = net.J.shape[0]
    ng = net.gr_in.shape[0]
    o = fs_ratio(net.cl_a.shape[0])
    for g in range(ng):
        fstate[o + g] = ratio(x, net, g)
    _build_constraints(net, x, clm, grm, A, 0, n)
    scale = 0.0
    for r in range(n):
        for c in range(n):
            scale = max(scale, abs(A[r, c]))
    if not lu_factor(A, piv, n, 1e-13 * scale):
        istate[IS_REDUNDANT] = 1
        return _least_norm_constraints(net, x, clm, grm, A, G, n, istate)
    istate[IS_REDUNDANT] = 0
    for c in range(nb):
        for r in range(n):
            sol[r] = 0.0
        sol[c] = 1.0
        lu_solve(A, piv, sol, n)
        for r in range(n):
            G[r, c] = sol[r]
    if G.shape[1] > nb:
        # with moving ratios: the columns that multiply the gear rows' velocity terms
        for g in range(ng):
            row = _gear_row(net, clm, grm, g)
            for r in range(n):
                sol[r] = 0.0
            if row >= 0:
                sol[row] = 1.0
                lu_solve(A, piv, sol, n)
            for r in range(n):
                G[r, nb + g] = sol[r]
    _exact_zeros(G, n, nb)
    return True


@jit_inline
def _exact_zeros(G, n, nb):
    """Rounding-level entries of the solution operator to exact zeros, where the exact operator has
    them: a body that locks hold at rest keeps its speed exactly, so no event function of an
    element at standstill (a gear's power flow) creeps through zero by rounding."""
    g_max = 0.0
    for r in range(n):
        for c in range(nb):
            g_max = max(g_max, abs(G[r, c]))
    for r in range(n):
        for c in range(nb):
            if abs(G[r, c]) <= 1e-13 * g_max:
                G[r, c] = 0.0


@jit_inline
def _least_norm_constraints(net, x, clm, grm, A, G, n, istate):
    """Redundant locks: the least-norm solution of the singular constraint system into ``G``.

    Two locks that hold the same body (parallel clutches, a brake on either side of a gear,
    a stuck gear and a bearing brake) make the matrix singular: the motion is still unique,
    the constraint torques are not. The solution operator is the pseudo-inverse (from a
    Jacobi SVD in the spare rows of ``A``), which picks, of all torque distributions that
    give the motion, the one of least Euclidean norm. A null vector that moves a body means
    the motion itself is undetermined: False, with that body in ``istate[IS_BAD_BODY]``. A body
    without inertia that nothing holds is named before one with inertia: only a lossy gear's loss
    against a lock beside it leaves a body with inertia open, which the mode decision resolves
    (:func:`wetclutch.sim.modes._evaluate`), so what it cannot resolve is the massless body.
    """
    nb = net.J.shape[0]
    nm = A.shape[1]
    o_u = nm
    o_v = 2 * nm
    o_s = o_v + n
    _build_constraints(net, x, clm, grm, A, o_u, n)
    svd_jacobi(A, o_u, o_v, n)
    s_max = 0.0
    for j in range(n):
        s_max = max(s_max, A[o_s, j])
    tol = 1e-11 * s_max
    istate[IS_BAD_BODY] = -1
    worst = -1
    w_max = 1e-8
    massless = -1
    m_max = 1e-8
    for j in range(n):
        if A[o_s, j] <= tol:
            for k in range(nb):
                v = abs(A[o_v + k, j])
                if v > w_max:
                    w_max = v
                    worst = k
                if net.J[k] == 0.0 and v > m_max:
                    m_max = v
                    massless = k
    if worst >= 0:
        istate[IS_BAD_BODY] = massless if massless >= 0 else worst
        return False
    for c in range(G.shape[1]):
        # body torque c, or (moving ratios) the velocity term of gear c - nb, in its row
        src = c if c < nb else _gear_row(net, clm, grm, c - nb)
        for r in range(n):
            acc = 0.0
            if src >= 0:
                for j in range(n):
                    sj = A[o_s, j]
                    if sj > tol:
                        acc += A[o_v + r, j] * A[o_u + src, j] / (sj * sj)
            G[r, c] = acc
    _exact_zeros(G, n, nb)
    return True


@jit_inline
def _solve_constraints(G, z, dx, nb, n, full, vel, nv):
    """Accelerations into ``dx`` (skipped unless ``full``) and constraint torques into ``z[nb:n]``
    (the right-hand side there: the velocity terms ``vel`` of the first ``nv`` gears, none if 0)."""
    for r in range(0 if full else nb, n):
        acc = 0.0
        for c in range(nb):
            acc += G[r, c] * z[c]
        for g in range(nv):
            acc += G[r, nb + g] * vel[g]
        if r < nb:
            dx[r] = acc
        else:
            z[r] = acc


@jit_inline
def _constraint_torques(x, net, clm, grm, z, aux):
    """Locked clutches' and gears' torques from the solution into ``aux``; the gears' loss power."""
    nb = net.J.shape[0]
    nc = net.cl_a.shape[0]
    ng = net.gr_in.shape[0]
    ns = net.sp_k.shape[0]
    _, _, o_gear_out, _, o_gear_in = aux_offsets(nc, ng, ns)
    col = nb
    for j in range(nc):
        if clm[j] == LOCKED:
            aux[j] = z[col]
            col += 1
    p_gear = 0.0
    for g in range(ng):
        lam = z[col]
        aux[o_gear_out + g] = lam
        if abs(grm[g]) == STUCK:
            aux[o_gear_in + g] = z[col + 1]
            col += 2
            continue
        if abs(grm[g]) == IDLE:
            aux[o_gear_out + g] = 0.0
            aux[o_gear_in + g] = 0.0
            col += 1
            continue
        c = 1.0 / net.gr_eta[g] if grm[g] > 0 else net.gr_eta[g]
        p_gear += lam * x[net.gr_out[g]] * (c - 1.0)
        aux[o_gear_in + g] = -ratio(x, net, g) * c * lam
        col += 1
    return p_gear


@jit
def factors(net, x, clm, grm, ws, n):
    """The constraint solution ``ws.G`` of the current modes and ratios (:func:`_factor_constraints`), taken from
    the cache in ``ws.A``'s last rows where these modes and ratios had it made before. A cached solution is the one
    the factorisation gives (the same operations on the same matrix), so the motion does not depend on the cache.
    Redundant locks' least-norm solutions are not cached."""
    nc = net.cl_a.shape[0]
    ng = net.gr_in.shape[0]
    A, G = ws.A, ws.G
    nmat = A.shape[1]
    base = A.shape[0] - FACTOR_CACHE * (nmat + 1)
    o = fs_ratio(nc)
    for k in range(FACTOR_CACHE):
        key = base + k * (nmat + 1)
        if A[key, 0] != 1.0 or A[key, 1] != n:
            continue
        same = True
        for j in range(nc):
            if A[key, 2 + j] != clm[j]:
                same = False
                break
        if same:
            for g in range(ng):
                if A[key, 2 + nc + g] != grm[g] or A[key, 2 + nc + ng + g] != ratio(x, net, g):
                    same = False
                    break
        if not same:
            continue
        for g in range(ng):
            ws.fstate[o + g] = A[key, 2 + nc + ng + g]
        for r in range(n):
            for c in range(G.shape[1]):
                G[r, c] = A[key + 1 + r, c]
        ws.istate[IS_REDUNDANT] = 0
        return True
    if not _factor_constraints(net, x, clm, grm, A, ws.piv, ws.sol, G, n, ws.istate, ws.fstate):
        return False
    if ws.istate[IS_REDUNDANT] == 0 and 2 + nc + 2 * ng <= nmat and G.shape[1] <= nmat:
        k = ws.istate[IS_CACHE_NEXT]
        ws.istate[IS_CACHE_NEXT] = (k + 1) % FACTOR_CACHE
        key = base + k * (nmat + 1)
        A[key, 0], A[key, 1] = 1.0, n
        for j in range(nc):
            A[key, 2 + j] = clm[j]
        for g in range(ng):
            A[key, 2 + nc + g] = grm[g]
            A[key, 2 + nc + ng + g] = ws.fstate[o + g]
        for r in range(n):
            for c in range(G.shape[1]):
                A[key + 1 + r, c] = G[r, c]
    return True


@jit_inline
def rhs(t, left, x, net, ext, ws, dx, aux, refactor, full=True):
    """Derivatives ``dx`` and element torques ``aux`` (layout: :func:`~wetclutch.sim.workspace.aux_offsets`)
    of state ``x`` for the workspace's modes; False if the constraint system is singular.

    The constraint factors are remade when ``refactor`` is set. With ``full`` False only
    ``aux`` is needed (an output row): the accelerations and the actuator's pressure
    derivative are then skipped.
    """
    nb = net.J.shape[0]
    ns = net.sp_k.shape[0]
    nc = net.cl_a.shape[0]
    ng = net.gr_in.shape[0]
    e0 = nb + ns
    clm = ws.clm
    grm = ws.grm
    z = ws.z
    p_drag, p_src, p_damp = _applied_torques(t, left, x, net, ext, dx, aux, z)
    if net.act.shape[0] > 0:
        # the actuator's states' rates into dx, its force on the valve stem into z and its power into p_src
        # (here, not in a helper of its own: each level of inlining copies the actuator's whole IR once more)
        u = signals.value(int(net.act[act_.U_SIG]), t, left, net.sig, net.tab, ext)
        f_stem, _, ws.fstate[FS_AMP_G] = act_.evaluate(x, net.act, u, ext, dx, full, ws.fstate[FS_AMP],
                                                       ws.fstate[FS_PISTON], ws.fstate[FS_PLAY_CUR],
                                                       ws.fstate[FS_PLAY_DIR], ws.fstate[FS_PLAY_TAU],
                                                       ws.fstate[FS_PLAY_G])
        stem = int(net.act[act_.STEM_BODY])
        z[stem] += f_stem
        p_src += f_stem * x[stem]
    nlock = _clutch_torques(t, left, x, net, ext, clm, dx, aux, z)
    if net.th.shape[0] > 0:
        # the heated clutch's slip power (its dissipation rate, 0 while locked) heats the pack
        th_.rates(x, net.th, dx[e0 + int(net.th[th_.CLUTCH])], dx)
    n = nb + nlock + ng
    for g in range(ng):
        if abs(grm[g]) == STUCK:
            n += 1
    moving = _ratio_rates(t, left, net, ext, dx, ws.fstate)
    if refactor or (moving and _ratios_moved(x, net, ws.fstate)):
        if not factors(net, x, clm, grm, ws, n):
            return False
    nv = 0
    if moving:
        # the velocity terms r' w_in of the gear rows (in the free scratch ``sol``)
        nv = ng
        for g in range(ng):
            k = net.gr_state[g]
            ws.sol[g] = dx[k] * x[net.gr_in[g]] if k >= 0 and abs(grm[g]) != STUCK else 0.0
    _solve_constraints(ws.G, z, dx, nb, n, full, ws.sol, nv)
    p_gear = _constraint_torques(x, net, clm, grm, z, aux)
    dx[e0 + nc + E_DRAG] = p_drag
    dx[e0 + nc + E_DAMPER] = p_damp
    dx[e0 + nc + E_GEAR] = p_gear
    dx[e0 + nc + E_SOURCE] = p_src
    return True


@jit
def rhs_call(t, x, net, ext, ws, dx, aux, refactor, full):
    """:func:`rhs` at the right limit of the signals, as a real call: for the paths that run at most once per
    output row, restart or located event, which would otherwise each compile a copy of it.

    Pass the flags as plain booleans (``bool(False)``): a literal one compiles a copy of its own.
    """
    return rhs(t, False, x, net, ext, ws, dx, aux, refactor, full)


@jit_inline
def hold_margins(aux, x, net, grm, k):
    """A stuck gear holds while the input torque, seen at the output (``q``), has the
    sign ``s`` of the held torque and ``eta |lam| <= |q| <= |lam| / eta``."""
    nc = net.cl_a.shape[0]
    ng = net.gr_in.shape[0]
    ns = net.sp_k.shape[0]
    _, _, o_gear_out, _, o_gear_in = aux_offsets(nc, ng, ns)
    lam = aux[o_gear_out + k]
    q = -aux[o_gear_in + k] / ratio(x, net, k)
    sg = 1.0 if grm[k] > 0 else -1.0
    return sg * (q - net.gr_eta[k] * lam), sg * (lam / net.gr_eta[k] - q)


@jit_inline
def static_limit(net, j, cap, grip):
    """The torque a locked clutch ``j`` of capacity ``cap`` holds: its static friction, times ``1 + grip``."""
    return net.cl_peak[j] * cap * poly(net.cl_poly, j, 0.0) * (1.0 + grip)


@jit_inline
def events(x, aux, net, clm, grm, g, fstate):
    """Event functions into ``g``: each is >= 0 while the current modes are valid. The valve amplifier's is
    the one the right-hand side stored in ``fstate`` when it last ran, which must have been at ``x``."""
    nc = net.cl_a.shape[0]
    ng = net.gr_in.shape[0]
    o_grip = fs_grip(nc, ng)
    for j in range(nc):
        cap = aux[nc + j]
        m = clm[j]
        if net.cl_oneway[j] != 0:
            # one-way: locked, it holds any torque that drives b forward and its static friction
            # backward; it slides only with b overrunning a
            if m == LOCKED:
                g[2 * j] = static_limit(net, j, max(cap, 0.0), fstate[o_grip + j]) + aux[j]
            else:
                g[2 * j] = -slip(x, net, j)
            g[2 * j + 1] = 1.0
        elif m == LOCKED:
            g[2 * j] = static_limit(net, j, cap, fstate[o_grip + j]) - abs(aux[j])
            g[2 * j + 1] = cap
        elif m == FREE:
            g[2 * j] = -cap
            g[2 * j + 1] = 1.0
        else:
            g[2 * j] = m * slip(x, net, j)
            g[2 * j + 1] = cap
    for k in range(ng):
        lam = aux[2 * nc + k]
        if abs(grm[k]) == STUCK:
            g[2 * nc + 2 * k], g[2 * nc + 2 * k + 1] = hold_margins(aux, x, net, grm, k)
        elif net.gr_eta[k] == 1.0 or abs(grm[k]) == IDLE:
            # an ideal gear's power flow ends no mode (both directions are the same constraint: a gear whose
            # torque and speed are zero at once, at a standstill, would switch by rounding, over and over);
            # an idle gear's torque is zero, and the locks beside it end its mode
            g[2 * nc + 2 * k] = 1.0
            g[2 * nc + 2 * k + 1] = 1.0
        else:
            g[2 * nc + 2 * k] = grm[k] * lam * x[net.gr_out[k]]
            g[2 * nc + 2 * k + 1] = 1.0
    e = 2 * nc + 2 * ng
    n_amp = 1 if net.act.shape[0] > 0 else 0
    if g.shape[0] - n_amp > e:
        # moving ratios: each stays within its limits; held at one, its command keeps pushing beyond
        o = fs_ratio(nc) + ng
        for k in range(ng):
            i = net.gr_state[k]
            if i < 0:
                g[e + k] = 1.0
            elif fstate[o + k] != 0.0:
                g[e + k] = fstate[o + k] * fstate[o + ng + k]
            else:
                g[e + k] = min(x[i] - net.gr_lim[k, LIM_MIN], net.gr_lim[k, LIM_MAX] - x[i])
        e += ng
    if n_amp:
        # the valve amplifier's and the piston's modes: their function as the right-hand side last evaluated it
        # (at ``x``)
        g[e] = fstate[FS_AMP_G]
