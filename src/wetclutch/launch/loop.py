"""A controlled launch from standstill on the virtual rig.

The rig of :mod:`wetclutch.plant.clutch` (primary at 150 rad/s, secondary at rest,
brake as road load) runs in closed loop with a discrete controller of
:mod:`wetclutch.launch.controller`: every sample (1 kHz by default) the true signals
pass through the rig's sensor chain (:mod:`wetclutch.rig.sensors`: low-pass filter,
noise, quantisation, low-speed dropout), the controller computes the valve's DC input,
and the engine advances to the next sample. The whole loop runs compiled
(:func:`_closed_loop`); Python only prepares arrays and reads the results.

The clutch is in standby from t = 0; the torque request comes at
``t_request`` (1 s); the run goes on through synchronisation and stops
``t_after`` seconds after the clutch has locked for good (or at ``t_max``). With
``post_sync_hold`` the CVT's ratio moves after lock-up to hold the axle torque
(:mod:`wetclutch.launch.ratio_hold`), and the run goes on through the hold's time limit
(and up to :data:`HOLD_T_MAX` by default: a small request locks late).
"""

from __future__ import annotations

import csv
import functools
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from numba import njit
from scipy.optimize import brentq

from ..errors import (SimulationError, WetclutchError, check_flag, check_instance, check_integer, check_number,
                      kind_of, named)
from ..params import Params, check_oil_temp
from ..physics import actuator
from ..physics.friction import knee, normal_force
from ..plant import clutch
from ..rig.sensors import NOISE_STD, filter_sample, reading, sensor_table
from ..sim import coldstart
from ..sim.integrator import advance
from ..sim.network import Trajectory, failure, outputs
from ..sim.rhs import ratio, spring_torque
from ..sim.signals import External
from ..sim.workspace import IS_REJECTED, IS_SETTLE, IS_STEPS, LOCKED, OK, SETTLE_ALL, SETTLE_INPUT, new_workspace
from . import controller as control
from . import design as design_
from . import metrics, ratio_hold
from .adaptation import Adaptation

_jit = njit(cache=True, error_model="numpy")

PROFILES = ("step", "ramp")
RAMP_TIME = 0.3  # s: a ``ramp`` request rises over this time
N_CH = len(control.MEASURED)

#: where the loop finds the measured quantities: state indices (pressure, speeds), the axle spring and the CVT
#: gear, in the slots of the controller's measured channels (the oil temperature is a constant of the run)
N_PROBE = N_CH - 1
#: integration steps (accepted and rejected) a launch may take: a launch takes some 23 thousand; a plant that makes
#: the engine crawl (a valve stem or clutch chattering between stick and slip) ends as a failed launch, not a hang
MAX_STEPS = 3_000_000
#: the default relative tolerance of the plant's integration in a launch (:attr:`Conditions.rtol`)
RTOL = 1e-5
#: the absolute tolerance of the plant's integration (the valve stem's speed gets its own: ``RigNetwork.atol``)
ATOL = 1e-9
ERR_STEPS = -1
#: the loop has used every sensor-noise sample it was given (:data:`NOISE_CHUNK`)
NEED_NOISE = -2
#: seconds of sensor noise drawn at a time: a launch ends half a second after its clutch has locked, mostly long
#: before ``t_max``, and drawing all of ``t_max`` was some 3 % of a launch's time
NOISE_CHUNK = 4.0
#: the end of a run at the latest, s: :data:`T_MAX`, or HOLD_T_MAX with the post-sync hold, whose request may be
#: small enough to lock only after 10-20 s (25 N m on the built-in rig at 10.3 s, 15 N m at 18.6 s)
T_MAX = 12.0
HOLD_T_MAX = 60.0


def _probe(rn: clutch.RigNetwork) -> np.ndarray:
    net = rn.network
    body = {b.name: i for i, b in enumerate(net.bodies)}
    probe = np.zeros(N_PROBE, dtype=np.int64)
    probe[control.M_P] = rn.i_pressure
    probe[control.M_TR] = next(i for i, s in enumerate(net.springs) if s.name == "axle")
    probe[control.M_WP], probe[control.M_W1] = body["p"], body["1"]
    probe[control.M_WR], probe[control.M_WS] = body["r"], body["s"]
    probe[control.M_RATIO] = next(i for i, g in enumerate(net.gears) if g.name == "cvt")
    return probe


@_jit
def _true_values(net, x, probe, temp, truth):
    truth[control.M_P] = x[probe[control.M_P]]
    truth[control.M_TR] = spring_torque(net, probe[control.M_TR], x)[0]
    for c in (control.M_WP, control.M_W1, control.M_WR, control.M_WS):
        truth[c] = x[probe[c]]
    truth[control.M_RATIO] = ratio(x, net, probe[control.M_RATIO])
    truth[control.M_TEMP] = temp


def _cold_jobs(net, ext, ws) -> list[tuple[str, str, tuple]]:
    """What the closed loop compiles besides the integrator, for a first run's second process."""
    rec, meas = np.zeros(1), np.zeros(N_CH)
    return [coldstart.job(control.step, rec, np.zeros(control.N_CS), meas, 0.0),
            coldstart.job(ratio_hold.step, rec, np.zeros(ratio_hold.N_HS), meas, 0.0, False),
            coldstart.job(ratio_hold.valve, np.zeros(ratio_hold.N_HS), meas, 0.0, False),
            coldstart.job(_true_values, net, ws.x, np.zeros(N_PROBE, dtype=np.int64), 0.0, meas)]


