"""Baseline "clutch step" run of the actuator and driveline with :func:`scipy.integrate.solve_ivp`.

A typical hand-written model used as a speed baseline for the compiled engine: a plain
Python right-hand side, a stiff method (BDF by default), terminal ``events`` for the
mode switches and a loop restarting ``solve_ivp`` after every event and at the input
step. Same equations and default parameters (oil at 85 C) as
``wetclutch.plant.clutch.build(Params(), Step(1.0, 0.2, 1.0))``: the parameter values are
read from :mod:`wetclutch`, the dynamics are written here.

State ``y = [w_p, w_1, phi, w_s, x, v, I, p, I_m]``: primary, clutch-output speeds, axle twist,
secondary speed, valve stem position and speed, coil current, clutch pressure (SI, gauge),
magnetising current; then, as the engine carries them, nine quadratures: the energy
dissipated in the clutch, the road-load brake, the stem friction, air drag, the dampers and
the CVT, the work of the actuator's force on the stem, and the oil volumes into and out of
the clutch (``bookkeeping=False`` leaves them out: a lighter model than the engine's).

* Coil: current controller (setpoint ``g_current u``) whose voltage the output stage clips to
  ``-R_fw I .. V_sup``: saturating at the supply voltage, freewheeling where it asks for less than
  the freewheel circuit's ``-R_fw I``: three modes of the output stage, switched at events.
* Magnet: the magnetising current ``I_m`` follows ``I`` through a smoothed play of
  half-width ``I_hyst`` (``dI_m/dt = dI/dt min(z, 1)^n``, ``z = (I - I_m) sign(dI/dt) / I_hyst``, ``n`` the
  play's exponent);
  force ``k_F1 I_m + k_F2 I_m^2``, continued linearly above ``I_sat``.
* Stem: ``m v' = F_mag(I_m) + F_pre - A_fb p - c x - d v - friction``, Coulomb
  friction by exact stick/slip (events: ``v = 0``, holding force beyond ``F_friction``).
* Hydraulics: supply port (and the clutch's feed restriction) in series with the laminar
  line, steady flow force on the stem, drain port, seal leakage (laminar gap in series
  with an orifice), relief;
  aerated-oil compliance plus the piston stroking against its reset spring.
* Driveline: clutch torque ``F_n F_n / (F_n + F_knee) mu(|slip|) sign(slip)`` with
  ``F_n = A_p (p - p_contact)``, oil drag ``b (w_p - w_1)``, CVT ``w_r = i w_1`` (massless
  output) losing ``eta`` against the power flow and held at standstill while the torques
  stay in the efficiency band, axle spring-damper, road load as a Coulomb brake, air drag.

Simplifications (checked against the engine's event log of this run): the clutch only goes
from open to slipping (it never locks within 5 s) and the road-load brake only releases, so
the reverse switches are not modelled.

Agreement with the engine (``__main__``): the same events (stem stick/slip switches, the piston leaving its stop, contact,
road-load release, the amplifier's modes); pressure within 2 Pa at 1.2-5 s, torque onset within 7 us; about 100 Pa at
worst on the 1 ms grid, right after contact (a steep rise; integration error of both sides);
the energy terms at 5 s within 0.01 %, and the energy balance closes to 3e-8 of the
stored energy (the engine's to 1e-13).
"""

import math

import numpy as np
from _timing import median_time
from scipy.integrate import solve_ivp

import wetclutch as wc
from wetclutch.physics import actuator as A
from wetclutch.physics import oil
from wetclutch.plant import clutch
from wetclutch.sim.network import integrate
from wetclutch.sim.signals import Step

W_P, W_1, PHI, W_S, X, V, I, P, IM = range(9)
# bookkeeping (quadratures): energy dissipated in the clutch, road-load brake, stem friction, air drag,
# dampers, CVT; work of the actuator's force on the stem; oil volume in and out of the clutch
E_CL, E_BR, E_SF, E_AIR, E_DAMP, E_GEAR, W_SRC, V_IN, V_OUT = range(9, 18)
#: the engine's names (``Trajectory.energies``) of the energy states E_CL ... W_SRC, in that order
ENERGY_TERMS = ("dissipated_clutch", "dissipated_brake", "dissipated_stem_friction", "dissipated_drag",
                "dissipated_damper", "dissipated_gear", "source_work")
