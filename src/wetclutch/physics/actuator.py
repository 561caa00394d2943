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
drives the coil; its output saturates at the supply voltage, so a large step
rises with ``L/R``; when the controller asks for a negative voltage the output
transistor blocks and the current decays through the freewheel circuit with
``L/(R + R_freewheel)``. These are the amplifier's three modes (regulating,
saturated, freewheeling): the coil voltage jumps where the freewheel circuit takes
over, so the engine switches them at located events (:func:`amplifier_event`), as it
does a clutch's, and never inside a step. In PWM mode the coil sees the supply voltage during the
high part of each period and freewheels through a diode during the low part, so
the mean current is about ``duty * V_supply / R_coil``.

Magnet (the study: "friction of the magnet causes hysteresis", and "no simple model
known" for the force): the force follows the magnetisation of the iron, which lags
the coil current by a play (backlash, Prandtl) of half-width ``I_hyst``: ``I_m``
stays put while ``|I - I_m| < I_hyst`` and is dragged along at that distance
beyond. The play is smoothed as a Duhem model, ``dI_m/dt = dI/dt * min(z, 1)^n`` with
``z = (I - I_m) sign(dI/dt) / I_hyst`` (0 when negative) and ``n`` = ``valve.play_exponent`` (8), so it
needs no events; the steep power keeps ``I_m`` nearly still inside the play (a larger ``n``: a sharper play,
the ideal one as ``n`` grows), and the lag settles at
``I_hyst`` while the current keeps moving one way. A PWM ripple smaller than the
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
    N_ACT,
) = range(47)

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
def event(cur, p, u, act, amp_mode, piston):
    """The actuator's event function: the amplifier's (:func:`amplifier_event`) and the piston's
    (:func:`piston_event`), whichever is nearer its switch."""
    return _with_piston(amplifier_event(cur, u, act, amp_mode), p, act, piston)


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
def play_rate(cur, cur_dot, i_m, r, n):
    """dI_m/dt of the smoothed play (Duhem form, see the module docstring) of half-width ``r`` > 0 and exponent
    ``n`` (a whole number >= 1)."""
    z = (cur - i_m if cur_dot > 0.0 else i_m - cur) * (1.0 / r)
    if z <= 0.0:
        return 0.0
    # I_m never outruns I: capping keeps the rate bounded even where a trial stage of the
    # explicit integrator overshoots the play (an uncapped z^n runs away there)
    z = min(z, 1.0)
    # z^n as (z^(n/2))^2 (times z for odd n), z^(n/2) by squaring: a handful of products where a float power
    # would cost a logarithm and an exponential in every stage (numba's ``z ** n`` with a run-time n is not the
    # same number: it moved a launch by 17 of 12,897 steps)
    k = int(n)
    m = k // 2
    half = 1.0
    b = z
    while m > 0:
        if m & 1:
            half *= b
        m >>= 1
        if m > 0:
            b *= b
    if k % 2 == 1:
        return cur_dot * half * half * z
    return cur_dot * half * half


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
    freewheeling where the controller asks for a negative one, else regulating (PWM: regulating, unused)."""
    if act[MODE] == PWM:
        return REGULATE
    v = _regulator_voltage(x[int(act[STATE]) + CURRENT], u, act)
    if v > act[V_SUP]:
        return SATURATED
    if v < 0.0:
        return FREEWHEEL
    return REGULATE


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def amplifier_event(cur, u, act, mode):
    """The amplifier's event function: >= 0 while ``mode`` holds (the controller's voltage within the
    stage's range, above it, or below zero). PWM: 1 (its edges are time events)."""
    if act[MODE] == PWM:
        return 1.0
    return _range_margin(_regulator_voltage(cur, u, act), act, mode)


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def _range_margin(v, act, mode):
    """The DC amplifier's event function at the controller's voltage ``v`` (:func:`amplifier_event`)."""
    if mode == SATURATED:
        return v - act[V_SUP]
    if mode == FREEWHEEL:
        return -v
    return min(v, act[V_SUP] - v)


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def evaluate(x, act, u, ext, dx, full=True, mode=REGULATE, piston=AT_STOP):
    """Write the actuator's state rates into ``dx``; return (force on the stem, clutch normal force,
    the actuator's event function, :func:`event`).

    ``u`` is the input (V in DC mode; ignored in PWM mode, where ``ext`` holds the level) and
    ``mode`` the DC amplifier's (:func:`amplifier_mode`, decided at the last restart: within a step
    the regulating mode's voltage runs on beyond its range until the event is located), ``piston`` the
    piston's (:func:`piston_mode`, likewise: the stroke's compliance holds until its band's edge is located).
    With ``full`` False only the forces are wanted: the pressure derivative is skipped.
    """
    i0 = int(act[STATE])
    cur = x[i0 + CURRENT]
    p = x[i0 + PRESSURE]
    # ---- electronics and coil
    if act[MODE] == PWM:
        # low part of a period: the current freewheels through the diode (about 0 V)
        v = act[V_SUP] if ext[int(act[PWM_EXT])] > 0.5 else 0.0
        g_amp = 1.0
    else:
        v_reg = _regulator_voltage(cur, u, act)
        g_amp = _range_margin(v_reg, act, mode)
        if mode == SATURATED:
            v = act[V_SUP]
        elif mode == FREEWHEEL:
            v = -act[R_FW] * cur  # output transistor blocks: freewheel
        else:
            v = v_reg
    # constant reciprocals: the divide then runs off the dependency chain of the state
    cur_dot = (v - act[R_COIL] * cur) * (1.0 / act[L_COIL])
    dx[i0 + CURRENT] = cur_dot
    # ---- magnetisation: a play on the current (hysteresis); none: I_m tracks I exactly
    if act[I_HYST] > 0.0:
        i_m = x[i0 + MAGNETISATION]
        dx[i0 + MAGNETISATION] = play_rate(cur, cur_dot, i_m, act[I_HYST], act[PLAY_N])
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
    r = np.zeros(N_ACT)
    r[V_SUP], r[R_COIL], r[L_COIL], r[R_FW] = v.V_supply, v.R_coil, v.L_coil, v.R_freewheel
    r[K_AMP], r[G_CURRENT] = v.amp_gain, v.g_current
    r[K_F1], r[K_F2], r[F_PRE], r[A_FB] = v.k_F1, v.k_F2, v.F_preload, v.A_fb
    r[I_HYST], r[I_SAT], r[PLAY_N] = v.I_hyst, v.I_sat, v.play_exponent
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