coldstart.register(_cold_jobs)


@_jit
def _closed_loop(net, ext, ws, u_slot, probe, temp, sensors, noise, ctrl, cs, hold, hs, t_ref, dt, t_after, rtol, atol,
                 k0, zf, lock, out_t, out_x, out_aux, out_mode, out_meas, out_u):
    """Run the sampled loop from sample ``k0`` (with a ratio ``hold`` record, the CVT's ratio rate goes to the input
    slot after ``u_slot``); returns (status, number of samples). It stops with ``NEED_NOISE`` where the rows of
    ``noise`` end before the samples do, and goes on from there when called again with the next rows; what it
    carries over is in ``zf`` (the sensor filters' states) and ``lock`` (the time the clutch locked, -1: not)."""
    n = t_ref.shape[0]
    truth = np.zeros(N_CH)
    meas = np.zeros(N_CH)
    for k in range(k0, n):
        if k >= noise.shape[0]:
            return NEED_NOISE, k
        _true_values(net, ws.x, probe, temp, truth)
        for c in range(N_CH):
            v = filter_sample(sensors[c], zf[c], truth[c], k == 0)
            meas[c] = reading(sensors[c], v, noise[k, c])
            out_meas[k, c] = meas[c]
        u = control.step(ctrl, cs, meas, t_ref[k])
        if hold.shape[0] > 0:
            u = ratio_hold.valve(hs, meas, u, cs[control.CS_PHASE] == control.LOCKUP)
            ext[u_slot + 1] = ratio_hold.step(hold, hs, meas, t_ref[k], cs[control.CS_PHASE] >= control.TORQUE)
        out_u[k] = u
        ext[u_slot] = u
        # a new valve input alone moves no force at once; the ratio hold's rate moves the CVT's
        ws.istate[IS_SETTLE] = SETTLE_INPUT if hold.shape[0] == 0 and k > 0 else SETTLE_ALL
        status = advance(net, ext, ws, (k + 1) * dt, dt, 0.0, rtol, atol, np.inf, out_t, out_x, out_aux, out_mode)
        if status != OK:
            return status, k
        if ws.istate[IS_STEPS] + ws.istate[IS_REJECTED] > MAX_STEPS:
            return ERR_STEPS, k
        if ws.clm[0] == LOCKED:
            if lock[0] < 0.0:
                lock[0] = (k + 1) * dt
            elif (k + 1) * dt - lock[0] >= t_after:
                return OK, k + 1
        else:
            lock[0] = -1.0
    return OK, n


#: the requested axle torque a launch takes, N m (above the lower end, up to the upper end)
T_REF_RANGE_NM = (0.0, 1000.0)
#: the factor on the sensors' noise a launch takes (both ends included)
NOISE_SCALE_RANGE = (0.0, 10.0)


def condition_error(target: str, x: float, name: str | None = None) -> str | None:
    """Why a launch cannot take the value ``x`` of condition ``target``.

    Parameters
    ----------
    target : str
        ``oil_temp_C``, ``t_ref`` or ``noise_scale``.
    x : float
        The condition's value (oil temperature in C, request in N m, noise factor).
    name : str, optional
        What to call it in the sentence (default ``target``; the command line's option).

    Returns
    -------
    str or None
        One sentence naming the condition and its limits, or None if a launch takes ``x``.
    """
    name = name or target
    if target == "oil_temp_C":
        try:
            check_oil_temp(x, name)
        except WetclutchError as e:
            return str(e)
        return None
    if target == "t_ref":
        lo, hi = T_REF_RANGE_NM
        return None if lo < x <= hi else f"{name} must be in ({lo:g}, {hi:g}] N m (got {x:g})"
    lo, hi = NOISE_SCALE_RANGE
    return None if lo <= x <= hi else f"{name} must be in {lo:g}..{hi:g} (got {x:g})"