LOCKED, STUCK = 2, 3  # stem/brake held; CVT held at standstill (+-3: sign of the held torque)
T_STEP, U0, U1 = 1.0, 0.2, 1.0  # input step, V
ONSET = 0.2  # clutch torque defining the onset, N m
DT_OUT = 1e-3  # output grid, s (as the engine's default)
SCALE = np.array([100.0, 100.0, 1.0, 10.0, 1e-3, 1e-2, 1.0, 1e6, 1.0,  # typical magnitudes of y
                  1e3, 10.0, 1e-4, 100.0, 100.0, 1.0, 1e-3, 1e-5, 1e-6])


class Rig:
    """Parameter values of the default rig (SI units), read from :mod:`wetclutch`."""

    def __init__(self, temp_C: float = 85.0):
        prm = wc.Params()
        d, v, f = prm.driveline, prm.valve, prm.friction
        self.r = A.pack(prm, temp_C).tolist()  # floats, indexed by wetclutch.physics.actuator names
        self.J_p, self.J_1, self.J_s, self.b_1, self.b_2 = d.J_p, d.J_1, d.J_s, d.b_1, d.b_2
        self.i, self.eta, self.k_a, self.d_a, self.w_p0 = d.ratio, d.eta, d.k_a, d.d_a, d.omega_p0
        self.drag = f.drag_20C * oil.dynamic_viscosity(temp_C) / oil.dynamic_viscosity(20.0)
        self.mu = [c * f.mu_scale for c in f.mu_slip_poly]
        self.m, self.c, self.d, self.F_f, self.T_load = v.m_stem, v.c_stem, v.d_stem, v.F_friction, prm.engage.T_load


def _k_eff(p, k_oil, x0):
    """Bulk modulus of oil with entrained air (polytropic air, series compliance), Pa."""
    p_abs = oil.P_ATM + p
    v_air = x0 * (oil.P_ATM / p_abs) ** (1.0 / oil.KAPPA_AIR)
    x = v_air / (v_air + 1.0 - x0)
    return 1.0 / ((1.0 - x) / k_oil + x / (oil.KAPPA_AIR * p_abs))


def _port_flows(r, xs, p):
    """Openings of the supply and drain ports (m) and the flows through them (m^3/s)."""
    o_sup = min(max(xs - r[A.OVERLAP], 0.0), r[A.X_PORT])
    o_drn = min(max(-xs - r[A.OVERLAP], 0.0), r[A.X_PORT])
    q_in = 0.0
    if o_sup > 0.0:  # turbulent port (with the feed restriction in series) and the laminar line
        a = r[A.CDW] * o_sup * math.sqrt(2.0 / r[A.RHO])
        if r[A.A_FEED] > 0.0:
            a = a * r[A.A_FEED] / math.sqrt(a * a + r[A.A_FEED] ** 2)
        a2r = a * a * r[A.R_LINE]
        dp = r[A.P_SUP] - p
        q_in = math.copysign(0.5 * (-a2r + math.sqrt(a2r * a2r + 4.0 * a * a * abs(dp))), dp)
    q_drn = r[A.CDW] * o_drn * math.sqrt(2.0 * max(p, 0.0) / r[A.RHO])
    return o_sup, o_drn, q_in, q_drn


def _seal_leak(r, p):
    """Laminar seal gap in series with a turbulent orifice: p = Q/G + (Q/K)^2, m^3/s."""
    g, k = r[A.G_LEAK], r[A.K_SEAL]
    if k <= 0.0 or p <= 0.0:
        return g * p
    return 2.0 * g * p / (1.0 + math.sqrt(1.0 + 4.0 * g * g * p / (k * k)))


