"""The clutch actuator: valve electronics and coil, magnet, hydraulics, piston (spec 3-5).

The actuator adds five states to the engine's state vector: the coil current
``I`` (A), the clutch pressure ``p`` (Pa, gauge), the oil volumes that have
flowed in through the valve and out (drain, leakage, relief), m^3, which close
the oil volume balance, and the magnetising current ``I_m`` (A) that the
magnet's iron follows through its hysteresis. The valve stem is a body of
the network (mass ``m_stem``) on a spring-damper to the ground, with a Coulomb
brake for the stem friction; so stem stick/slip (a small hysteresis in DC mode,
dithered out by PWM) is solved exactly by the engine like any clutch. The actuator pushes
on the stem with the magnet force minus the pressure feedback, and sets the
normal force of the clutch.

Chain of effects::

    u (V or duty) -> amplifier / PWM -> coil (L, R) -> I -> play (hysteresis) -> I_m
    F_mag(I_m) = k_F1 I_m + k_F2 I_m^2 up to I_sat, then rising linearly (saturated iron)
    stem: m x'' = F_mag + F_preload - A_fb p - F_flow - c x - d x' - friction
    F_flow = k_flow (opening x pressure drop across the port): the steady flow force
    x > overlap: supply -> clutch through the stem port, in series with the clutch installation's
                 feed restriction (turbulent) and feed line (laminar);
    x < -overlap: clutch -> tank;  relief above p_relief
    seal leakage: a laminar gap in series with a turbulent orifice (the rings' joint gaps)
    dp/dt = (Q_in - Q_drain - Q_leak - Q_relief) / C(p)
    C(p) = V(p)/K_oil (+ A_p^2 / k_reset while the piston strokes)
    F_n = A_p (p - p_contact) after the plates touch

Electronics (spec 5): in DC mode a current controller with setpoint ``g_current * u``
drives the coil; its output saturates at the supply voltage, so a large step
rises with ``L/R``; when the controller asks for a negative voltage the output
transistor blocks and the current decays through the freewheel circuit with
``L/(R + R_freewheel)``. In PWM mode the coil sees the supply voltage during the
high part of each period and freewheels through a diode during the low part, so
the mean current is about ``duty * V_supply / R_coil``.

Magnet (spec 5: "friction of the magnet causes hysteresis", and "no simple model
known" for the force): the force follows the magnetisation of the iron, which lags
the coil current by a play (backlash, Prandtl) of half-width ``I_hyst``: ``I_m``
stays put while ``|I - I_m| < I_hyst`` and is dragged along at that distance
beyond. The play is smoothed as a Duhem model, ``dI_m/dt = dI/dt * min(z, 1)^8`` with
``z = (I - I_m) sign(dI/dt) / I_hyst`` (0 when negative), so it needs no events; the
steep power keeps ``I_m`` nearly still inside the play, and the lag settles at
``I_hyst`` while the current keeps moving one way. A PWM ripple smaller than the
play wears the lag down only slowly (the iron sees minor loops), so unlike the
stem's Coulomb friction, which the ripple dithers out, this hysteresis stays
visible in PWM mode. Above ``I_sat`` the iron saturates: the force keeps the slope it
had there (``F`` grows like the ampere-turns, not their square), which the valve test
(up to 1.4 A) sees and the whole-clutch curves (at most 0.8 A) hardly do.

This module holds the flat parameter layout and the compiled kernel; the engine
calls :func:`evaluate` from its right-hand side.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .oil import _compliance_j as oil_compliance

# layout of the flat actuator record (indices into ``act``)
(
    STATE,  # index of I in the state vector (p, V_in, V_out follow)
    STEM_BODY,
    STEM_SPRING,  # state index of the stem spring deflection = stem position
    CLUTCH,
    U_SIG,
    MODE,  # 0 DC, 1 PWM
    PWM_EXT,  # ext slot holding the PWM level (0/1)
    PWM_FREQ,
    V_SUP,
    R_COIL,
    L_COIL,
    R_FW,
    K_AMP,
    G_CURRENT,
    K_F1,
    K_F2,
    F_PRE,
    A_FB,
    OVERLAP,
    X_PORT,
    CDW,
    RHO,
    P_SUP,
    R_LINE,
    V0,
    A_P,
    K_RESET,
    P_PRE,
    P_CONTACT,
    X_CONTACT,
    K_OIL,  # pure-oil bulk modulus at the oil temperature
    AIR,  # entrained air volume fraction at atmospheric pressure
    K_FLOW,  # steady flow force per (opening x pressure drop), N/(m Pa)
    A_FEED,  # turbulent feed restriction of the clutch installation, m^3/(s Pa^0.5); 0: none
    K_RESTRICT,  # turbulent outflow Q = K sqrt(p): seal rings, or the valve test's restriction
    G_LEAK,
    P_RELIEF,
    G_RELIEF,
    F_KNEE,
    I_HYST,  # half-width of the magnet's hysteresis (play on the coil current), A; 0: none
    I_SAT,  # coil current above which the magnet force rises only linearly, A
    K_SEAL,  # turbulent orifice in series with the laminar seal gap G_LEAK, m^3/(s Pa^0.5); 0: none
    N_ACT,
) = range(43)

DC, PWM = 0, 1


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def piston_position(p, act):
    """Piston travel (m) at pressure ``p``: at its stop, stroking against the reset spring, at contact."""
    if p <= act[P_PRE]:
        return 0.0
    if p >= act[P_CONTACT]:
        return act[X_CONTACT]
    return act[A_P] / act[K_RESET] * (p - act[P_PRE])


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def normal_force(p, act):
    """Plate normal force (N), zero until the plates touch."""
    return act[A_P] * (p - act[P_CONTACT]) if p > act[P_CONTACT] else 0.0


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def magnet_force(i_m, act):
    """Magnet force (N) at magnetising current ``i_m``: quadratic, then linear beyond ``I_SAT`` (C1)."""
    i_s = act[I_SAT]
    if i_m <= i_s:
        return act[K_F1] * i_m + act[K_F2] * i_m * i_m
    return act[K_F1] * i_s + act[K_F2] * i_s * i_s + (act[K_F1] + 2.0 * act[K_F2] * i_s) * (i_m - i_s)


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def play_rate(cur, cur_dot, i_m, r):
    """dI_m/dt of the smoothed play (Duhem form, see the module docstring) of half-width ``r`` > 0."""
    z = (cur - i_m if cur_dot > 0.0 else i_m - cur) * (1.0 / r)
    if z <= 0.0:
        return 0.0
    # I_m never outruns I: capping keeps the rate bounded even where a trial stage of the
    # explicit integrator overshoots the play (an uncapped z^8 runs away there)
    z = min(z, 1.0)
    z2 = z * z
    z4 = z2 * z2
    return cur_dot * z4 * z4


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def seal_leak(p, act):
    """Seal leakage (m^3/s): the laminar gap ``G_LEAK`` in series with the turbulent orifice ``K_SEAL``.

    ``p = Q / G + (Q / K)^2``; solved as ``Q = 2 G p / (1 + sqrt(1 + 4 G^2 p / K^2))``, which
    stays accurate when either term dominates. Cold oil: the gap (1/viscosity) limits the
    flow; warm oil: the orifice (no viscosity) does.
    """
    g = act[G_LEAK]
    k = act[K_SEAL]
    if k <= 0.0 or p <= 0.0:
        return g * p
    return 2.0 * g * p / (1.0 + np.sqrt(1.0 + 4.0 * g * g * p / (k * k)))


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def evaluate(x, act, u, ext, dx, full=True):
    """Write dI/dt and dp/dt into ``dx``; return (force on the stem, clutch normal force).

    ``u`` is the input (V in DC mode; ignored in PWM mode, where ``ext`` holds the level).
    With ``full`` False only the forces are wanted: the pressure derivative is skipped.
    """
    i0 = int(act[STATE])
    cur = x[i0]
    p = x[i0 + 1]
    # ---- electronics and coil
    if act[MODE] == PWM:
        # low part of a period: the current freewheels through the diode (about 0 V)
        v = act[V_SUP] if ext[int(act[PWM_EXT])] > 0.5 else 0.0
    else:
        i_ref = act[G_CURRENT] * u
        v = act[R_COIL] * i_ref + act[K_AMP] * (i_ref - cur)
        if v > act[V_SUP]:
            v = act[V_SUP]
        elif v < 0.0:
            v = -act[R_FW] * cur  # output transistor blocks: freewheel
    # constant reciprocals: the divide then runs off the dependency chain of the state
    cur_dot = (v - act[R_COIL] * cur) * (1.0 / act[L_COIL])
    dx[i0] = cur_dot
    # ---- magnetisation: a play on the current (hysteresis); none: I_m tracks I exactly
    if act[I_HYST] > 0.0:
        i_m = x[i0 + 4]
        dx[i0 + 4] = play_rate(cur, cur_dot, i_m, act[I_HYST])
    else:
        i_m = cur
        dx[i0 + 4] = cur_dot
    # ---- valve flows (written for few square roots and divisions: this runs in every stage)
    xs = x[int(act[STEM_SPRING])]
    o_sup = min(max(xs - act[OVERLAP], 0.0), act[X_PORT])
    o_drn = min(max(-xs - act[OVERLAP], 0.0), act[X_PORT])
    pp = max(p, 0.0)
    q_in = 0.0
    if o_sup > 0.0:
        # stem port and feed restriction (turbulent, Q = a sqrt(dp); in series they combine as
        # 1/a^2 = 1/a_port^2 + 1/a_feed^2) in series with the laminar supply line (R_line Q)
        cw = act[CDW] * o_sup
        a2 = cw * cw * 2.0 / act[RHO]
        af2 = act[A_FEED] * act[A_FEED]
        if af2 > 0.0:
            a2 = a2 * af2 / (a2 + af2)
        dp = act[P_SUP] - p
        a2r = a2 * act[R_LINE]
        q_in = 0.5 * (np.sqrt(a2r * a2r + 4.0 * a2 * abs(dp)) - a2r)
        if dp < 0.0:
            q_in = -q_in
    if full:
        q_out = seal_leak(p, act)  # drain, leakage and relief
        if o_drn > 0.0:
            q_out += act[CDW] * o_drn * np.sqrt(2.0 * pp / act[RHO])
        if act[K_RESTRICT] > 0.0:
            q_out += act[K_RESTRICT] * np.sqrt(pp)
        if p > act[P_RELIEF]:
            q_out += act[G_RELIEF] * (p - act[P_RELIEF])
        # ---- oil volume behind the valve and the piston's compliance
        cap = (act[V0] + act[A_P] * piston_position(p, act)) * oil_compliance(pp, act[K_OIL], act[AIR])
        if act[P_PRE] < p < act[P_CONTACT]:
            cap += act[A_P] * act[A_P] / act[K_RESET]
        dx[i0 + 1] = (q_in - q_out) / cap
        dx[i0 + 2] = q_in
        dx[i0 + 3] = q_out
    f_mag = magnet_force(i_m, act)
    # steady flow (Bernoulli) force: the jet through an open port pulls the stem towards closing
    dp_in = act[P_SUP] - p - act[R_LINE] * q_in
    f_flow = act[K_FLOW] * (o_sup * max(dp_in, 0.0) - o_drn * pp)
    f_stem = f_mag + act[F_PRE] - act[A_FB] * p - f_flow
    return f_stem, normal_force(p, act)


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def friction_factor(f_n, act):
    """Drop of the friction at low normal force (plates barely pressed, spec 6): ``F / (F + F_knee)``.

    A rational knee rather than ``1 - exp(-F/F_knee)``: the same shape to within the
    study's scatter, without a transcendental function in every evaluation."""
    return f_n / (f_n + act[F_KNEE]) if act[F_KNEE] > 0.0 else 1.0


N_STATES = 5  # I, p, V_in, V_out, I_m