@dataclass(frozen=True)
class Conditions:
    """One launch: the request and the conditions it meets.

    Attributes
    ----------
    t_ref : float
        Requested axle torque ``T_r``, N m, of a ``step`` or ``ramp`` profile. A CSV profile gives its own
        request: another ``t_ref`` than the default beside it is refused.
    profile : str or Path
        ``step``, ``ramp`` (linear over :data:`RAMP_TIME`), or a CSV file with
        columns ``time`` (s, from the request) and ``t_ref`` (N m).
    oil_temp_C : float or None
        Oil temperature, C (None: the parameter set's ``rig.oil_temp_C``).
    t_request : float
        When the torque is requested, s into the run (the clutch in standby before it).
    t_after : float
        How long the run goes on after the clutch has locked for good, s.
    dt : float
        The controller's sample time, s (0.1..10 ms).
    seed : int
        Seed of the sensors' noise (>= 0); launch ``i`` of a sequence takes ``seed + i``.
    noise : bool
        Whether the sensors add noise (False: ideal readings).
    noise_scale : float
        Factor on every sensor's noise (0..10).
    post_sync_hold : bool
        Whether the CVT's ratio holds the axle torque after lock-up (:mod:`wetclutch.launch.ratio_hold`).
    hold_time : float
        The post-sync hold's time limit, s (0..60).
    t_max : float or None
        The end of the run at the latest, s (None: :data:`T_MAX`, or :data:`HOLD_T_MAX` with
        ``post_sync_hold``; see :attr:`horizon`). The run ends ``t_after`` after lock-up if that is sooner.
    rtol : float
        Relative tolerance of the plant's integration between controller samples. The closed loop
        (stick/slip, a valve stem with friction, sensor noise) carries any change at rounding level
        into shifts of a few ms: a launch at 1e-6 ends its slip up to 5 ms apart from one at 1e-8. At
        the default 1e-5 a launch's figures equal those at 1e-8 as closely (t95 within 2 ms, lock-up
        within 1.4 ms, overshoot within 0.05 points), and the figures of 800 sampled clutches are
        distributed as at 1e-6, in two thirds of the steps. At 1e-4 a sustained oscillation came out
        with a third less amplitude: too loose.
    """

    t_ref: float = 100.0
    profile: str = "step"
    oil_temp_C: float | None = None
    t_request: float = 1.0
    t_after: float = 0.5
    t_max: float | None = None
    dt: float = 1e-3
    seed: int = 0
    noise: bool = True
    noise_scale: float = 1.0
    post_sync_hold: bool = False
    hold_time: float = ratio_hold.HOLD_TIME
    rtol: float = RTOL

    @property
    def horizon(self) -> float:
        """The end of the run at the latest, s: ``t_max``, or by default :data:`T_MAX` (:data:`HOLD_T_MAX` with the
        post-sync hold)."""
        if self.t_max is not None:
            return self.t_max
        return HOLD_T_MAX if self.post_sync_hold else T_MAX

    def checked(self) -> Conditions:
        """These conditions with their numbers as Python numbers, or one line naming the first field a launch cannot
        take (its command-line option where the command line gave it: ``--t-ref``, else the field: ``t_ref``)."""
        def name(field_: str) -> str:
            return named(field_, _OPTIONS[field_]) if field_ in _OPTIONS else field_

        numbers = {f: check_number(getattr(self, f), name(f), _UNITS[f])
                   for f in ("t_ref", "t_request", "t_after", "dt", "noise_scale", "hold_time", "rtol")}
        for f in ("oil_temp_C", "t_max"):
            if getattr(self, f) is not None:
                numbers[f] = check_number(getattr(self, f), name(f), _UNITS[f])
        seed = check_integer(self.seed, name("seed"))
        flags = {f: check_flag(getattr(self, f), f) for f in ("noise", "post_sync_hold")}
        if not isinstance(self.profile, (str, os.PathLike)):
            raise WetclutchError(f"{name('profile')} must be step, ramp or a CSV file's path, not "
                                 f"{kind_of(self.profile)}")
        c = replace(self, **numbers, **flags, seed=seed)
        if (why := condition_error("t_ref", c.t_ref, name("t_ref"))) is not None:
            raise WetclutchError(why)
        if c.oil_temp_C is not None:
            check_oil_temp(c.oil_temp_C, name("oil_temp_C"))
        if c.profile not in PROFILES and not Path(c.profile).is_file():
            raise WetclutchError(f"{name('profile')} must be step, ramp or an existing CSV file (got '{c.profile}')")
        # the command line gives the default when --t-ref is left out (and refuses --t-ref beside a CSV profile
        # itself): only a request other than the default shows that one was given
        if c.profile not in PROFILES and c.t_ref != Conditions.t_ref:
            raise WetclutchError(f"{name('t_ref')} {c.t_ref:g} N m is given with {name('profile')} '{c.profile}', "
                                 f"which gives the request itself; leave {name('t_ref')} out")
        if c.seed < 0:
            raise WetclutchError(f"{name('seed')} must be >= 0 (got {c.seed})")
        if (why := condition_error("noise_scale", c.noise_scale, name("noise_scale"))) is not None:
            raise WetclutchError(why)
        if not 1e-4 <= c.dt <= 1e-2:
            raise WetclutchError(f"controller sample time dt must be in 0.1..10 ms "
                                 f"(got {c.dt * 1e3:g} ms)")
        if not 0.0 <= c.t_request <= 100.0:
            raise WetclutchError(f"t_request must be in 0..100 s (got {c.t_request:g})")
        if not 0.0 <= c.t_after <= 120.0:
            raise WetclutchError(f"t_after must be in 0..120 s (got {c.t_after:g})")
        if not c.t_request + 0.5 < c.horizon <= 120.0:
            raise WetclutchError(f"t_max must be in (t_request + 0.5, 120] s (got {c.horizon:g})")
        if not 0.0 < c.hold_time <= 60.0:
            raise WetclutchError(f"{name('hold_time')} must be in (0, 60] s (got {c.hold_time:g})")
        if not c.post_sync_hold and c.hold_time != ratio_hold.HOLD_TIME:
            raise WetclutchError(f"hold_time needs post_sync_hold=True (it limits that hold; got hold_time "
                                 f"{c.hold_time:g} without it)")
        if not 1e-10 <= c.rtol <= 1e-3:
            raise WetclutchError(f"rtol must be in 1e-10..1e-3 (got {c.rtol:g})")
        return c