def _feedback(r, p):
    """The stem's feedback chamber: leak through orifice, guide gap and vent (m^3/s), and the chamber's pressure.

    The whole path is ``p = Q/G + (Q/K)^2`` (K: the orifices in series), solved as the positive root
    of that quadratic in Q; the chamber sits behind the damping orifice."""
    if r[A.FB_DAMP] <= 0.0 or p <= 0.0:
        return 0.0, p
    g, k2 = r[A.FB_GAP], r[A.FB_TURB] ** 2
    q = (math.sqrt(1.0 / (g * g) + 4.0 * p / k2) - 1.0 / g) * k2 / 2.0
    return q, p - (q / r[A.FB_DAMP]) ** 2


def _flows(r, ports, p):
    """Oil flows into and out of the clutch volume (drain port, seal leak, restriction, relief), m^3/s.

    ``ports``: :func:`_port_flows` at this state."""
    _, _, q_in, q_drn = ports
    q_out = q_drn + _seal_leak(r, p) + _feedback(r, p)[0] + r[A.K_RESTRICT] * math.sqrt(max(p, 0.0))
    if p > r[A.P_RELIEF]:
        q_out += r[A.G_RELIEF] * (p - r[A.P_RELIEF])
    return q_in, q_out


def _capacitance(r, p):
    """Compliance of the clutch volume (oil, entrained air, the piston on its reset spring), m^3/Pa."""
    stroke = min(max(r[A.A_P] * (p - r[A.P_PRE]) / r[A.K_RESET], 0.0), r[A.X_CONTACT])  # piston travel
    cap = (r[A.V0] + r[A.A_P] * stroke) / _k_eff(max(p, 0.0), r[A.K_OIL], r[A.AIR])
    if r[A.P_PRE] < p < r[A.P_CONTACT]:
        cap += r[A.A_P] ** 2 / r[A.K_RESET]  # the piston strokes against the reset spring
    return cap


def _magnet(r, i_m):
    """Magnet force at magnetising current ``i_m``: quadratic, continued linearly above ``I_sat``, N."""
    i_s = r[A.I_SAT]
    if i_m <= i_s:
        return r[A.K_F1] * i_m + r[A.K_F2] * i_m * i_m
    return r[A.K_F1] * i_s + r[A.K_F2] * i_s * i_s + (r[A.K_F1] + 2.0 * r[A.K_F2] * i_s) * (i_m - i_s)


def _play(r, cur, cur_dot, i_m):
    """dI_m/dt: the magnet's hysteresis, a smoothed play of half-width ``I_hyst`` on the current."""
    if r[A.I_HYST] <= 0.0:
        return cur_dot
    z = (cur - i_m if cur_dot > 0.0 else i_m - cur) / r[A.I_HYST]
    return cur_dot * min(z, 1.0) ** r[A.PLAY_N] if z > 0.0 else 0.0


def _stem_force(m, y, ports=None):
    """Magnet force + preload - pressure feedback - spring: what the friction must hold, N."""
    r = m.r
    i_m = y[IM] if r[A.I_HYST] > 0.0 else y[I]
    o_sup, o_drn, q_in, _ = _port_flows(r, y[X], y[P]) if ports is None else ports
    dp_in = r[A.P_SUP] - y[P] - r[A.R_LINE] * q_in  # steady flow force: the jets pull the stem shut
    f_flow = r[A.K_FLOW] * (o_sup * max(dp_in, 0.0) - o_drn * max(y[P], 0.0))
    return _magnet(r, i_m) + r[A.F_PRE] - r[A.A_FB] * _feedback(r, y[P])[1] - f_flow - m.c * y[X]


def _clutch_torque(m, y, mode):
    """Clutch torque on the output (N m): capacity from the normal force times mu(|slip|)."""
    f_n = m.r[A.A_P] * (y[P] - m.r[A.P_CONTACT])
    if mode == 0 or f_n <= 0.0:
        return 0.0
    s, mu = abs(y[W_P] - y[W_1]), 0.0
    for c in m.mu:
        mu = mu * s + c
    return mode * f_n * f_n / (f_n + m.r[A.F_KNEE]) * max(mu, 0.0)


