"""A controlled launch from standstill on the virtual rig (spec section 7).

The rig of :mod:`wetclutch.clutch` (primary at 150 rad/s, secondary at rest,
brake as road load) runs in closed loop with a discrete controller of
:mod:`wetclutch.control`: every sample (1 kHz by default) the true signals pass
through the rig's sensor chain (second-order Butterworth low-pass per channel,
white noise, quantisation, low-speed dropout, as :mod:`wetclutch.measurement`),
the controller computes the valve's DC input, and the engine advances to the
next sample. The whole loop runs compiled (:func:`_closed_loop`); Python only
prepares arrays and reads the results.

The clutch is in standby from t = 0; the torque request comes at
``t_request`` (1 s); the run goes on through synchronisation and stops
``t_after`` seconds after the clutch has locked for good (or at ``t_max``).
"""

from __future__ import annotations

import functools
import json
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from numba import njit
from scipy import signal as ss

from . import clutch, control, engine, measurement, metrics
from .errors import SimulationError, WetclutchError
from .network import new_workspace
from .params import Params
from .signals import External

_jit = njit(cache=True, error_model="numpy")

#: measured channels in the closed loop's order (control.M_*), SI; oil_temp in C
CHANNELS = ("p_clutch", "T_r", "omega_p", "omega_1", "omega_r", "omega_s", "oil_temp")
PROFILES = ("step", "ramp")
RAMP_TIME = 0.3  # s: a ``ramp`` request rises over this time


@_jit
def _closed_loop(net, ext, ws, u_slot, idx, phys, sensors, noise, ctrl, cs, t_ref, dt, t_after,
                 out_t, out_x, out_aux, out_mode, out_meas, out_u):
    """Run the sampled loop; returns (status, number of samples)."""
    n = t_ref.shape[0]
    n_ch = sensors.shape[0]
    truth = np.zeros(n_ch)
    meas = np.zeros(n_ch)
    zf = np.zeros((n_ch, 2))
    t_lock = -1.0
    for k in range(n):
        x = ws.x
        truth[0] = x[idx[0]]
        truth[1] = phys[0] * x[idx[5]] + phys[1] * (x[idx[3]] - x[idx[4]])
        truth[2] = x[idx[1]]
        truth[3] = x[idx[2]]
        truth[4] = x[idx[3]]
        truth[5] = x[idx[4]]
        truth[6] = phys[2]
        for c in range(n_ch):
            s = sensors[c]
            v = truth[c]
            if s[10] > 0.0:  # second-order section, transposed direct form II
                if k == 0:
                    zf[c, 0] = s[5] * v
                    zf[c, 1] = s[6] * v
                y = s[0] * v + zf[c, 0]
                zf[c, 0] = s[1] * v - s[3] * y + zf[c, 1]
                zf[c, 1] = s[2] * v - s[4] * y
                v = y
            dropout = s[9] > 0.0 and abs(v) < s[9]
            v += s[7] * noise[k, c]
            if s[8] > 0.0:
                v = np.round(v / s[8]) * s[8]
            meas[c] = 0.0 if dropout else v
            out_meas[k, c] = meas[c]
        u = control.step(ctrl, cs, meas, t_ref[k])
        out_u[k] = u
        ext[u_slot] = u
        ws.istate[0] = 1
        status = engine.advance(net, ext, ws, (k + 1) * dt, dt, 0.0, 1e-6, 1e-9, np.inf, out_t, out_x, out_aux, out_mode)
        if status != engine.OK:
            return status, k
        if ws.clm[0] == engine.LOCKED:
            if t_lock < 0.0:
                t_lock = (k + 1) * dt
            elif (k + 1) * dt - t_lock >= t_after:
                return engine.OK, k + 1
        else:
            t_lock = -1.0
    return engine.OK, n


def sensor_table(dt: float, noise: bool, sensors=measurement.DEFAULT_SENSORS, noise_scale: float = 1.0) -> np.ndarray:
    """Per channel: b0 b1 b2 a1 a2 zi0 zi1 noise_std resolution min_speed has_filter (see :func:`_closed_loop`)."""
    table = np.zeros((len(CHANNELS), 11))
    if not noise:
        return table
    for c, name in enumerate(CHANNELS):
        spec = sensors[name]
        if spec.cutoff_hz is not None and spec.cutoff_hz < 0.5 / dt:
            sos = ss.butter(2, spec.cutoff_hz, fs=1.0 / dt, output="sos")[0]
            table[c, :3] = sos[:3]
            table[c, 3:5] = sos[4:6]
            table[c, 5:7] = ss.sosfilt_zi(sos[None, :])[0]
            table[c, 10] = 1.0
        table[c, 7] = spec.noise_std * noise_scale
        table[c, 8] = spec.resolution
        table[c, 9] = spec.min_speed or 0.0
    return table