#: the command-line options of the conditions that ``wetclutch launch`` sets, for its error messages
_OPTIONS = {"t_ref": "--t-ref", "oil_temp_C": "--oil-temp", "profile": "--profile", "seed": "--seed",
            "noise_scale": "--noise-scale", "hold_time": "--hold-time"}
#: the units of the conditions' numbers, for the error messages
_UNITS = {"t_ref": "N m", "oil_temp_C": "C", "t_request": "s", "t_after": "s", "t_max": "s", "dt": "s",
          "noise_scale": "", "hold_time": "s", "rtol": ""}


def reference(cond: Conditions, t: np.ndarray) -> np.ndarray:
    """The torque request on the sample times ``t`` (zero before the request)."""
    tau = t - cond.t_request
    if cond.profile == "step":
        r = np.full(t.size, cond.t_ref)
    elif cond.profile == "ramp":
        r = cond.t_ref * np.clip(tau / RAMP_TIME, 0.0, 1.0)
    else:
        where = f"{named('profile', '--profile')} {cond.profile}"
        # a first data row longer than the header makes pandas take the leading column for an index and shift the rest
        # under the wrong names, silently where that column counts 0, 1, 2 (a later long row fails to tokenize)
        if (malformed := _longer_than_header(cond.profile)) is not None:
            raise WetclutchError(f"{where}: {malformed}")
        try:
            f = pd.read_csv(cond.profile)
            tt = np.asarray(f["time"], dtype=float)
            rr = np.asarray(f["t_ref"], dtype=float)
        except (OSError, KeyError, ValueError, pd.errors.ParserError) as e:
            raise WetclutchError(f"{where}: needs numeric columns 'time' and 't_ref' ({type(e).__name__})") from None
        if tt.size < 2:
            raise WetclutchError(f"{where}: needs at least two rows (time, t_ref), has {tt.size}")
        for name, v in (("time", tt), ("t_ref", rr)):
            if not np.all(np.isfinite(v)):
                raise WetclutchError(f"{where}: '{name}' is not finite in data row {int(np.argmin(np.isfinite(v))) + 1}")
        if np.any(np.diff(tt) <= 0):
            raise WetclutchError(f"{where}: 'time' must increase (data row {int(np.argmax(np.diff(tt) <= 0)) + 2})")
        if np.any(rr < 0) or np.any(rr > 1000):
            raise WetclutchError(f"{where}: 't_ref' must be in 0..1000 N m")
        if not np.any(rr > 0):
            raise WetclutchError(f"{where}: 't_ref' is 0 throughout: no torque is requested")
        r = np.interp(tau, tt, rr)
    return np.where(tau >= 0.0, r, 0.0)


def _longer_than_header(path: str | os.PathLike) -> str | None:
    """The first line of CSV file ``path`` with more fields than its header, said in a few words, or None (no such
    line, or a file the csv module cannot read either: the caller's own message stands).

    Parameters
    ----------
    path : str or Path
        The profile's file.

    Returns
    -------
    str or None
        ``line 3 is malformed: it has 3 fields, the header 2``, or None.
    """
    try:
        with open(path, encoding="utf-8-sig", newline="") as fh:
            rows = csv.reader(fh)
            # pandas skips blank lines, before the header too
            header = next((row for row in rows if row), None)
            if header is None:
                return None
            for row in rows:
                if len(row) > len(header):
                    return f"line {rows.line_num} is malformed: it has {len(row)} fields, the header {len(header)}"
    except (OSError, UnicodeDecodeError, csv.Error):
        return None
    return None


@dataclass
class LaunchResult:
    """A launch: measured signals (plus ``t_ref`` and ``u``), true signals, and its figures.

    ``signals`` and ``truth`` are tables of ``signal_columns`` and ``truth_columns``, made when first read: a
    verification of a thousand launches reads only their figures.
    """

    signal_columns: dict[str, np.ndarray]
    truth_columns: dict[str, np.ndarray]
    summary: dict[str, Any]
    conditions: Conditions
    controller: str
    stats: dict[str, int] = field(default_factory=dict)
    kiss_found_Pa: float | None = None
    adaptation: Adaptation = field(default_factory=Adaptation)

    def __repr__(self) -> str:
        # a notebook shows this: the figures, not every sample of the signals
        s = self.summary
        fmt = lambda k, f: "-" if s.get(k) is None else format(s[k], f)  # noqa: E731
        failed = [k for k, ok in s.get("requirements", {}).items() if not ok]
        return (f"LaunchResult({self.controller}, t_ref {fmt('t_ref_Nm', 'g')} N m, oil {fmt('oil_temp_C', 'g')} C: "
                f"t95 {fmt('t95_settled_s', '.3f')} s (settled), overshoot {fmt('overshoot_pct', '.1f')} %, "
                f"error {fmt('steady_state_error_pct', '.2f')} %, creep {fmt('creep_Nm', '.1f')} N m, "
                f"lock-up {fmt('t_sync_s', '.2f')} s; "
                + ("all requirements met" if not failed else "fails " + ", ".join(failed))
                + f"; {len(self.signal_columns.get('time', ()))} samples)")

    @functools.cached_property
    def signals(self) -> pd.DataFrame:
        """The measured signals, ``t_ref`` and ``u`` on the controller's sample times."""
        return pd.DataFrame(self.signal_columns)

    @functools.cached_property
    def truth(self) -> pd.DataFrame:
        """The true signals on the same times."""
        return pd.DataFrame(self.truth_columns)