def _axle(m, y):
    """Axle torque on the secondary = CVT output torque (N m)."""
    return m.k_a * y[PHI] + m.d_a * (m.i * y[W_1] - y[W_S])


def _regulator(r, y, u):
    """The current controller's voltage before the output stage limits it (V)."""
    i_ref = r[A.G_CURRENT] * u
    return r[A.R_COIL] * i_ref + r[A.K_AMP] * (i_ref - y[I])


def _within(v, v_fw, v_sup):
    """The regulating output stage's event function: its voltage's margin to either limit (>= 0 inside)."""
    return min(v - v_fw, v_sup - v)


def _amp_mode(r, y, u):
    """The output stage's mode: saturated (1) above the supply voltage, freewheeling (-1) below the freewheel
    circuit's voltage, else 0."""
    v = _regulator(r, y, u)
    return 1 if v > r[A.V_SUP] else -1 if v < -r[A.R_FW] * y[I] else 0


def _rhs(t, y, m, modes, u):
    """Time derivative of ``y`` for fixed modes (clutch, brake, stem, CVT, amplifier) and input ``u`` (V).

    With the bookkeeping states (``len(y) == 18``) also the energy and oil-volume rates."""
    r, (mc, mb, ms, mg, ma), dy = m.r, modes, [0.0] * len(y)
    if ma == 1:
        volt = r[A.V_SUP]
    elif ma == -1:
        volt = -r[A.R_FW] * y[I]  # the output transistor blocks: freewheel
    else:
        volt = _regulator(r, y, u)
    dy[I] = (volt - r[A.R_COIL] * y[I]) / r[A.L_COIL]
    dy[IM] = _play(r, y[I], dy[I], y[IM])
    ports = _port_flows(r, y[X], y[P])
    q_in, q_out = _flows(r, ports, y[P])
    dy[P] = (q_in - q_out) / _capacitance(r, y[P])
    f_stem = _stem_force(m, y, ports)
    if ms != LOCKED:
        dy[X] = y[V]
        dy[V] = (f_stem - m.d * y[V] - m.F_f * ms) / m.m
    t_c = _clutch_torque(m, y, mc)
    t_oil = m.drag * (y[W_P] - y[W_1])
    lam = _axle(m, y)
    c = 1.0 / m.eta if mg > 0 else m.eta
    dy[W_P] = (-m.b_1 * y[W_P] * abs(y[W_P]) - t_c - t_oil) / m.J_p
    if abs(mg) != STUCK:
        dy[W_1] = (t_c + t_oil - m.i * c * lam) / m.J_1
    dy[PHI] = m.i * y[W_1] - y[W_S]
    if mb != LOCKED:
        dy[W_S] = (lam - m.b_2 * y[W_S] * abs(y[W_S]) - m.T_load * mb) / m.J_s
    if len(y) > IM + 1:
        dy[E_CL] = t_c * (y[W_P] - y[W_1])
        dy[E_BR] = 0.0 if mb == LOCKED else m.T_load * abs(y[W_S])
        dy[E_SF] = 0.0 if ms == LOCKED else m.F_f * abs(y[V])
        dy[E_AIR] = m.b_1 * abs(y[W_P]) ** 3 + m.b_2 * abs(y[W_S]) ** 3
        dy[E_DAMP] = m.d_a * dy[PHI] ** 2 + m.drag * (y[W_P] - y[W_1]) ** 2 + m.d * y[V] ** 2
        dy[E_GEAR] = 0.0 if abs(mg) == STUCK else (c - 1.0) * lam * m.i * y[W_1]
        dy[W_SRC] = (f_stem + m.c * y[X]) * y[V]  # the actuator's force on the stem (its spring is stored energy)
        dy[V_IN] = q_in
        dy[V_OUT] = q_out
    return dy