@dataclass(frozen=True)
class Conditions:
    """One launch: the request and the conditions it meets.

    Attributes
    ----------
    t_ref : float
        Requested axle torque ``T_r``, N m.
    profile : str or Path
        ``step``, ``ramp`` (linear over :data:`RAMP_TIME`), or a CSV file with
        columns ``time`` (s, from the request) and ``t_ref`` (N m).
    oil_temp_C : float or None
        Oil temperature, C (None: the parameter set's ``rig.oil_temp_C``).
    """

    t_ref: float = 100.0
    profile: str = "step"
    oil_temp_C: float | None = None
    t_request: float = 1.0
    t_after: float = 0.5
    t_max: float = 12.0
    dt: float = 1e-3
    seed: int = 0
    noise: bool = True
    noise_scale: float = 1.0

    def checked(self) -> Conditions:
        if not 0.0 < self.t_ref <= 1000.0:
            raise WetclutchError(f"--t-ref must be in (0, 1000] N m (got {self.t_ref:g})")
        if self.oil_temp_C is not None and not -30.0 <= self.oil_temp_C <= 150.0:
            raise WetclutchError(f"--oil-temp {self.oil_temp_C:g} C is outside -30..150 C")
        if self.profile not in PROFILES and not Path(self.profile).is_file():
            raise WetclutchError(f"--profile must be step, ramp or an existing CSV file (got '{self.profile}')")
        if self.seed < 0:
            raise WetclutchError(f"--seed must be >= 0 (got {self.seed})")
        if not 0.0 <= self.noise_scale <= 10.0:
            raise WetclutchError(f"--noise-scale must be in 0..10 (got {self.noise_scale:g})")
        if not 1e-4 <= self.dt <= 1e-2:
            raise WetclutchError(f"controller sample time must be in 0.1..10 ms (got {self.dt * 1e3:g} ms)")
        if not self.t_request + 0.5 < self.t_max <= 120.0:
            raise WetclutchError(f"t_max must be in (t_request + 0.5, 120] s (got {self.t_max:g})")
        return self


def reference(cond: Conditions, t: np.ndarray) -> np.ndarray:
    """The torque request on the sample times ``t`` (zero before the request)."""
    tau = t - cond.t_request
    if cond.profile == "step":
        r = np.full(t.size, cond.t_ref)
    elif cond.profile == "ramp":
        r = cond.t_ref * np.clip(tau / RAMP_TIME, 0.0, 1.0)
    else:
        try:
            f = pd.read_csv(cond.profile)
            tt = np.asarray(f["time"], dtype=float)
            rr = np.asarray(f["t_ref"], dtype=float)
        except (OSError, KeyError, ValueError, pd.errors.ParserError) as e:
            raise WetclutchError(f"--profile {cond.profile}: needs numeric columns 'time' and 't_ref' ({type(e).__name__})") from None
        if tt.size < 2 or not np.all(np.isfinite(tt)) or not np.all(np.isfinite(rr)) or np.any(np.diff(tt) <= 0):
            raise WetclutchError(f"--profile {cond.profile}: 'time' must increase and all values be finite")
        if np.any(rr < 0) or np.any(rr > 1000):
            raise WetclutchError(f"--profile {cond.profile}: 't_ref' must be in 0..1000 N m")
        r = np.interp(tau, tt, rr)
    return np.where(tau >= 0.0, r, 0.0)