def _design(plant: Params, controller: design_.Design | str) -> design_.Design:
    if isinstance(controller, design_.Design):
        return controller
    if not isinstance(controller, str):
        raise WetclutchError(f"controller must be a design (wetclutch.launch.design.design(...)) or a kind "
                             f"({', '.join(design_.KINDS)}), not {kind_of(controller)}")
    if controller not in design_.KINDS:
        raise WetclutchError(f"unknown controller '{controller}' (choose from {', '.join(design_.KINDS)})")
    return design_.cached(plant, controller)


def _check_run(params: Params | None, conditions: Conditions | None, nominal: metrics.Response | None,
               adaptation: Adaptation | None) -> None:
    """Refuse arguments of a launch of the wrong kind (one line naming the argument)."""
    if params is not None:
        check_instance(params, Params, "params", "a parameter set (wetclutch.load_params(...)) or None")
    if conditions is not None:
        check_instance(conditions, Conditions, "conditions", "wetclutch.launch.Conditions(...) or None")
    if nominal is not None:
        check_instance(nominal, metrics.Response, "nominal", "a wetclutch.launch.metrics.Response or None")
    if adaptation is not None:
        check_instance(adaptation, Adaptation, "adaptation",
                       "a wetclutch.launch.adaptation.Adaptation (a launch result's .adaptation) or None")