def energy_residual(m, y):
    """Largest |stored + dissipated - initial - supplied| over the rows of ``y`` (18 states), relative to
    the largest stored or supplied energy: the same measure as the engine's ``Trajectory.energy_residual``."""
    stored = (0.5 * (m.J_p * y[:, W_P] ** 2 + m.J_1 * y[:, W_1] ** 2 + m.J_s * y[:, W_S] ** 2 + m.m * y[:, V] ** 2)
              + 0.5 * (m.k_a * y[:, PHI] ** 2 + m.c * y[:, X] ** 2))
    balance = stored + y[:, E_CL:W_SRC].sum(axis=1) - stored[0] - y[:, W_SRC]
    return float(np.max(np.abs(balance)) / max(np.max(np.abs(stored)), np.max(np.abs(y[:, W_SRC]))))


def _gear_margins(m, y, mc, mg):
    """Held CVT: margins (>= 0 while held) of the input torque seen at the output within the efficiency band."""
    q = (_clutch_torque(m, y, mc) + m.drag * y[W_P]) / m.i
    lam, s = _axle(m, y), math.copysign(1.0, mg)
    return s * (q - m.eta * lam), s * (lam / m.eta - q)


def _gear_at_rest(m, y, mc):
    """CVT mode at standstill (clutch mode ``mc``): held, or driven backward (output wins) or forward (input wins)."""
    lam = _axle(m, y)
    held = -STUCK if (lam if lam != 0.0 else _clutch_torque(m, y, mc) + m.drag * y[W_P]) < 0.0 else STUCK
    m_in, m_out = _gear_margins(m, y, mc, held)
    return -1 if m_in < 0.0 else 1 if m_out < 0.0 else held


def _stem_at_rest(m, y):
    """Stem mode at zero speed: stuck while the friction can hold it, else sliding with the force."""
    f = _stem_force(m, y)
    return LOCKED if abs(f) <= m.F_f else (1 if f > 0.0 else -1)


def _event(fun, direction, terminal=True):
    """Mark ``fun`` as a solve_ivp event crossing zero in ``direction``."""
    fun.terminal, fun.direction = terminal, direction
    return fun


def _events(m, modes, want_onset, u, y):
    """``(name, event function)`` pairs valid in the current modes at input ``u`` and state ``y``."""
    mc, mb, ms, mg, ma = modes
    ev = []
    if mc == 0:
        ev.append(("contact", _event(lambda t, y, *_: y[P] - m.r[A.P_CONTACT], 1)))
    elif want_onset:
        ev.append(("onset", _event(lambda t, y, *_: abs(_clutch_torque(m, y, mc)) - ONSET, 1, False)))
    if mb == LOCKED:
        ev.append(("brake", _event(lambda t, y, *_: abs(_axle(m, y)) - m.T_load, 1)))
    if ms == LOCKED:
        ev.append(("stem_slip", _event(lambda t, y, *_: abs(_stem_force(m, y)) - m.F_f, 1)))
    else:
        ev.append(("stem_stop", _event(lambda t, y, *_: y[V], -ms)))
    if abs(mg) == STUCK:
        ev.append(("gear_back", _event(lambda t, y, *_: _gear_margins(m, y, mc, mg)[0], -1)))
        ev.append(("gear_fwd", _event(lambda t, y, *_: _gear_margins(m, y, mc, mg)[1], -1)))
    else:
        ev.append(("gear_flow", _event(lambda t, y, *_: mg * _axle(m, y) * y[W_1], -1)))
    v_sup = m.r[A.V_SUP]
    if ma == 1:
        ev.append(("amp", _event(lambda t, y, *_: _regulator(m.r, y, u) - v_sup, -1)))
    elif ma == -1:
        ev.append(("amp", _event(lambda t, y, *_: -m.r[A.R_FW] * y[I] - _regulator(m.r, y, u), -1)))
    else:
        ev.append(("amp", _event(lambda t, y, *_: _within(_regulator(m.r, y, u), -m.r[A.R_FW] * y[I], v_sup), -1)))
    if y[P] < m.r[A.P_PRE]:
        # the piston leaves its stop: the stroke's compliance, a thousand times the oil's, begins
        ev.append(("stroke", _event(lambda t, y, *_: y[P] - m.r[A.P_PRE], 1)))
    return ev