def controller_record(name: str, params: Params, gains: Any = None, dt: float = 1e-3) -> np.ndarray:
    """The controller's flat record, designed on the nominal parameter set ``params``."""
    if name not in control.CONTROLLERS:
        raise WetclutchError(f"unknown controller '{name}' (choose from {', '.join(control.CONTROLLERS)})")
    if name == "pi":
        g = gains or control.PIGains()
        r = np.zeros(8)
        r[control.KIND] = control.PI
        r[control.KP_B], r[control.KI_B] = g.kp, g.ki
    else:
        g = gains or control.LaunchGains()
        f = params.friction
        poly = np.trim_zeros(np.asarray(f.mu_slip_poly, dtype=float), "f") * f.mu_scale
        if poly.size > 3:
            # the controller's friction law is quadratic (the study's fit); dropping terms would be silent
            raise WetclutchError(f"friction.mu_slip_poly: the launch controller takes at most a quadratic, "
                                 f"got {poly.size} coefficients")
        table = _feedforward(params)
        r = np.zeros(control.FF_TABLE + table.size)
        r[control.KIND] = control.LAUNCH
        h, d = params.hydraulics, params.driveline
        r[control.P_KISS] = clutch.p_contact(params)
        r[control.HOLD_OFFSET], r[control.FILL_EXIT], r[control.HOLD_RATE] = g.hold_offset, g.fill_exit, g.hold_rate
        r[control.A_P], r[control.RATIO], r[control.ETA] = h.A_p, d.ratio, d.eta
        mu = np.zeros(3)
        mu[3 - poly.size:] = poly
        r[control.MU2], r[control.MU1], r[control.MU0] = mu
        r[control.F_KNEE] = f.F_knee
        r[control.KP_P], r[control.KI_P] = g.kp_p, g.ki_p
        r[control.KP_T], r[control.KI_T], r[control.TAU_REF], r[control.TAU_THETA], r[control.THETA0] = g.kp_t, g.ki_t, g.tau_ref, g.tau_theta, g.theta0
        r[control.P_MAX] = min(h.p_supply, h.p_relief)
        r[control.DITHER_AMP], r[control.DITHER_HALF] = g.dither_amp, round(0.5 / (g.dither_hz * dt))
        r[control.KP_HOLD], r[control.HOLD_LEAD], r[control.FILL_EXIT_COLD] = g.kp_hold, g.hold_lead, g.fill_exit_cold
        r[control.DIP], r[control.DIP_N] = g.dip, round(g.dip_time / dt)
        r[control.KI_HOLD], r[control.REQ_LEAD] = g.ki_hold, g.req_lead
        r[control.DITHER_AMP_T], r[control.DITHER_HALF_T] = g.dither_amp_torque, round(0.5 / (g.dither_hz_torque * dt))
        r[control.FF_SHIFT_T] = g.ff_shift_torque * params.valve.I_hyst / params.valve.g_current
        T, P = control.MAP_TEMPS, control.MAP_PRESSURES
        r[control.FF_T0], r[control.FF_DT], r[control.FF_NT] = T[0], T[1] - T[0], T.size
        r[control.FF_P0], r[control.FF_DP], r[control.FF_NP] = P[0], P[1] - P[0], P.size
        r[control.FF_TABLE:] = table.ravel()
    r[control.DT] = dt
    r[control.U_MIN], r[control.U_MAX] = 0.2, 5.0  # the DC input range of the rig (rig.INPUT_RANGE)
    return r


def design_params(rig: Params) -> Params:
    """What the controller is designed on: the default rig at the rig's CVT ratio.

    The transmission controller commands the ratio, so it knows it; everything
    else (friction, fill, efficiency, stiffness, temperature) it must cope with.
    """
    d = Params()
    d.driveline.ratio = rig.driveline.ratio
    return d


def _feedforward(params: Params) -> np.ndarray:
    # keyed on the sections the static pressure map depends on, so that designs
    # differing only in the driveline share one table
    key = json.dumps({k: params.model_dump()[k] for k in ("valve", "hydraulics", "friction")}, sort_keys=True)
    return _feedforward_table(key)


@functools.lru_cache(maxsize=8)
def _feedforward_table(key: str) -> np.ndarray:
    params = Params.model_validate(json.loads(key))
    return control.inverse_map(control.static_map(params))


@dataclass
class LaunchResult:
    """A launch: measured signals (plus ``t_ref`` and ``u``), true signals, and its figures."""

    signals: pd.DataFrame
    truth: pd.DataFrame
    summary: dict[str, Any]
    conditions: Conditions
    controller: str
    stats: dict[str, int] = field(default_factory=dict)