def simulate(params: Params | None = None, controller: design_.Design | str = "launch",
             conditions: Conditions | None = None, nominal: metrics.Response | None = None,
             adaptation: Adaptation | None = None) -> LaunchResult:
    """Run one closed-loop launch.

    Parameters
    ----------
    params
        The plant as it really is (the study's defaults if None).
    controller
        A :class:`~wetclutch.launch.design.Design` (designed on any plant: a design
        running on a plant that differs from its own is what verification does), or a
        kind, ``launch`` or ``baseline``, to design on ``params`` itself.
    conditions
        Request, profile, oil temperature, noise seed.
    nominal
        The nominal launch's response, for the robustness requirement (default: the
        design on its own plant at that plant's oil temperature, interpolated between
        request levels as a verification judges it, :func:`nominal_grid`).
    adaptation
        What the launch controller learnt on earlier launches (default: nothing); the
        result carries the state after this launch.
    """
    _check_run(params, conditions, nominal, adaptation)
    p = params if params is not None else Params()
    d = _design(p, controller)
    if d.kind == "baseline" and adaptation is not None and adaptation != Adaptation():
        raise WetclutchError("adaptation: the baseline controller has no adaptation (pass none)")
    cond = (conditions or Conditions()).checked()
    temp = p.rig.oil_temp_C if cond.oil_temp_C is None else float(cond.oil_temp_C)
    ctrl = design_.record(d, cond.dt)
    hold = ratio_hold.pack(p, cond.dt, cond.hold_time) if cond.post_sync_hold else np.zeros(0)
    hs = ratio_hold.initial_state(p)
    rn = clutch.build(p, External(0), pwm=False, config="clutch", temp_C=temp,
                      ratio_rate=External(1) if cond.post_sync_hold else None)
    net, x0, ext = rn.network.compile()
    ws = new_workspace(net, x0)
    n = int(round(cond.horizon / cond.dt))
    t_grid = np.arange(n) * cond.dt
    t_ref = reference(cond, t_grid)
    probe = _probe(rn)
    sensors = sensor_table(control.MEASURED, 1.0 / cond.dt, noise=cond.noise, noise_scale=cond.noise_scale)
    rng = np.random.default_rng(cond.seed)
    chunk = int(round(NOISE_CHUNK / cond.dt))
    noise = rng.standard_normal((min(chunk, n), N_CH)) if cond.noise else np.zeros((n, N_CH))
    out = outputs(n, x0.size, ws.aux.size, len(rn.network.clutches))
    out_meas = np.zeros((n, N_CH))
    out_u = np.zeros(n)
    learnt = adaptation or Adaptation()
    start = learnt.kiss(temp) if d.kind == "launch" else None
    inertia = control.start_inertia(ctrl, learnt.inertia) if d.kind == "launch" else None
    margin = learnt.hold_margin(temp) if d.kind == "launch" else None
    cs = control.initial_state(d.settings["p_kiss"] if start is None else start, start is not None,
                               learnt.friction_factor(temp) if d.kind == "launch" else None,
                               learnt.friction_slope(temp) if d.kind == "launch" else None, inertia or 0.0,
                               margin or 0.0, learnt.inertia is not None)
    t_after = cond.t_after + (cond.hold_time if cond.post_sync_hold else 0.0)
    coldstart.begin(net, ext, ws)
    zf, lock, m = np.zeros((N_CH, 2)), np.full(1, -1.0), 0
    while True:
        status, m = _closed_loop(net, ext, ws, 0, probe, temp, sensors, noise, ctrl, cs, hold, hs, t_ref, cond.dt,
                                 t_after, cond.rtol, rn.atol(ATOL), m, zf, lock, *out, out_meas, out_u)
        if status != NEED_NOISE:
            break
        # the generator's stream goes on as if all of it had been drawn at once
        noise = np.concatenate([noise, rng.standard_normal((min(chunk, n - noise.shape[0]), N_CH))])
    if status == ERR_STEPS:
        raise SimulationError(f"launch simulation stopped at {m * cond.dt:.3f} s: more than {MAX_STEPS} integration "
                              "steps (the plant chatters between stick and slip)")
    if status != OK:
        raise SimulationError(f"launch simulation failed: {failure(rn.network, ws, status)}")
    tr = Trajectory.from_run(rn.network, ws, *out, m)
    m = tr.t.size
    signals = {"time": t_grid[:m], **{c: out_meas[:m, j] for j, c in enumerate(control.MEASURED)},
               "t_ref": t_ref[:m], "u": out_u[:m]}
    w_p = tr.speed("p")
    truth = {
        "time": tr.t,
        "p_clutch": tr.actuator_state(actuator.PRESSURE),
        "T_r": tr.spring_torque("axle"),
        "T_c": tr.clutch_torque("clutch"),
        "slip": w_p - tr.speed("1"),
        "omega_s": tr.speed("s"),
        "locked": tr.locked("clutch"),
        "E_clutch": tr.dissipated("clutch"),
        "T_plate": tr.plate_temperature(),
    }
    t_sync = tr.sync_time("clutch")
    resp = metrics.response(signals["time"], signals["T_r"], t_ref[:m], cond.t_request, t_sync, torque_noise(cond))
    if nominal is None:
        nominal = nominal_at(nominal_grid(d, cond.profile), cond.t_ref)
    summary = metrics.summary(resp, nominal, slip_energy=float(truth["E_clutch"][-1]), t_sync=t_sync,
                              contact=metrics.first_contact(tr.t, truth["T_c"], cond.t_request),
                              input_max=metrics.input_at_max(signals["time"], signals["u"], ctrl[control.U_MAX],
                                                             resp.window, signals["T_r"], signals["t_ref"]))
    judged = cond.t_ref
    if cond.profile not in PROFILES:
        # a CSV profile's request is its own: the one the response is judged against, over the steady window
        w = (signals["time"] >= resp.window[0]) & (signals["time"] <= resp.window[1])
        judged = float(np.mean(signals["t_ref"][w])) if np.any(w) else float(np.max(signals["t_ref"]))
    summary.update(controller=d.kind, t_ref_Nm=judged, profile=str(cond.profile), oil_temp_C=temp)
    t_peak, limit = float(np.max(truth["T_plate"])), p.thermal.T_plate_limit_C
    summary.update(T_plate_peak_C=t_peak, T_plate_limit_C=limit, T_plate_over_limit=bool(t_peak > limit))
    found = float(cs[control.CS_KISS]) if d.kind == "launch" and cs[control.CS_FOUND] else None
    # the learnt kiss point, unless the launch set it aside (``_dip_drains``) and started from the design's
    kiss_start = ((start if cs[control.CS_KISS_LEARNT] != 0.0 else d.settings["p_kiss"]) if d.kind == "launch"
                  else None)
    summary.update(kiss_start_Pa=kiss_start, kiss_found_Pa=found, hold_margin_Pa=margin,
                   limit_cycles_seen=int(cs[control.CS_LC_SEEN]) if d.kind == "launch" else None)
    friction = (float(cs[control.CS_THETA_LEARNT]) if d.kind == "launch" and cs[control.CS_THETA_N] >= control.THETA_LEARN_N
                else None)
    summary.update(friction_factor_start=learnt.friction_factor(temp) if d.kind == "launch" else None,
                   friction_factor_found=friction)
    if cond.post_sync_hold:
        signals["ratio"] = tr.ratio("cvt")
        summary.update(ratio_hold.summary(tr.t, truth["T_r"], t_ref[:m], signals["ratio"], t_sync, hs))
    slope = float(cs[control.CS_SLOPE_FOUND]) if d.kind == "launch" and np.isfinite(cs[control.CS_SLOPE_FOUND]) else None
    summary.update(friction_slope_start=learnt.friction_slope(temp) if d.kind == "launch" else None,
                   friction_slope_found=slope)
    measured = control.output_inertia(cs) if d.kind == "launch" else None
    summary.update(output_inertia_start_kg_m2=inertia, output_inertia_found_kg_m2=measured)
    summary.update(request_shaped=bool(cs[control.CS_SHAPED] != 0.0) if d.kind == "launch" else None)
    if found is not None:
        learnt = learnt.learn(temp, found, friction, slope, measured, control.crept(ctrl, cs, resp.creep_Nm))
    return LaunchResult(signals, truth, summary, cond, d.kind, tr.stats, found, learnt)


_NOMINAL: dict[tuple[str, Conditions], metrics.Response] = {}