def _switch(m, name, y, modes, u):
    """New modes after event ``name`` at state ``y`` and input ``u`` (``y`` is projected in place where a body
    stops)."""
    mc, mb, ms, mg, ma = modes
    if name == "amp":
        # out of a limit into regulation; out of regulation across the nearer limit (the root may lie on
        # either side of it)
        v = _regulator(m.r, y, u)
        ma = 0 if ma != 0 else (1 if v > 0.5 * m.r[A.V_SUP] else -1)
    elif name == "contact":
        mc = 1 if y[W_P] > y[W_1] else -1
    elif name == "stroke":
        y[P] = m.r[A.P_PRE] * (1.0 + 1e-12)  # on the stroke's side of the root
    elif name == "brake":
        mb = 1 if _axle(m, y) > 0.0 else -1
    elif name == "stem_slip":
        ms = 1 if _stem_force(m, y) > 0.0 else -1
    elif name == "stem_stop":
        y[V] = 0.0
        ms = _stem_at_rest(m, y)
    elif name in ("gear_back", "gear_fwd"):
        mg = -1 if name == "gear_back" else 1
    elif abs(y[W_1]) <= 1e-8 * max(1.0, abs(y[W_P])):  # gear_flow through a standstill
        y[W_1] = 0.0
        mg = _gear_at_rest(m, y, mc)
    else:  # gear_flow: the torque reversed, so the power flows the other way
        mg = -mg
    return (mc, mb, ms, mg, ma)


def actuator_step_scipy(t_end: float = 5.0, method: str = "BDF", rtol: float = 1e-6, atol=None,
                        bookkeeping: bool = True) -> dict:
    """Simulate the clutch step (0.2 V -> 1 V at 1 s, oil at 85 C) from 0 to ``t_end`` with ``solve_ivp``.

    Returns ``t``, ``p_clutch`` (Pa) and the state rows ``y`` on the 1 ms output grid,
    ``onset_time`` (s, first time the clutch torque exceeds 0.2 N m, or None), ``n_events``
    (terminal events handled), ``log`` ((time, event name) of each), the final state ``y_end``
    and ``nfev``. ``atol`` defaults to ``1e-3 rtol`` times the typical magnitude of each state.
    ``bookkeeping``: integrate the energy and oil-volume quadratures as the engine does (the
    same equations); without them the model is lighter than the engine's.
    """
    m = Rig()
    n_y = 18 if bookkeeping else 9
    atol = 1e-3 * rtol * SCALE[:n_y] if atol is None else atol
    grid = np.union1d(np.linspace(0.0, t_end, int(round(t_end / DT_OUT)) + 1), [min(T_STEP, t_end)])
    t, y = 0.0, np.zeros(n_y)
    y[W_P] = m.w_p0
    modes = (0, LOCKED, _stem_at_rest(m, y), _gear_at_rest(m, y, 0), 0)  # clutch open, road load held
    onset, log, k, nfev, stalls, out = None, [], 0, 0, 0, []
    for t_b, u in ((min(T_STEP, t_end), U0), (t_end, U1)):
        modes = (*modes[:4], _amp_mode(m.r, y, u))  # the input steps: the output stage's mode anew
        while t < t_b:
            named = _events(m, modes, onset is None, u, y)
            t_eval = grid[k : np.searchsorted(grid, t_b, side="right")]
            sol = solve_ivp(_rhs, (t, t_b), y, method=method, t_eval=t_eval, rtol=rtol, atol=atol,
                            events=[f for _, f in named], args=(m, modes, u))
            nfev += sol.nfev
            if len(sol.t):  # solve_ivp returns empty lists when no output time was reached
                out.append((sol.t, sol.y))
                k += len(sol.t)
            if named[0][0] == "onset" and sol.t_events[0].size:  # the only non-terminal event
                onset = float(sol.t_events[0][0])
            if sol.status != 1:  # reached t_b, which is on the output grid
                t, y = t_b, sol.y[:, -1].copy()
                continue
            j = next(j for j, (_, f) in enumerate(named) if f.terminal and sol.t_events[j].size)
            stalls = stalls + 1 if sol.t_events[j][0] <= t else 0
            if stalls > 20:
                raise RuntimeError(f"event loop stalled at t={t}")
            t, y = float(sol.t_events[j][0]), sol.y_events[j][0].copy()
            modes = _switch(m, named[j][0], y, modes, u)
            log.append((t, named[j][0]))
    t_out = np.concatenate([t for t, _ in out])
    y_out = np.concatenate([y.T for _, y in out])
    return dict(t=t_out, p_clutch=y_out[:, P], y=y_out, onset_time=onset, n_events=len(log), log=log, y_end=y,
                nfev=nfev)


