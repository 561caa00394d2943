"""The clutch actuator: valve electronics and coil, magnet, hydraulics, piston.

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

The piston's compliance while it strokes is some thousand times the oil's, over a pressure band
of a tenth of a bar or two: the piston at its stop, stroking and at the plates are three modes,
switched at located events (:func:`piston_event`) where the pressure reaches the band's edges. A
step that crossed the band unseen would fill the clutch without its stroke.

Electronics: in DC mode a current controller with setpoint ``g_current * u``
drives the coil through a high-side output transistor, with a freewheel circuit
(diode and ``R_freewheel``) from ground to the coil. The transistor's current
``I_t`` is what the controller sets; the freewheel circuit carries the rest of
the coil current, so the coil voltage is ``v = -R_freewheel (I - I_t)`` below 0 V
and the transistor's drop above: ``v`` is the controller's voltage clipped to
``-R_freewheel I .. V_supply``. A large step up rises with ``L/R`` at the supply
voltage; where the controller asks for less than ``-R_freewheel I`` the
transistor blocks and the current decays with ``L/(R + R_freewheel)``. These are
the amplifier's three modes (regulating, saturated, freewheeling). The voltage is
continuous across their edges (a stage whose voltage jumped from 0 V to
``-R_freewheel I`` would hold a falling input's current on the edge by switching
back and forth at once, with no time between: Zeno behaviour), but its slope is
not, so the engine switches them at located events (:func:`amplifier`), as it
does a clutch's, and never inside a step. In PWM mode the coil sees the supply voltage during the
high part of each period and freewheels through a diode during the low part, so
the mean current is about ``duty * V_supply / R_coil``.

Magnet (the study: "friction of the magnet causes hysteresis", and "no simple model
known" for the force): the force follows the magnetisation of the iron, which lags
the coil current by a play (backlash, Prandtl) of half-width ``I_hyst``: ``I_m``
stays put while ``|I - I_m| < I_hyst`` and is dragged along at that distance
beyond. The play is smoothed as a Duhem model, ``dI_m/dt = dI/dt * min(z, 1)^n`` with
``z = (I - I_m) sign(dI/dt) / I_hyst`` (0 when negative) and ``n`` = ``valve.play_exponent`` (8), so it
switches no modes (a sharp play would hold and drag by turns); the steep power keeps ``I_m`` nearly still inside
the play (a larger ``n``: a sharper play, the ideal one as ``n`` grows), and the lag settles at
``I_hyst`` while the current keeps moving one way. The model is rate-independent: while the current moves one way,
the lag ``zeta`` (``z`` with the direction of the current's travel) obeys ``dzeta/dsigma = 1 - g(zeta)`` in the
path ``sigma = |I - I_0| / I_hyst`` (``g`` = 0 for ``zeta <= 0``, ``zeta^n`` up to 1, 1 beyond), so ``I_m`` is a
function of ``I`` alone. Its rate, ``n |dI/dt| / I_hyst`` where the lag nears the play's edge, is the stiffest of
the plant (1.6e4 1/s on the torque dither's swings), so the engine does not integrate ``I_m``: within each step,
where the current is monotone (a located event where it turns, :func:`play_event`), ``I_m`` is the exact map of the
current (:func:`magnetisation`, the flow through tables, :func:`play_flow`), its state slot holds its value at the
step's start and is moved on where a step ends. A PWM ripple smaller than the
play wears the lag down only slowly (the iron sees minor loops), so unlike the
stem's Coulomb friction, which the ripple dithers out, this hysteresis stays
visible in PWM mode. Above ``I_sat`` the iron saturates: the force keeps the slope it
had there (``F`` grows like the ampere-turns, not their square), which the valve test
(up to 1.4 A) sees and the whole-clutch curves (at most 0.8 A) hardly do.

This module owns the flat actuator record: it names the offsets, and :func:`pack`
(physical parameters at an oil temperature) and :func:`wire` (where the actuator sits in
a network's state vector) are the only code that fills one. The engine calls the
compiled kernel :func:`evaluate` from its right-hand side.
"""