def torque_noise(cond: Conditions) -> float:
    """Standard deviation (N m) of the white noise on the measured axle torque ``T_r`` in a launch under ``cond``:
    the sensor's, which the ripple does not count (:func:`wetclutch.launch.metrics.response`)."""
    return float(sensor_table(["T_r"], 1.0 / cond.dt, noise=cond.noise, noise_scale=cond.noise_scale)[0, NOISE_STD])


def nominal_response(d: design_.Design, cond: Conditions) -> metrics.Response:
    """The response of the design on its own plant (that plant's oil temperature, no noise seed change) to ``cond``'s
    request: one level of :func:`nominal_grid`, what the robustness requirement compares a launch with."""
    c = replace(cond, oil_temp_C=None, seed=0)
    key = (d.key(), c)
    if key not in _NOMINAL:
        res = simulate(d.plant, d, c, nominal=metrics.Response.empty())
        sig = res.signal_columns
        _NOMINAL[key] = metrics.response(sig["time"], sig["T_r"], sig["t_ref"], c.t_request, res.summary["t_sync_s"],
                                         torque_noise(c))
    return _NOMINAL[key]


#: the request levels (N m) of the nominal launches a launch is judged against, interpolated between
#: (:func:`nominal_grid`)
NOMINAL_LEVELS = np.array([25.0, 50.0, 100.0, 150.0, 200.0])
#: the nominal responses at :data:`NOMINAL_LEVELS`: settled t95 (s), overshoot (%), and the level (N m) whose
#: nominal launch each was taken from (:func:`nominal_grid`)
Grid = tuple[np.ndarray, np.ndarray, np.ndarray]


def nominal_grid(design: design_.Design, profile: str = "step") -> Grid:
    """Settled t95 and overshoot of the design's nominal launch at :data:`NOMINAL_LEVELS` (interpolated between);
    a CSV profile, which gives the request itself, has one nominal launch for every level.

    A level whose nominal launch does not settle takes the response of the nearest level that does
    (:func:`held_where_settled`): the design's own clutch synchronises before the judged window (a light primary
    flywheel or an overdrive CVT ratio at the largest requests) or cannot hold the request, while a sampled clutch
    (a lower ratio, more capacity) does; its launch is judged against the nominal's response where the nominal
    settles, not failed for the nominal's sake."""
    if profile not in PROFILES:
        rows = [nominal_response(design, Conditions(profile=profile))] * len(NOMINAL_LEVELS)
    else:
        rows = [nominal_response(design, Conditions(t_ref=float(lv), profile=profile))
                for lv in NOMINAL_LEVELS]
    return held_where_settled(np.array([r.t95_settled_s for r in rows]), np.array([r.overshoot_pct for r in rows]))


def held_where_settled(t95: np.ndarray, overshoot: np.ndarray) -> Grid:
    """The nominal responses at :data:`NOMINAL_LEVELS`, each level whose settled t95 is not finite (the launch never
    settled) taking the t95 and overshoot of the nearest level that settled, the lower one on a tie; the third
    array names the level each was taken from. With no level settled, all stay as they are (no launch passes the
    robustness requirement against them)."""
    t95, overshoot = np.array(t95, dtype=float), np.array(overshoot, dtype=float)
    source = NOMINAL_LEVELS.copy()
    settled = np.flatnonzero(np.isfinite(t95))
    if settled.size:
        for i in np.flatnonzero(~np.isfinite(t95)):
            j = settled[np.argmin(np.abs(settled - i) + 0.5 * (settled > i))]
            t95[i], overshoot[i], source[i] = t95[j], overshoot[j], NOMINAL_LEVELS[j]
    return t95, overshoot, source


def nominal_at(grid: Grid, t_ref: float) -> metrics.Response:
    """The nominal response a launch of request ``t_ref`` (N m) is judged against: ``grid`` (:func:`nominal_grid`)
    interpolated between its levels."""
    t95 = float(np.interp(t_ref, NOMINAL_LEVELS, grid[0]))
    ovs = float(np.interp(t_ref, NOMINAL_LEVELS, grid[1]))
    return replace(metrics.Response.empty(), t95_settled_s=t95, overshoot_pct=ovs)


def _open_loop(params: Params, conditions: Conditions, u: float, after: float = 0.0) -> Trajectory:
    """The plant with the valve input held at ``u`` from the start up to ``after`` (s) past the request (no
    controller)."""
    cond = conditions.checked()
    temp = params.rig.oil_temp_C if cond.oil_temp_C is None else float(cond.oil_temp_C)
    return clutch.run(params, u, cond.t_request + after, temp_C=temp, dt_out=cond.dt, rtol=cond.rtol, atol=ATOL)[1]


def fastest_contact(params: Params, conditions: Conditions, within: float = 0.0) -> float | None:
    """When the plates first touch (s from the request, negative before it) with the valve input at the top of its
    range from the start: the fastest fill the valve gives, whatever the controller. None: not up to ``within`` (s)
    after the request, so that no controller fills this clutch by then (``within`` 0: before torque is asked for;
    the response time asked for: no launch of this clutch answers in time)."""
    tr = _open_loop(params, conditions, design_.INPUT_RANGE["dc"][1], within)
    contact = metrics.first_contact(tr.t, tr.clutch_torque("clutch"), conditions.t_request)
    return contact if contact is not None and contact <= within else None