def _engine_run(t_end, dt_out):
    """The engine's run of the same step (``wetclutch.sim.network.integrate``, its default tolerances)."""
    rn = clutch.build(wc.Params(), Step(T_STEP, U0, U1))
    return rn, integrate(rn.network, t_end, dt_out=dt_out)


if __name__ == "__main__":
    _engine_run(5.0, DT_OUT)  # JIT warm-up
    wall_e, (rn, tr) = median_time(lambda: _engine_run(5.0, DT_OUT), 3)
    p_eng = tr.x[:, rn.i_pressure]
    T_c = np.abs(_engine_run(1.5, 1e-5)[1].clutch_torque("clutch"))  # onset: interpolated on a 10 us grid
    n = np.argmax(T_c > ONSET)
    onset_eng = 1e-5 * (n - 1 + (ONSET - T_c[n - 1]) / (T_c[n] - T_c[n - 1]))
    ev_e = {name: tr.events[tr.events[:, 1] == j, 0] for j, name in enumerate(("contact", "brake", "stem"))}
    print(f"engine (rtol 1e-8): {wall_e * 1e3:.1f} ms/run (median of 3), {tr.stats['events']} events")
    for method in ("BDF", "LSODA"):
        wall, res = median_time(lambda method=method: actuator_step_scipy(method=method), 3)
        ev_s = {name: np.array([t for t, nm in res["log"] if nm.startswith(name)]) for name in ev_e}
        print(f"\nsolve_ivp {method} rtol 1e-6: {wall * 1e3:.0f} ms/run (median of 3, {wall / wall_e:.0f}x engine),"
              f" {res['nfev']} rhs calls, {res['n_events']} events\n    t [s]  p engine [Pa]  p scipy [Pa]  diff [Pa]")
        for tq in (1.2, 1.5, 3.0, 5.0):
            pe, ps = np.interp(tq, tr.t, p_eng), np.interp(tq, res["t"], res["p_clutch"])
            print(f"{tq:9.2f} {pe:14.1f} {ps:13.1f} {ps - pe:10.1f}")
        dp = np.abs(res["p_clutch"] - np.interp(res["t"], tr.t, p_eng))
        print(f"max |p diff| on the 1 ms grid: {dp.max():.1f} Pa at t = {res['t'][np.argmax(dp)]:.3f} s")
        print(f"torque onset: engine {onset_eng:.6f} s, scipy {res['onset_time']:.6f} s, "
              f"diff {(res['onset_time'] - onset_eng) * 1e6:+.1f} us")
        for name, what in (("contact", "plates touch"), ("brake", "road load releases")):
            print(f"{what}: engine {ev_e[name][0]:.6f} s, scipy {ev_s[name][0]:.6f} s")
        same = ev_e["stem"].size == ev_s["stem"].size
        print(f"stem stick/slip switches: engine {ev_e['stem'].size}, scipy {ev_s['stem'].size}" + (
            f", largest time difference {np.max(np.abs(ev_e['stem'] - ev_s['stem'])) * 1e3:.2f} ms" if same else ""))
        print(f"at 5 s: omega_p engine {tr.x[-1, 0]:.4f}, scipy {res['y_end'][W_P]:.4f}; "
              f"omega_s engine {tr.x[-1, 3]:.4f}, scipy {res['y_end'][W_S]:.4f} rad/s")