from __future__ import annotations

import functools

import numpy as np
from numba import njit

from ..params import Params
from . import friction, oil

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
    FB_DAMP,  # damping orifice into the stem's feedback chamber, m^3/(s Pa^0.5); 0: the chamber sees p
    FB_GAP,  # laminar clearance of the stem's guide out of the feedback chamber, m^3/(s Pa)
    FB_TURB,  # damping orifice and the guide's vent bore in series (turbulent part of the path), m^3/(s Pa^0.5)
    PLAY_N,  # exponent of the smoothed play (a whole number >= 1)
    PLAY_INV_DTAU,  # intervals of the play's flow table per unit of its path (:func:`play_flow`)
    N_ACT,
) = range(48)

#: intervals of each of the play's two tables (:func:`play_flow`, :func:`play_time`): a quintic each, to
#: some 2e-12 of the play's width at n = 8 and 2e-11 at n = 1, 2 or 64
PLAY_INTERVALS = 384
#: the tables follow the named slots: the flow's, then the flow time's
PLAY_FLOW = N_ACT
PLAY_TIME = N_ACT + 6 * PLAY_INTERVALS
#: the record's length
RECORD_SIZE = N_ACT + 12 * PLAY_INTERVALS
#: the flow table ends where the lag is within this share of I_hyst of its limit, a rounding of 1 (an exponential
#: beyond it, a library call in every stage, made a clutch step twice as slow)
PLAY_TAIL = 1e-16
#: the play's direction holds while the coil current's rate does not turn by more than this (in volts across the
#: coil, the event function's unit): far above the rate's rounding at rest (some 1e-14 V), far below a turn that
#: moves the magnetisation (a 1e-9 V turn over a 1 ms step moves the current by 1e-11 A on the 0.1 H coil)
PLAY_TURN = 1e-9

DC, PWM = 0, 1
#: modes of the DC amplifier's output stage
REGULATE, SATURATED, FREEWHEEL = 0, 1, -1
N_STATES = 5  # I, p, V_in, V_out, I_m: the actuator's block of the state vector, in this order
CURRENT, PRESSURE, VOLUME_IN, VOLUME_OUT, MAGNETISATION = range(N_STATES)

#: hydraulic loads of the valve: the clutch, or the study's valve test (a restriction instead of the clutch)
CONFIGS = ("clutch", "valve-only")
#: the study's valve test restriction passes 32 l/min; here at the supply pressure
VALVE_TEST_FLOW = 32.0 / 60000.0


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def piston_position(p, act):
    """Piston travel (m) at pressure ``p``: at its stop, stroking against the reset spring, at contact."""
    if p <= act[P_PRE]:
        return 0.0
    if p >= act[P_CONTACT]:
        return act[X_CONTACT]
    return act[A_P] / act[K_RESET] * (p - act[P_PRE])