def open_plates_creep(params: Params, conditions: Conditions) -> float:
    """The creep (N m: the mean axle torque over the creep window before the request) with the valve input at the
    bottom of its range from the start: what the open plates' oil drag alone pushes into the waiting vehicle,
    whatever the controller."""
    tr = _open_loop(params, conditions, design_.INPUT_RANGE["dc"][0])
    return metrics.standby(tr.t, tr.spring_torque("axle"), conditions.t_request)[0]


def _pressed(p: np.ndarray, params: Params) -> np.ndarray:
    """``F_n knee(F_n)`` at clutch pressures ``p``: what the plates' torque is proportional to at a given slip and
    pack temperature (:mod:`wetclutch.physics.friction`)."""
    f_n = normal_force.py_func(np.asarray(p, dtype=float), actuator.contact_pressure(params), params.hydraulics.A_p)
    return f_n * knee.py_func(f_n, params.friction.F_knee)


def capacity_allows(params: Params, result: LaunchResult) -> bool:
    """Whether some launch on this clutch could meet the two requirements its capacity decides, the steady-state
    error and the ripple over the judged window, along ``result``'s slip.

    The plates' capacity ``T_cap(t)`` is that at the valve's highest static pressure ``p_max`` (input at the top of
    its range, at the launch's oil temperature): at the launch's slip and pack temperature the plates' torque is
    proportional to ``F_n knee(F_n)``, so it is the launch's clutch torque ``T_c`` times ``F_n knee(F_n)`` at
    ``p_max`` over the same at the launch's pressure, and at the axle ``eta / i`` of it (the clutch output's
    acceleration left out: in a launch at its capacity the axle torque and ``eta / i T_c`` differ by 0.01 % over the
    judged window). Of the torques under ``T_cap`` with a given mean over the window, the flat-topped
    ``min(T_cap, c)`` varies least, and its ripple grows with ``c`` (values within ``[0, c]`` about a mean ``m``
    vary by at most ``(c - m) m``, the Bhatia-Davis bound): the clutch allows the launch if the lowest level whose
    mean is within the steady-state error of the request has its ripple within the limit. A launch that gave the
    clutch more torque would have slipped less: where the friction falls as the slip falls, which is where a
    capacity sags, its friction would have been lower, so the test is, if anything, generous there. Where the plates
    do not slide under pressure (open, or locked) nothing bounds the torque."""
    w0, w1 = result.summary["steady_window_s"]
    sig, tr = result.signal_columns, result.truth_columns
    win = (sig["time"] >= w0) & (sig["time"] <= w1)
    ref = float(np.mean(sig["t_ref"][win])) if np.any(win) else 0.0
    if not metrics.judged_window(w0, w1) or not ref > 0.0:
        return True  # no steady state to judge
    p_max = clutch.static_pressure(params, design_.INPUT_RANGE["dc"][1], temp_C=result.summary["oil_temp_C"])
    pressed = _pressed(tr["p_clutch"], params)
    sliding = (pressed > 0.0) & (tr["locked"] == 0)
    scale = np.divide(_pressed(np.array([p_max]), params)[0], pressed, out=np.zeros_like(pressed), where=sliding)
    d = params.driveline
    cap = np.where(sliding, d.eta / d.ratio * tr["T_c"] * scale, np.inf)
    cap = np.interp(sig["time"][win], tr["time"], cap)
    err = metrics.REQ_ESS_PCT / 100.0
    top = max(float(np.max(cap[np.isfinite(cap)], initial=0.0)), (1.0 + err) * ref)

    def mean_at(c: float) -> float:
        return float(np.mean(np.minimum(cap, c)))

    if mean_at(top) < (1.0 - err) * ref:
        return False  # the mean falls short of the request whatever the shape
    lowest = brentq(lambda c: mean_at(c) - (1.0 - err) * ref, 0.0, top)
    return metrics.ripple_pct(np.minimum(cap, lowest)) <= metrics.REQ_RIPPLE_PCT


def sequence(params: Params, controller: design_.Design | str, conditions: Conditions, n: int,
             adaptation: Adaptation | None = None, nominal: metrics.Response | None = None) -> list[LaunchResult]:
    """``n`` launches of one clutch, the controller's adaptation carried from each to the next.

    Launch ``i`` runs with noise seed ``conditions.seed + i``; the last result's
    ``adaptation`` is the state after the sequence.
    """
    n = check_sequence(n, named("n", "--sequence"))
    _check_run(params, conditions, nominal, adaptation)
    conditions = (conditions if conditions is not None else Conditions()).checked()
    out: list[LaunchResult] = []
    learnt = adaptation
    for i in range(n):
        res = simulate(params, controller, replace(conditions, seed=conditions.seed + i), nominal, learnt)
        learnt = res.adaptation
        out.append(res)
    return out


def check_sequence(n: int, name: str = "--sequence") -> int:
    """``n`` if it is a sequence length (an integer in 1..100), else one line naming it ``name`` (the option, or
    the argument of a Python call)."""
    n = check_integer(n, name)
    if not 1 <= n <= 100:
        raise WetclutchError(f"{name} must be in 1..100 (got {n})")
    return n