def simulate(params: Params | None = None, controller: str = "launch", conditions: Conditions | None = None,
             design: Params | None = None, gains: Any = None, nominal: metrics.Response | None = None) -> LaunchResult:
    """Run one closed-loop launch.

    Parameters
    ----------
    params
        The rig as it really is (the study's defaults if None).
    controller
        ``launch`` or ``pi`` (see :mod:`wetclutch.control`).
    conditions
        Request, profile, oil temperature, noise seed.
    design
        The nominal parameter set the controller was designed on (default: the
        defaults). Verification runs a controller designed on the defaults
        against rigs that differ from them.
    nominal
        The nominal launch's response, for the robustness requirement (default:
        computed on ``design`` at the design oil temperature).
    """
    p = params if params is not None else Params()
    cond = (conditions or Conditions()).checked()
    temp = p.rig.oil_temp_C if cond.oil_temp_C is None else float(cond.oil_temp_C)
    ctrl = controller_record(controller, design or design_params(p), gains, cond.dt)
    rn = clutch.build(p, External(0), pwm=False, config="clutch", temp_C=temp)
    net, x0, ext = rn.network.compile()
    ws = new_workspace(net, x0)
    n = int(round(cond.t_max / cond.dt))
    t_grid = np.arange(n) * cond.dt
    t_ref = reference(cond, t_grid)
    body = {b.name: i for i, b in enumerate(rn.network.bodies)}
    nb = len(rn.network.bodies)
    axle = next(i for i, s in enumerate(rn.network.springs) if s.name == "axle")
    idx = np.array([rn.i_pressure, body["p"], body["1"], body["r"], body["s"], nb + axle], dtype=np.int64)
    phys = np.array([p.driveline.k_a, p.driveline.d_a, temp])
    sensors = sensor_table(cond.dt, cond.noise, noise_scale=cond.noise_scale)
    rng = np.random.default_rng(cond.seed)
    noise = rng.standard_normal((n, len(CHANNELS))) if cond.noise else np.zeros((n, len(CHANNELS)))
    out_t = np.zeros(n)
    out_x = np.zeros((n, x0.size))
    out_aux = np.zeros((n, ws.aux.size))
    out_mode = np.zeros((n, len(rn.network.clutches)), dtype=np.int64)
    out_meas = np.zeros((n, len(CHANNELS)))
    out_u = np.zeros(n)
    cs = np.zeros(control.N_CS)
    status, m = _closed_loop(net, ext, ws, 0, idx, phys, sensors, noise, ctrl, cs, t_ref, cond.dt, cond.t_after,
                             out_t, out_x, out_aux, out_mode, out_meas, out_u)
    if status != engine.OK:
        raise SimulationError(f"launch simulation failed at t = {ws.fstate[0]:.4g} s (status {status})")
    m = min(m, int(ws.istate[1]))
    signals = pd.DataFrame({"time": t_grid[:m], **{c: out_meas[:m, j] for j, c in enumerate(CHANNELS)},
                            "t_ref": t_ref[:m], "u": out_u[:m]})
    nc = len(rn.network.clutches)
    ng = len(rn.network.gears)
    e0 = nb + len(rn.network.springs)
    truth = pd.DataFrame({
        "time": out_t[:m],
        "p_clutch": out_x[:m, rn.i_pressure],
        "T_r": out_aux[:m, 2 * nc + ng + axle],
        "T_c": out_aux[:m, 0],
        "slip": out_x[:m, body["p"]] - out_x[:m, body["1"]],
        "omega_s": out_x[:m, body["s"]],
        "locked": (out_mode[:m, 0] == engine.LOCKED).astype(np.int8),
        "E_clutch": out_x[:m, e0],
    })
    ev = ws.evlog[: min(int(ws.istate[6]), ws.evlog.shape[0])]
    locks = ev[(ev[:, 1] == 0) & (ev[:, 2] == engine.LOCKED)]
    t_sync = float(locks[-1, 0]) if locks.size and out_mode[m - 1, 0] == engine.LOCKED else None
    resp = metrics.response(signals["time"].to_numpy(), signals["T_r"].to_numpy(), t_ref[:m], cond.t_request, t_sync)
    if nominal is None:
        nominal = nominal_response(controller, cond, gains)
    summary = metrics.summary(resp, nominal, slip_energy=float(truth["E_clutch"].iloc[-1]), t_sync=t_sync)
    summary.update(controller=controller, t_ref_Nm=cond.t_ref, profile=str(cond.profile), oil_temp_C=temp)
    stats = {"steps": int(ws.istate[2]), "rejected": int(ws.istate[3]), "events": int(ws.istate[4])}
    return LaunchResult(signals, truth, summary, cond, controller, stats)


@functools.lru_cache(maxsize=64)
def _nominal(controller: str, cond: Conditions, gains: Any) -> metrics.Response:
    res = simulate(Params(), controller, cond, gains=gains, nominal=metrics.Response.empty())
    return metrics.response(res.signals["time"].to_numpy(), res.signals["T_r"].to_numpy(),
                            res.signals["t_ref"].to_numpy(), cond.t_request, res.summary["t_sync_s"])


def nominal_response(controller: str, cond: Conditions, gains: Any = None) -> metrics.Response:
    """The response of the design rig (defaults, design oil temperature, same request) for comparison."""
    return _nominal(controller, replace(cond, oil_temp_C=None, seed=0), gains)


def write(result: LaunchResult, out: str | Path, params: Params) -> None:
    """``signals.csv``, ``truth.csv``, ``summary.json`` and ``plot.png`` of a launch, written atomically."""
    from .output import atomic_dir, write_json
    from .plotting import plot_launch

    with atomic_dir(out) as d:
        result.signals.to_csv(d / "signals.csv", index=False, float_format="%.8g")
        result.truth.to_csv(d / "truth.csv", index=False, float_format="%.8g")
        write_json(d / "summary.json", {**result.summary, "conditions": _jsonable(asdict(result.conditions)),
                                        "params": params.model_dump()})
        plot_launch(result.signals, result.truth, result.summary, d / "plot.png")


def _jsonable(d: dict[str, Any]) -> dict[str, Any]:
    return json.loads(json.dumps(d, default=str))