#: the clutch piston's modes: at its stop (below the reset spring's prestress), stroking (the spring's compliance
#: adds to the oil's), at the plates (above the contact pressure)
AT_STOP, STROKING, AT_PLATES = 0, 1, 2
#: the actuator's event function is in volts (the amplifier's range); the piston's, in pascals, counts 1 bar as 10 V
PISTON_EVENT_SCALE = 1e-4


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def piston_mode(p, act):
    """The piston's mode at pressure ``p`` (:data:`AT_STOP`, :data:`STROKING`, :data:`AT_PLATES`)."""
    if p <= act[P_PRE]:
        return AT_STOP
    if p >= act[P_CONTACT]:
        return AT_PLATES
    return STROKING


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def piston_event(p, act, mode):
    """The piston's event function (Pa): >= 0 while ``mode`` holds. The stroke's compliance is a thousand times the
    oil's: a step that crossed the stroke's narrow pressure band unseen would fill the clutch without its stroke."""
    if mode == AT_STOP:
        return act[P_PRE] - p
    if mode == AT_PLATES:
        return p - act[P_CONTACT]
    return min(p - act[P_PRE], act[P_CONTACT] - p)


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def _with_piston(g_amp, p, act, piston):
    """The amplifier's event function ``g_amp`` and the piston's at ``p``, whichever is nearer its switch."""
    return min(g_amp, PISTON_EVENT_SCALE * piston_event(p, act, piston))


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def event(cur, p, u, ext, act, amp_mode, piston, direction):
    """The actuator's event function: the amplifier's (:func:`amplifier`), the play's (:func:`play_event`, the
    current moving in ``direction``) and the piston's (:func:`piston_event`), whichever is nearer its switch."""
    v, g_amp = amplifier(cur, u, ext, act, amp_mode)
    return _with_piston(min(g_amp, play_event(cur, v, act, direction)), p, act, piston)


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def normal_force(p, act):
    """Plate normal force (N), zero until the plates touch (:func:`wetclutch.physics.friction.normal_force`)."""
    return friction.normal_force(p, act[P_CONTACT], act[A_P])


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def magnet_force(i_m, act):
    """Magnet force (N) at magnetising current ``i_m``: quadratic, then linear beyond ``I_SAT`` (C1)."""
    i_s = act[I_SAT]
    if i_m <= i_s:
        return act[K_F1] * i_m + act[K_F2] * i_m * i_m
    return act[K_F1] * i_s + act[K_F2] * i_s * i_s + (act[K_F1] + 2.0 * act[K_F2] * i_s) * (i_m - i_s)


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def _quintic(act, o, u):
    """The table at ``act[o]`` (six power-series coefficients per interval) at ``u`` intervals from its start."""
    k = min(int(u), PLAY_INTERVALS - 1)
    t = u - k
    c = o + 6 * k
    return act[c] + t * (act[c + 1] + t * (act[c + 2] + t * (act[c + 3] + t * (act[c + 4] + t * act[c + 5]))))


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def play_flow(tau, act):
    """The play's lag ``zeta`` after the path ``tau`` (in ``I_hyst``) from a lag of 0: ``dzeta/dtau = 1 - g(zeta)``.

    Negative ``tau`` is the flow's linear part, where the iron stays put; beyond the table the lag is 1 to rounding
    (:data:`PLAY_TAIL`)."""
    if tau <= 0.0:
        return tau
    u = tau * act[PLAY_INV_DTAU]
    if u < PLAY_INTERVALS:
        return _quintic(act, PLAY_FLOW, u)
    return 1.0


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def play_time(zeta, act):
    """The path (in ``I_hyst``) along which the play's flow takes a lag of 0 to ``zeta`` (:func:`play_flow`'s
    inverse; ``inf`` at and beyond the play's edge, where the lag no longer moves).

    ``integral_0^zeta dv / (1 - v^n) = -log(1 - zeta) / n + R(zeta)``: the logarithm carries the divergence at the
    edge, and ``R`` is smooth on [0, 1] (a table)."""
    if zeta <= 0.0:
        return zeta
    if zeta >= 1.0:
        return np.inf
    return -np.log1p(-zeta) / act[PLAY_N] + _quintic(act, PLAY_TIME, zeta * PLAY_INTERVALS)


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def play_step(cur, i_m0, act, cur0, direction, tau0, g0):
    """The magnetising current at coil current ``cur`` within a step of monotone current that began at ``cur0``,
    ``i_m0`` in ``direction`` (+1 rising, -1 falling), and the flow's path and lag there (:func:`play_flow`).

    ``tau0`` is the flow's path at the step's start and ``g0`` its lag there as the flow gives it: the increments
    of the lag are the flow's, so a run of steps adds up to the flow over their whole path (``I_m`` moves with
    ``I`` less the lag's growth). A current a little against ``direction`` (a stage's overshoot) runs the flow
    backwards along the same curve."""
    r = act[I_HYST]
    sigma = direction * (cur - cur0) * (1.0 / r)
    tau = tau0 + sigma
    if tau <= 0.0:
        # inside the play: the iron stays put
        return i_m0, tau, tau
    g = play_flow(tau, act)
    return i_m0 + direction * r * (sigma - (g - g0)), tau, g


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def magnetisation(cur, i_m0, act, cur0, direction, tau0, g0):
    """:func:`play_step`'s magnetising current (A)."""
    return play_step(cur, i_m0, act, cur0, direction, tau0, g0)[0]


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def play_start(x, act, u, ext, mode, direction):
    """The play's step state at a restart at state ``x`` (input ``u``, amplifier mode ``mode``): the current's
    direction (its rate's sign; ``direction`` kept where the rate is 0), the current, and the flow's path and lag
    of the lag ``zeta = direction (I - I_m) / I_hyst`` (:func:`play_step`). No play: the direction and current."""
    i0 = int(act[STATE])
    cur = x[i0 + CURRENT]
    rate = amplifier(cur, u, ext, act, mode)[0] - act[R_COIL] * cur
    if rate > 0.0:
        direction = 1.0
    elif rate < 0.0:
        direction = -1.0
    if act[I_HYST] <= 0.0:
        return direction, cur, 0.0, 0.0
    tau = play_time(direction * (cur - x[i0 + MAGNETISATION]) * (1.0 / act[I_HYST]), act)
    return direction, cur, tau, play_flow(tau, act)


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def play_event(cur, v, act, direction):
    """The play's event function (V): >= 0 while the coil current moves in ``direction`` (within
    :data:`PLAY_TURN`) at coil voltage ``v``. A step must not contain a turn of the current: the magnetisation is
    a function of the current only along a monotone path (always 1 without a play)."""
    if act[I_HYST] <= 0.0:
        return 1.0
    return direction * (v - act[R_COIL] * cur) + PLAY_TURN


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def gap_and_orifice(p, g, k):
    """Flow (m^3/s) through a laminar gap ``g`` in series with a turbulent orifice ``k`` (0: none) under ``p``.

    ``p = Q / g + (Q / k)^2``; solved as ``Q = 2 g p / (1 + sqrt(1 + 4 g^2 p / k^2))``, which
    stays accurate when either term dominates. Cold oil: the gap (1/viscosity) limits the
    flow; warm oil: the orifice (no viscosity) does.
    """
    if k <= 0.0 or p <= 0.0:
        return g * p
    return 2.0 * g * p / (1.0 + np.sqrt(1.0 + 4.0 * g * g * p / (k * k)))


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def seal_leak(p, act):
    """Seal leakage (m^3/s): the laminar gap ``G_LEAK`` in series with the turbulent orifice ``K_SEAL``."""
    return gap_and_orifice(p, act[G_LEAK], act[K_SEAL])


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def feedback_flow(p, act):
    """Flow (m^3/s) through the stem's feedback chamber: damping orifice, guide clearance, vent bore."""
    if act[FB_DAMP] <= 0.0:
        return 0.0
    return gap_and_orifice(p, act[FB_GAP], act[FB_TURB])


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def feedback_pressure(p, q_fb, act):
    """Pressure (Pa) in the stem's feedback chamber: ``p`` less the damping orifice's drop at flow ``q_fb``.

    The chamber at the stem's end is fed from the valve outlet through a damping orifice and
    leaks through the clearance of the stem's guide (laminar, 1/viscosity) and the guide's vent
    bore to the tank. Warm oil leaks more, the orifice drops more, the stem feels less than the
    outlet pressure and the valve settles higher: the whole clutch's static pressure rises with
    oil temperature. The drop grows with the square of the flow, so small pressures hardly feel it.
    """
    if act[FB_DAMP] <= 0.0:
        return p
    r = q_fb * (1.0 / act[FB_DAMP])
    return p - r * r


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def _regulator_voltage(cur, u, act):
    """The DC current controller's output voltage before its stage limits it (V)."""
    i_ref = act[G_CURRENT] * u
    return act[R_COIL] * i_ref + act[K_AMP] * (i_ref - cur)


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def amplifier_mode(x, act, u):
    """The DC amplifier's mode at state ``x`` and input ``u``: saturated above the supply voltage,
    freewheeling where the controller asks for less than the freewheel circuit's voltage, else regulating (PWM:
    regulating, unused)."""
    if act[MODE] == PWM:
        return REGULATE
    cur = x[int(act[STATE]) + CURRENT]
    v = _regulator_voltage(cur, u, act)
    if v > act[V_SUP]:
        return SATURATED
    if v < -act[R_FW] * cur:
        return FREEWHEEL
    return REGULATE


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def amplifier(cur, u, ext, act, mode):
    """(the voltage (V) that drives the coil at current ``cur``, the amplifier's event function).

    The voltage is the DC amplifier's in its ``mode``, or in PWM mode the supply's or, in the period's low part
    (``ext`` holds the level), the freewheel diode's (about 0 V). The event function is >= 0 while ``mode`` holds (the
    controller's voltage within the stage's range, above it, or below zero); PWM: 1 (its edges are time events)."""
    if act[MODE] == PWM:
        return (act[V_SUP] if ext[int(act[PWM_EXT])] > 0.5 else 0.0), 1.0
    v_reg = _regulator_voltage(cur, u, act)
    v_fw = -act[R_FW] * cur  # the freewheel circuit's voltage with the output transistor blocked
    if mode == SATURATED:
        return act[V_SUP], v_reg - act[V_SUP]
    if mode == FREEWHEEL:
        return v_fw, v_fw - v_reg
    return v_reg, min(v_reg - v_fw, act[V_SUP] - v_reg)


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def evaluate(x, act, u, ext, dx, full=True, mode=REGULATE, piston=AT_STOP, cur0=0.0, direction=1.0, tau0=0.0,
             g0=0.0):
    """Write the actuator's state rates into ``dx``; return (force on the stem, clutch normal force,
    the actuator's event function, :func:`event`).

    ``u`` is the input (V in DC mode; ignored in PWM mode, where ``ext`` holds the level) and
    ``mode`` the DC amplifier's (:func:`amplifier_mode`, decided at the last restart: within a step
    the regulating mode's voltage runs on beyond its range until the event is located), ``piston`` the
    piston's (:func:`piston_mode`, likewise: the stroke's compliance holds until its band's edge is located).
    ``cur0``, ``direction``, ``tau0``, ``g0`` are the play's state at the step's start (:func:`play_step`; the
    magnetisation's slot of ``x`` holds its value there, and its rate is 0).
    With ``full`` False only the forces are wanted: the pressure derivative is skipped.
    """
    i0 = int(act[STATE])
    cur = x[i0 + CURRENT]
    p = x[i0 + PRESSURE]
    # ---- electronics and coil
    v, g_amp = amplifier(cur, u, ext, act, mode)
    # constant reciprocals: the divide then runs off the dependency chain of the state
    cur_dot = (v - act[R_COIL] * cur) * (1.0 / act[L_COIL])
    dx[i0 + CURRENT] = cur_dot
    # ---- magnetisation: a play on the current (hysteresis), a map of the current within the step; none: I_m
    # tracks I exactly
    if act[I_HYST] > 0.0:
        i_m = magnetisation(cur, x[i0 + MAGNETISATION], act, cur0, direction, tau0, g0)
        dx[i0 + MAGNETISATION] = 0.0
        g_amp = min(g_amp, play_event(cur, v, act, direction))
    else:
        i_m = cur
        dx[i0 + MAGNETISATION] = cur_dot
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
    q_fb = feedback_flow(pp, act)
    if full:
        q_out = seal_leak(p, act) + q_fb  # drain, leakage (seals, the stem's feedback chamber) and relief
        if o_drn > 0.0:
            q_out += act[CDW] * o_drn * np.sqrt(2.0 * pp / act[RHO])
        if act[K_RESTRICT] > 0.0:
            q_out += act[K_RESTRICT] * np.sqrt(pp)
        if p > act[P_RELIEF]:
            q_out += act[G_RELIEF] * (p - act[P_RELIEF])
        # ---- oil volume behind the valve and the piston's compliance
        cap = (act[V0] + act[A_P] * piston_position(p, act)) * oil.compliance_nb(pp, act[K_OIL], act[AIR])
        if piston == STROKING:
            cap += act[A_P] * act[A_P] / act[K_RESET]
        dx[i0 + PRESSURE] = (q_in - q_out) / cap
        dx[i0 + VOLUME_IN] = q_in
        dx[i0 + VOLUME_OUT] = q_out
    f_mag = magnet_force(i_m, act)
    # steady flow (Bernoulli) force: the jet through an open port pulls the stem towards closing
    dp_in = act[P_SUP] - p - act[R_LINE] * q_in
    f_flow = act[K_FLOW] * (o_sup * max(dp_in, 0.0) - o_drn * pp)
    f_stem = f_mag + act[F_PRE] - act[A_FB] * feedback_pressure(p, q_fb, act) - f_flow
    return f_stem, normal_force(p, act), _with_piston(g_amp, p, act, piston)


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def friction_factor(f_n, act):
    """The friction knee at normal force ``f_n`` (:func:`wetclutch.physics.friction.knee`)."""
    return friction.knee(f_n, act[F_KNEE])


