"""Discrete-time torque controllers for a launch from standstill (spec section 7).

The controllers see only what the rig measures (``T_r``, speeds, ``p_clutch``,
``oil_temp``, after the sensor chain) and act on the valve's DC input ``u``
(V, within the amplifier's range). Each controller is a compiled step function
over a flat record of its settings (``ctrl``) and its own state vector
(``cs``), called once per sample by :mod:`wetclutch.launch`.

``launch`` (the design)
    Why each part is there:

    * **Fill and hold at the kiss point.** The fill dead time (0.1 to 0.5 s) is
      longer than the 0.2 s response asked for, so the clutch cannot answer from
      empty. As automatic transmissions do, the launch strategy fills the
      clutch while the car waits: full input until the measured pressure is
      ``fill_exit`` below the kiss point (the piston has stroked most of its way;
      in the stroke the pressure is the reset spring's force over the piston
      area, so it measures the piston's position), then a pressure set point
      that rises at ``hold_rate`` to ``hold_offset`` above the kiss point. The
      plates then just touch: at that low normal force friction is small (the
      friction knee), so only a creep torque of a few N m flows, which the road
      load holds. Holding *at* rather than *below* the kiss point matters: once
      the plates touch, the oil volume becomes a thousand times stiffer than the
      reset spring, and a valve opened wide to stroke the piston then slams the
      pressure towards the supply. The kiss point (contact pressure) comes from
      identification (``wetclutch identify`` estimates it as the pressure at
      torque onset) or the parameter set; ``hold_offset`` covers a kiss-point
      error of that size.
    * **Feedforward through the inverse static map.** The torque request is
      turned into a pressure through the nominal friction law
      (``T_c = T_r i / eta``, ``F_n = T_c / mu(slip)``, ``p = p_kiss + F_n / A_p``)
      and the pressure into a voltage through the inverse of the clutch's
      static pressure-vs-voltage map at the measured oil temperature
      (gain scheduling on temperature: the map is tabulated over 20 to 100 C).
    * **Feedback on pressure and on torque.** A PI loop on the measured pressure
      removes static-map errors. Friction differs from unit to unit by some
      20 %; an integrator alone would take too long to make that up within
      0.2 s, so the controller also estimates a friction factor ``theta`` (the
      measured ``T_r`` over the nominal model's torque at the measured pressure,
      low-pass filtered) and scales its friction law by it: an adaptive
      feedforward. An integrator on the torque error removes what is left
      (efficiency, kiss-point error). The slip in ``mu(slip)`` comes from the
      primary and secondary flywheels, whose speeds are smooth.
    * **Dither.** In DC mode nothing shakes the valve stem, whose friction then
      makes the pressure stall in steps (the study's reason for PWM); worse, the
      magnet's hysteresis is a play of some 0.225 V of input, and after each
      reversal the input has to cross all of it before the force moves: with a
      pressure integrator slow enough for the hold, the pressure rose in
      staircases of 20 to 60 ms, which made the response time vary from launch
      to launch. Once torque is requested the input therefore carries a
      square-wave dither *wider* than the play (0.3 V at 125 Hz): the iron then
      follows the mean coil current (the play is dithered out as a backlash is)
      and the stem never sticks; the feedforward is shifted by the play, since
      the map was measured on the rising branch and the dithered magnet works
      on the centre line. The pressure integrator is faster then than in the
      hold. Before the request (and until the fill is complete) the dither
      stays small (0.05 V, inside the play): with the stem near its overlap a
      wide dither pumps oil in, because the supply drives the inflow with
      several bar and the drain only with the clutch pressure, and the
      pressure would creep up and slam at contact.
    * **A request during the fill.** If the request comes before the filtered
      pressure has reached the hold (cold oil, a long line, a late kiss point),
      the gentle, lead-limited approach of the hold would crawl; the set point
      then jumps to ``req_lead`` above the hold so that the valve opens and the
      fill completes: a jolt at contact is then only the torque arriving. The
      request itself waits until the fill is complete (latched, so that noise
      on the filtered pressure cannot stop it again).
    * **Anti-windup.** Both integrators stop when the input saturates in the
      direction that would wind them further (conditional integration), and
      the pressure target is limited to the supply pressure.

``pi`` (the baseline)
    A plain PI controller on ``T_r`` from the torque request on, with the valve
    at its lowest input before: no fill, no feedforward, no anti-windup.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

_jit = njit(cache=True, error_model="numpy", _nrt=False)

# --- measured channels, in the order the closed loop passes them
M_P, M_TR, M_WP, M_W1, M_WR, M_WS, M_TEMP = range(7)

# --- controller record: common fields
KIND, DT, U_MIN, U_MAX = range(4)
LAUNCH, PI = 0, 1
# launch controller
(P_KISS, HOLD_OFFSET, FILL_EXIT, A_P, RATIO, ETA, MU2, MU1, MU0, F_KNEE, KP_P, KI_P, KP_T, KI_T, P_MAX, TAU_REF,
 HOLD_RATE, TAU_THETA, THETA0, DITHER_AMP, DITHER_HALF, KP_HOLD, DIP, DIP_N, HOLD_LEAD, FILL_EXIT_COLD, FF_T0, FF_DT, FF_NT, FF_P0, FF_DP, FF_NP,
 KI_HOLD, DITHER_AMP_T, DITHER_HALF_T, FF_SHIFT_T, REQ_LEAD) = range(4, 41)
FF_TABLE = 41  # start of the (nt, np) table of input voltage vs (oil temperature, pressure)
# PI baseline (shares the slots after the common fields)
KP_B, KI_B = 4, 5

# --- controller state
CS_PHASE, CS_ZP, CS_ZT, CS_U, CS_REF, CS_PSET, CS_THETA, CS_K, CS_DIP, CS_PF, CS_FILLED = range(11)
N_CS = 11
FILL, HOLD, TORQUE, LOCKUP = 0, 1, 2, 3
SYNC_SLIP = 2.0  # rad/s: measured slip below which the clutch counts as synchronised


@_jit
def _table(ctrl, temp, p):
    """Bilinear interpolation of the feedforward voltage at (oil temperature, pressure)."""
    nt = int(ctrl[FF_NT])
    npp = int(ctrl[FF_NP])
    ft = min(max((temp - ctrl[FF_T0]) / ctrl[FF_DT], 0.0), nt - 1.0)
    fp = min(max((p - ctrl[FF_P0]) / ctrl[FF_DP], 0.0), npp - 1.0)
    it = min(int(ft), nt - 2)
    ip = min(int(fp), npp - 2)
    at = ft - it
    ap = fp - ip
    b = FF_TABLE + it * npp + ip
    lo = (1.0 - ap) * ctrl[b] + ap * ctrl[b + 1]
    hi = (1.0 - ap) * ctrl[b + npp] + ap * ctrl[b + npp + 1]
    return (1.0 - at) * lo + at * hi


@_jit
def _mu(ctrl, slip):
    s = abs(slip)
    return max((ctrl[MU2] * s + ctrl[MU1]) * s + ctrl[MU0], 1e-4)


@_jit
def _pressure_target(ctrl, t_ref, slip, theta):
    """Pressure (Pa) that gives axle torque ``t_ref`` under the nominal friction law scaled by ``theta``."""
    mu = _mu(ctrl, slip) * theta
    t_c = max(t_ref, 0.0) * ctrl[RATIO] / ctrl[ETA]
    f = t_c / mu
    # invert the knee F_eff = F^2 / (F + F_knee)
    f_n = 0.5 * (f + np.sqrt(f * f + 4.0 * f * ctrl[F_KNEE]))
    return ctrl[P_KISS] + f_n / ctrl[A_P]


@_jit
def _launch(ctrl, cs, meas, t_ref):
    dt = ctrl[DT]
    p = meas[M_P]
    temp = meas[M_TEMP]
    phase = int(cs[CS_PHASE])
    p_hold = ctrl[P_KISS] + ctrl[HOLD_OFFSET]
    # pressure averaged over some 20 ms: the fill decisions must not trip on sensor noise
    cs[CS_PF] = p if cs[CS_K] == 0.0 else cs[CS_PF] + (p - cs[CS_PF]) * dt / (0.02 + dt)
    if phase == FILL:
        # scheduled on oil temperature: cold oil strokes the piston slowly through the
        # viscous line, so the fill may run closer to the kiss point without overshoot
        a = min(max((temp - 20.0) / 65.0, 0.0), 1.0)
        exit_ = (1.0 - a) * ctrl[FILL_EXIT_COLD] + a * ctrl[FILL_EXIT]
        if p < ctrl[P_KISS] - exit_:
            cs[CS_U] = ctrl[U_MAX]
            return ctrl[U_MAX]
        # the piston has stroked most of the way: approach the kiss point gently, since
        # reaching the plates with the valve wide open would jolt the pressure up
        phase = HOLD
        cs[CS_PSET] = p
        cs[CS_DIP] = ctrl[DIP_N]
    if phase == HOLD and cs[CS_DIP] > 0.0:
        # after the full-input fill the magnet sits on the descending branch of its
        # hysteresis and would hold the valve open; a short dip of the input brings it
        # onto the rising branch, which the feedforward map describes
        cs[CS_DIP] -= 1.0
        cs[CS_PHASE] = phase
        u = max(_table(ctrl, temp, p_hold) - ctrl[DIP], ctrl[U_MIN])
        cs[CS_U] = u
        return u
    if phase == HOLD and t_ref > 0.0:
        phase = TORQUE
        cs[CS_REF] = 0.0
        cs[CS_THETA] = ctrl[THETA0]
    if phase == TORQUE and abs(meas[M_WP] - meas[M_W1]) < SYNC_SLIP and meas[M_W1] > 0.0:
        # synchronised: the clutch can carry no more torque; close it firmly
        phase = LOCKUP
    cs[CS_PHASE] = phase
    if phase == LOCKUP:
        cs[CS_U] = ctrl[U_MAX]
        return ctrl[U_MAX]
    if phase == HOLD:
        cs[CS_PSET] = min(cs[CS_PSET] + ctrl[HOLD_RATE] * dt, p_hold)
        # never ask for much more than the pressure there is: a valve set far above the
        # stroke pressure opens wide and slams the pressure up when the plates touch
        p_set = min(cs[CS_PSET], cs[CS_PF] + ctrl[HOLD_LEAD])
    else:
        # until the fill is complete (cold oil, long line) the request waits, and the
        # integrator with it: it would only wind up against a clutch that cannot answer yet
        # (latched: once filled, noise on the filtered pressure must not stop the request again)
        gated = cs[CS_FILLED] == 0.0 and cs[CS_PF] < p_hold
        if not gated:
            cs[CS_FILLED] = 1.0
            # the request through a first-order prefilter: a torque step through the valve's
            # fast, underdamped pressure response would jolt the driveline
            cs[CS_REF] += (t_ref - cs[CS_REF]) * dt / (ctrl[TAU_REF] + dt)
        r = cs[CS_REF]
        e_t = r - meas[M_TR]
        # slip from the secondary flywheel, not from omega_1: the light CVT input shakes
        # with the clutch torque, and feeding that back through mu(slip) closes a fast loop
        slip = meas[M_WP] - meas[M_WS] / ctrl[RATIO]
        # friction estimate: measured torque over the nominal model's at the measured
        # pressure, once the plates press hard enough for the ratio to mean something
        f_n = (p - ctrl[P_KISS]) * ctrl[A_P]
        if f_n > ctrl[F_KNEE] * 1.5:
            t_model = ctrl[ETA] / ctrl[RATIO] * _mu(ctrl, slip) * f_n * f_n / (f_n + ctrl[F_KNEE])
            theta = min(max(meas[M_TR] / t_model, 0.5), 2.0)
            cs[CS_THETA] += (theta - cs[CS_THETA]) * dt / (ctrl[TAU_THETA] + dt)
        th = cs[CS_THETA]
        p_r = _pressure_target(ctrl, r, slip, th)
        sens = _pressure_target(ctrl, r + 1.0, slip, th) - p_r  # Pa per N m
        p_set = p_r + cs[CS_ZT] + ctrl[KP_T] * sens * e_t
        p_set = min(max(p_set, p_hold), ctrl[P_MAX])
        if gated:
            # finish the fill; with the request there a jolt at contact is wanted rather than
            # feared, so the set point may lead the measured pressure further than in the hold
            p_set = p_hold + ctrl[REQ_LEAD]
        u_prev = cs[CS_U]
        wind_up = gated or (u_prev >= ctrl[U_MAX] and e_t > 0.0) or (u_prev <= ctrl[U_MIN] and e_t < 0.0)
        if not wind_up:
            cs[CS_ZT] += ctrl[KI_T] * sens * e_t * dt
    e_p = p_set - p
    # in the hold the plates have just touched; an overshoot there would leave the
    # stem in its overlap with the pressure trapped high, so push back harder
    # (a request still waiting for the fill counts as hold here: its stem sits near
    # the overlap, where a wide dither would pump oil in and slam the pressure up)
    hold = phase == HOLD or cs[CS_FILLED] == 0.0
    kp = ctrl[KP_HOLD] if hold else ctrl[KP_P]
    ki = ctrl[KI_HOLD] if hold else ctrl[KI_P]
    # with the torque dither wider than the magnet's play the iron follows the mean
    # current, not the rising branch the map was measured on: shift the map by the play
    shift = 0.0 if hold else ctrl[FF_SHIFT_T]
    u = _table(ctrl, temp, p_set) - shift + cs[CS_ZP] + kp * e_p
    if u > ctrl[U_MAX]:
        u = ctrl[U_MAX]
        if e_p < 0.0:
            cs[CS_ZP] += ki * e_p * dt
    elif u < ctrl[U_MIN]:
        u = ctrl[U_MIN]
        if e_p > 0.0:
            cs[CS_ZP] += ki * e_p * dt
    else:
        cs[CS_ZP] += ki * e_p * dt
    cs[CS_U] = u
    # a square-wave dither on top: it keeps the valve stem from sticking (the DC
    # drive lacks the dither that PWM gives); the integrators do not see it
    k = int(cs[CS_K])
    cs[CS_K] = k + 1
    if hold:
        amp, half = ctrl[DITHER_AMP], max(int(ctrl[DITHER_HALF]), 1)
    else:
        amp, half = ctrl[DITHER_AMP_T], max(int(ctrl[DITHER_HALF_T]), 1)
    d = amp if (k // half) % 2 == 0 else -amp
    return min(max(u + d, ctrl[U_MIN]), ctrl[U_MAX])


@_jit
def _pi(ctrl, cs, meas, t_ref):
    if t_ref <= 0.0:
        return ctrl[U_MIN]
    e = t_ref - meas[M_TR]
    cs[CS_ZT] += ctrl[KI_B] * e * ctrl[DT]
    return min(max(ctrl[KP_B] * e + cs[CS_ZT], ctrl[U_MIN]), ctrl[U_MAX])


@_jit
def step(ctrl, cs, meas, t_ref):
    """One controller sample: measured channels ``meas`` and request ``t_ref`` (N m) -> input (V)."""
    if int(ctrl[KIND]) == PI:
        return _pi(ctrl, cs, meas, t_ref)
    return _launch(ctrl, cs, meas, t_ref)


# ------------------------------------------------------------------ settings


@dataclass(frozen=True)
class LaunchGains:
    """Settings of the ``launch`` controller (SI; pressures in Pa, gains per Pa or per N m).

    Attributes
    ----------
    hold_offset : float
        Hold the pressure this far above the kiss point while waiting, Pa.
    fill_exit, fill_exit_cold : float
        End the full-input fill this far below the kiss point, Pa, with oil at
        85 C and at 20 C (linear in between).
    hold_rate : float
        Rate at which the pressure set point then approaches the hold pressure, Pa/s.
    kp_p, ki_p : float
        Pressure PI once the torque is requested: V/Pa and V/(Pa s).
    kp_hold, ki_hold : float
        Pressure PI while holding at the kiss point (and while a request waits for
        the fill), V/Pa and V/(Pa s): gentler than after the request, since a
        faster integrator there winds the valve open against the stroking piston
        and slams the pressure up at contact.
    hold_lead : float
        While approaching the hold, the set point stays at most this far above
        the measured pressure, Pa.
    req_lead : float
        A request that comes before the fill is complete asks for this much
        above the hold pressure, Pa, until the filtered pressure reaches the
        hold: the torque is wanted now, so the valve may open further than in
        the gentle hold approach (a slam at contact only brings the torque on).
    dip, dip_time : float
        After the fill, the input drops this far (V) below the hold input for
        this long (s), to bring the magnet onto its rising hysteresis branch.
    kp_t, ki_t : float
        Torque loop on the pressure target: proportional (-) and integral (1/s)
        gains on the torque error, scaled by the nominal pressure per N m.
    tau_ref : float
        Time constant of the first-order prefilter on the torque request, s.
    tau_theta : float
        Time constant of the friction estimate (measured over nominal torque), s.
    theta0 : float
        Friction factor assumed until it is measured: on the high side of the
        spread, so that a grippy unit does not overshoot before the estimate
        catches up (a slippery one is a little slower instead). 1.4 rather than
        1.2: with the pressure now rising without staircases, the first rise
        reaches the plates faster than the estimate (10 ms) settles, and at low
        CVT ratios (high torque gain onto the axle) the overshoot then set the
        robustness failures.
    dither_amp, dither_hz : float
        Square-wave dither on the valve input (V, Hz) against stem stick-slip,
        before the request and while the fill completes: smaller than the
        magnet's play, which swallows it, since near the overlap a wide dither
        pumps oil in (inflow from the supply is far stronger than drain flow).
    dither_amp_torque, dither_hz_torque : float
        The dither once the clutch is filled and torque is requested (V, Hz):
        wider than the magnet's play (about 0.225 V of input), so that the iron
        follows the mean coil current and neither the play nor the stem
        friction can stall the pressure in steps.
    ff_shift_torque : float
        Fraction of the design valve's play (``I_hyst / g_current``, V) taken
        off the feedforward under the wide dither: the map was measured on the
        rising hysteresis branch, the dithered magnet works on the centre line.
    """

    hold_offset: float = 0.05e5
    fill_exit: float = 0.1e5
    fill_exit_cold: float = 0.05e5
    hold_rate: float = 1.0e5
    kp_p: float = 0.05e-5
    ki_p: float = 5.0e-5
    kp_t: float = 0.0
    ki_t: float = 8.0
    tau_ref: float = 0.03
    tau_theta: float = 0.01
    theta0: float = 1.4
    dither_amp: float = 0.05
    kp_hold: float = 0.05e-5
    ki_hold: float = 2.0e-5
    dither_amp_torque: float = 0.3
    dither_hz_torque: float = 125.0
    ff_shift_torque: float = 1.0
    req_lead: float = 0.2e5
    dip: float = 0.5
    hold_lead: float = 0.01e5
    dip_time: float = 0.015
    dither_hz: float = 125.0


@dataclass(frozen=True)
class PIGains:
    """Settings of the ``pi`` baseline: u = kp e + ki int(e), e = T_ref - T_r (V/N m, V/(N m s)).

    Tuned by hand on the nominal 100 N m launch as the fastest pair whose slip phase
    does not settle into a limit cycle (kp 0.01 and ki 0.15 did); whatever the gains,
    the integrator winds up while the clutch fills, so the torque overshoots when the
    plates close.
    """

    kp: float = 0.001
    ki: float = 0.05


CONTROLLERS = ("launch", "pi")

#: oil temperatures (C) and input voltages (V) at which the feedforward map is tabulated
MAP_TEMPS = np.array([20.0, 40.0, 60.0, 80.0, 100.0])
MAP_VOLTS = np.linspace(0.2, 5.0, 17)
MAP_PRESSURES = np.linspace(0.0, 8e5, 33)


def static_map(params, temps: np.ndarray = MAP_TEMPS, volts: np.ndarray = MAP_VOLTS) -> np.ndarray:
    """Static clutch pressure (Pa) vs DC input, shape (len(temps), len(volts)), from the model.

    Each point is a constant-input run of the clutch configuration, averaged over
    its last second (:func:`wetclutch.clutch.static_pressure`).
    """
    from . import clutch

    return np.array([[clutch.static_pressure(params, float(v), temp_C=float(temp), t_end=3.0, dt_out=1e-2)
                      for v in volts] for temp in temps])


def inverse_map(p_static: np.ndarray, volts: np.ndarray = MAP_VOLTS, pressures: np.ndarray = MAP_PRESSURES) -> np.ndarray:
    """Input voltage for each target pressure, shape (n_temps, len(pressures)): the feedforward table.

    The static curve is made non-decreasing first (a flat stretch, e.g. below
    the prestress, maps to its lowest input); pressures beyond the reachable
    range map to the range's ends.
    """
    table = np.zeros((p_static.shape[0], pressures.size))
    for i, row in enumerate(p_static):
        mono = np.maximum.accumulate(row) + 1e-9 * np.arange(row.size)  # strictly increasing for interp
        table[i] = np.interp(pressures, mono, volts)
    return table