@njit(cache=True, error_model="numpy")
def piston_positions(p, act):
    """:func:`piston_position` over an array of pressures (for tables of a run's true states)."""
    out = np.empty(p.shape[0])
    for i in range(p.shape[0]):
        out[i] = piston_position(p[i], act)
    return out


# ---------------------------------------------------------------- packing the record


def _quintics(y: np.ndarray, d: np.ndarray, s: np.ndarray, h: float) -> np.ndarray:
    """The quintic Hermite interpolant of values ``y``, slopes ``d`` and curvatures ``s`` on a grid of spacing ``h``:
    six power-series coefficients per interval in its local coordinate 0..1 (:func:`_quintic`), flat."""
    d0, d1, s0, s1 = h * d[:-1], h * d[1:], h * h * s[:-1], h * h * s[1:]
    a = y[1:] - y[:-1] - d0 - 0.5 * s0
    b = d1 - d0 - s0
    c = s1 - s0
    return np.column_stack([y[:-1], d0, 0.5 * s0, 10.0 * a - 4.0 * b + 0.5 * c, -15.0 * a + 7.0 * b - c,
                            6.0 * a - 3.0 * b + 0.5 * c]).ravel()


def _play_smooth(v: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``r(v) = 1 / (1 - v^n) - 1 / (n (1 - v))``, the smooth part of the play's flow time's integrand, and its
    slope: ``T / (n S)`` with ``S = sum_{k<n} v^k`` and ``T = sum_{j<n-1} (n - 1 - j) v^j``, free of the cancellation
    at ``v = 1``."""
    pw = v[..., None] ** np.arange(n)
    k = np.arange(n)
    s_, ds = pw.sum(-1), (k[1:] * pw[..., :-1]).sum(-1)
    w = (n - 1 - k[:-1]).astype(float)
    t_, dt_ = (w * pw[..., :-1]).sum(-1), (w[1:] * k[1:-1] * pw[..., :-2]).sum(-1)
    return t_ / (n * s_), (dt_ * s_ - t_ * ds) / (n * s_ * s_)


@functools.lru_cache(maxsize=8)
def _play_tables(n: int) -> tuple[float, np.ndarray, np.ndarray]:
    """The play's tables for exponent ``n``: the flow's intervals per unit path, the flow's table (:func:`play_flow`)
    and the flow time's smooth part's (:func:`play_time`), each :data:`PLAY_INTERVALS` quintic Hermite intervals
    (values and two derivatives exact).

    ``R`` is summed by 20-point Gauss-Legendre per interval; the flow's nodes solve ``F(zeta) = tau`` by bisection
    and two Newton steps on the interpolated ``F``; its slopes follow from the flow itself (``1 - zeta^n``).
    """
    m = PLAY_INTERVALS
    h = 1.0 / m
    xg, wg = np.polynomial.legendre.leggauss(20)
    edges = np.arange(m + 1) * h
    r_quad, _ = _play_smooth(edges[:-1, None] + 0.5 * h * (xg + 1.0), n)
    big_r = np.concatenate([[0.0], np.cumsum(0.5 * h * (r_quad @ wg))])
    r_edge, dr_edge = _play_smooth(edges, n)
    time_table = _quintics(big_r, r_edge, dr_edge, h)

    def flow_time(z: np.ndarray) -> np.ndarray:
        k = np.minimum((z * m).astype(int), m - 1)
        t = z * m - k
        c = time_table.reshape(m, 6)[k]
        return -np.log1p(-z) / n + c[:, 0] + t * (c[:, 1] + t * (c[:, 2] + t * (c[:, 3] + t * (c[:, 4] + t * c[:, 5]))))

    tau = np.arange(m + 1) * (flow_time(np.array([1.0 - PLAY_TAIL]))[0] / m)
    lo, hi = np.zeros(m + 1), np.full(m + 1, 1.0 - PLAY_TAIL)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        below = flow_time(mid) < tau
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    g = 0.5 * (lo + hi)
    for _ in range(2):
        g -= (flow_time(g) - tau) * (1.0 - g**n)
    g[0], g[-1] = 0.0, 1.0 - PLAY_TAIL
    slope = 1.0 - g**n
    flow_table = _quintics(g, slope, -n * g ** (n - 1) * slope, tau[1])
    return 1.0 / tau[1], flow_table, time_table


def stroke_span(params: Params) -> float:
    """Pressure rise (Pa) over the piston's stroke, from the prestress to the kiss point: ``k_reset x_contact / A_p``."""
    h = params.hydraulics
    return h.k_reset * h.x_contact / h.A_p


def contact_pressure(params: Params) -> float:
    """Pressure at which the plates touch (Pa), the kiss point: prestress plus the reset spring over the stroke."""
    return params.hydraulics.p_prestress + stroke_span(params)


def pack(params: Params, temp_C: float, config: str = "clutch") -> np.ndarray:
    """The actuator's physical parameters at oil temperature ``temp_C`` as a flat record (wiring still unset).

    ``config`` is the valve's hydraulic load: ``clutch``, or ``valve-only``, the study's valve
    test, where a restriction passing :data:`VALVE_TEST_FLOW` at the supply pressure replaces
    the clutch (no piston, no feed line, no seal rings).
    """
    v, h = params.valve, params.hydraulics
    mu = oil.dynamic_viscosity(temp_C)
    r = np.zeros(RECORD_SIZE)
    r[V_SUP], r[R_COIL], r[L_COIL], r[R_FW] = v.V_supply, v.R_coil, v.L_coil, v.R_freewheel
    r[K_AMP], r[G_CURRENT] = v.amp_gain, v.g_current
    r[K_F1], r[K_F2], r[F_PRE], r[A_FB] = v.k_F1, v.k_F2, v.F_preload, v.A_fb
    r[I_HYST], r[I_SAT], r[PLAY_N] = v.I_hyst, v.I_sat, v.play_exponent
    r[PLAY_INV_DTAU], r[PLAY_FLOW:PLAY_TIME], r[PLAY_TIME:] = _play_tables(int(v.play_exponent))
    r[OVERLAP], r[X_PORT], r[CDW] = v.overlap, v.x_port, v.C_d * v.port_width
    # Merritt's steady flow force, jet angle 69 degrees
    r[K_FLOW] = v.flow_force * 2.0 * v.C_d * v.port_width * np.cos(np.radians(69.0))
    r[RHO] = oil.density(temp_C)
    r[P_SUP] = h.p_supply
    # Hagen-Poiseuille: laminar loss of the clutch's feed line, proportional to viscosity
    line = h.line_length if config == "clutch" else 0.0
    r[R_LINE] = 128.0 * mu * line / (np.pi * h.line_diameter**4)
    r[V0] = h.V0
    r[K_OIL], r[AIR] = oil.bulk_modulus(temp_C, air_fraction=0.0), h.air_fraction
    r[G_LEAK] = h.leak_85C * oil.dynamic_viscosity(85.0) / mu
    r[K_SEAL] = h.seal_orifice
    r[P_RELIEF], r[G_RELIEF] = h.p_relief, h.relief_conductance
    # the stem's feedback chamber (part of the valve, so in both configurations)
    k_orifice = v.C_d * np.sqrt(2.0 / r[RHO])
    r[FB_DAMP] = k_orifice * v.fb_orifice
    r[FB_GAP] = v.fb_gap_85C * oil.dynamic_viscosity(85.0) / mu
    if v.fb_orifice > 0.0 and v.fb_vent > 0.0:  # two orifices in series: 1/K^2 = 1/K_1^2 + 1/K_2^2
        r[FB_TURB] = k_orifice * v.fb_orifice * v.fb_vent / np.sqrt(v.fb_orifice**2 + v.fb_vent**2)
    else:
        r[FB_TURB] = r[FB_DAMP]
    r[F_KNEE] = params.friction.F_knee
    if config == "clutch":
        r[A_P], r[K_RESET], r[X_CONTACT] = h.A_p, h.k_reset, h.x_contact
        r[P_PRE], r[P_CONTACT] = h.p_prestress, contact_pressure(params)
        r[K_RESTRICT] = h.leak_orifice
        r[A_FEED] = v.C_d * h.feed_orifice * np.sqrt(2.0 / r[RHO])
    else:
        # no piston: the volume is the hose to the restriction
        r[A_P], r[K_RESET], r[X_CONTACT] = 0.0, 1.0, 0.0
        r[P_PRE] = r[P_CONTACT] = np.inf
        r[K_RESTRICT] = VALVE_TEST_FLOW / np.sqrt(h.p_supply)
        r[G_LEAK] = r[K_SEAL] = 0.0  # no clutch, so no seal rings to leak
    return r


def wire(record: np.ndarray, *, state: int, stem_body: int, stem_spring_state: int, clutch: int, u_signal: int,
         pwm: bool, pwm_slot: int, pwm_freq: float) -> np.ndarray:
    """A copy of ``record`` placed in a compiled network.

    Parameters
    ----------
    state
        Index of the actuator's first state (the coil current) in the state vector.
    stem_body, stem_spring_state
        The valve stem's body index and the state index of its spring's deflection (the stem position).
    clutch
        Index of the clutch whose capacity the actuator sets (-1: none).
    u_signal
        Index of the input's compiled signal.
    pwm, pwm_slot, pwm_freq
        PWM drive (else DC), the external-value slot that holds the PWM level, its frequency (Hz).
    """
    r = np.asarray(record, dtype=np.float64).copy()
    r[STATE], r[STEM_BODY], r[STEM_SPRING], r[CLUTCH] = state, stem_body, stem_spring_state, clutch
    r[U_SIG], r[MODE], r[PWM_EXT], r[PWM_FREQ] = u_signal, PWM if pwm else DC, pwm_slot, pwm_freq
    return r
