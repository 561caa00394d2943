"""Identification: from measurement files back to the clutch's parameters (spec sections 3 to 6 and 8).

Each estimator is a function over the arrays of checked recordings
(:class:`wetclutch.channels.Recording`, SI units) that returns its value with a
standard error and the files and time windows it came from (an :class:`Estimate`,
or a small record per run). :func:`identify` runs all estimators that the
recordings support:

* torque onset after a command step: dead time and contact pressure (:func:`onset`);
* friction versus slip from the slip phase of clutch runs (:func:`friction`), also
  binned by pressure and by oil temperature;
* static pressure versus command on the plateaus of steps and staircases, with the
  hysteresis between up and down staircases (:func:`static_gain`, :func:`hysteresis`);
* low-order pressure models fitted to steps and relaxations (:func:`step_models`)
  and the frequency response from noise, multisine and chirp runs
  (:func:`frequency_response`), as python-control LTI objects;
* driveline resonance and damping from the ring-out after synchronisation (:func:`resonance`);
* validation of the friction law and of the pressure model on each file left out
  of the fit (:func:`wetclutch.validation.validate`).

The rig's sensors low-pass filter their signals (:data:`wetclutch.measurement.DEFAULT_SENSORS`,
assumed for any rig); each channel is advanced by its filter's low-frequency group
delay before channels are combined, so that fast transients do not pair a new
pressure with an old torque.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import control
import numpy as np
from scipy import signal
from scipy.ndimage import maximum_filter1d
from scipy.optimize import least_squares

from . import clutch
from .channels import Recording, command_changes
from .driveline import ring_frequency
from .errors import WetclutchError
from .measurement import DEFAULT_SENSORS
from .onset import first_crossing
from .params import Params

BAR = 1e5
SLIP_MIN = 10.0  # rad/s: below it the speed sensors' resolution spoils the slip (spec 1)
SETTLE = 0.8  # s: shortest constant command that counts as a static plateau
BROADBAND = ("noise", "multisine", "chirp")
#: entries of ``identified.json`` that are always written (null when the files do not support them)
REPORTED = ("mu_slip_poly", "contact_pressure_Pa", "valve_gain", "clutch_gain_poly_bar_per_V", "resonance_Hz",
            "damping_ratio")


@dataclass
class Estimate:
    """An identified quantity with its uncertainty and provenance.

    ``value`` and ``se`` (standard error; None where no error model applies) are
    floats or lists of floats in ``unit``; ``sources`` lists ``{file, t_start, t_end}``.
    """

    value: Any
    se: Any
    unit: str
    sources: list[dict[str, Any]] = field(default_factory=list)
    extra: dict[str, Any] = field(default_factory=dict)

    def as_json(self) -> dict[str, Any]:
        return {"value": self.value, "se": self.se, "unit": self.unit, **self.extra, "sources": self.sources}


def _source(rec: Recording, t0: float, t1: float) -> dict[str, Any]:
    return {"file": str(rec.path), "t_start": round(float(t0), 4), "t_end": round(float(t1), 4)}


def _inflation(resid: np.ndarray) -> float:
    """Variance inflation of a mean or a fit for AR(1)-correlated residuals, ``(1 + rho) / (1 - rho)``.

    Filtered sensor signals sampled faster than their bandwidth are not independent
    samples; ignoring that would understate every standard error.
    """
    if resid.size < 3 or not np.any(resid):
        return 1.0
    rho = float(np.clip(np.corrcoef(resid[:-1], resid[1:])[0, 1], 0.0, 0.99))
    return (1.0 + rho) / (1.0 - rho)


def _weighted_mean(values: np.ndarray, ses: np.ndarray) -> tuple[float, float]:
    """Inverse-variance mean and its standard error, widened by the scatter when that exceeds the SEs."""
    w = 1.0 / np.maximum(ses, 1e-12) ** 2
    m = float(np.sum(w * values) / np.sum(w))
    se = float(np.sqrt(1.0 / np.sum(w)))
    if values.size > 1:
        se = max(se, float(np.std(values, ddof=1) / np.sqrt(values.size)))
    return m, se


def _robust_std(x: np.ndarray) -> float:
    return float(1.4826 * np.median(np.abs(x - np.median(x)))) if x.size else 0.0


def aligned(rec: Recording) -> dict[str, np.ndarray]:
    """The recording's channels advanced by their sensor filters' group delay ``sqrt(2) / (2 pi f_c)``."""
    t = rec.t
    out = dict(rec.data)
    for ch, x in rec.data.items():
        spec = DEFAULT_SENSORS.get(ch)
        if spec is not None and spec.cutoff_hz is not None and ch != "oil_temp":
            out[ch] = np.interp(t + np.sqrt(2.0) / (2.0 * np.pi * spec.cutoff_hz), t, x)
    return out


def _smooth(x: np.ndarray, n: int) -> np.ndarray:
    return np.convolve(x, np.ones(n) / n, mode="same") if n > 1 else x


# ---------------------------------------------------------------- segments of a command


@dataclass(frozen=True)
class Plateau:
    """A stretch of constant command and the settled pressure at its end."""

    rec: Recording
    u: float
    p: float  # Pa
    se: float  # Pa
    direction: str  # "first", "up" or "down"
    t0: float
    t1: float


def plateaus(rec: Recording) -> list[Plateau]:
    """Static pressures on the constant-command stretches (at least :data:`SETTLE` long) of a step-like run."""
    if rec.experiment in BROADBAND:
        return []
    t, u, p = rec.t, rec.data["u"], rec.data["p_clutch"]
    edges = np.concatenate([[0], command_changes(t, u), [t.size]])
    out: list[Plateau] = []
    prev_u = None
    for a, b in zip(edges[:-1], edges[1:]):
        # settle past the ramp of the change, then average the last 40 %
        level = float(np.median(u[a:b]))
        if t[b - 1] - t[a] >= SETTLE:
            k = a + int(0.6 * (b - a))
            seg = p[k:b]
            se = float(np.std(seg) / np.sqrt(seg.size) * np.sqrt(_inflation(seg - seg.mean())))
            direction = "first" if prev_u is None else ("up" if level > prev_u else "down")
            out.append(Plateau(rec, level, float(seg.mean()), se, direction, float(t[k]), float(t[b - 1])))
        prev_u = level
    return out


# ---------------------------------------------------------------- onset: dead time, contact pressure


@dataclass(frozen=True)
class Onset:
    """Torque onset after a rising command step of one clutch run."""

    rec: Recording
    t_command: float
    dead_time: float
    dead_time_se: float
    p_contact: float
    p_contact_se: float
    level: float  # command after the step
    baseline: float  # T_r before the onset (oil drag through the CVT), N m
    noise: float  # T_r noise, N m
    slip0: float  # slip before the onset, rad/s


def onset(rec: Recording) -> Onset | None:
    """Dead time (command step to torque onset) and contact pressure of a clutch step run.

    The torque onset is where ``T_r`` (delay-compensated) first rises 8 noise
    standard deviations above its level before the step. After the plates touch
    the pressure jumps within a few milliseconds (the piston stops, the oil
    volume is stiff), so the pressure at the onset is the end of the slow stroke
    phase: a straight line fitted to the pressure from 60 ms to 5 ms before the
    onset (clear of the jump) and evaluated at the onset. This avoids reading the pressure on its steep flank,
    where one sample of jitter would be worth tenths of a bar.
    """
    if rec.config != "clutch" or rec.experiment != "step":
        return None
    d = aligned(rec)
    t, u, p, T = rec.t, d["u"], d["p_clutch"], d["T_r"]
    changes = command_changes(t, u)
    if changes.size == 0 or u[changes[0]] <= u[changes[0] - 1]:
        return None
    k_cmd = int(changes[0])
    pre = (t > t[k_cmd] - 0.5) & (t < t[k_cmd])
    if np.count_nonzero(pre) < 20:
        return None
    base, noise = float(np.median(T[pre])), max(_robust_std(T[pre]), 1e-3)
    crossing = first_crossing(t, T - base, 8.0 * noise, start=k_cmd)
    if crossing is None:
        return None
    t_on, k_on, _ = crossing
    dt = rec.dt
    # the stroke line: 60 ms to 5 ms before the (interpolated) onset, clear of the jump
    w = (t > t_on - 0.06) & (t < t_on - 0.005) & (t > t[k_cmd])
    if np.count_nonzero(w) < 10:
        return None
    coef, cov = np.polyfit(t[w] - t_on, p[w], 1, cov=True)
    p_c, p_c_se = float(coef[1]), float(np.sqrt(cov[1, 1]))
    slope_T = (T[k_on] - T[k_on - 1]) / dt
    t_se = float(np.hypot(dt / np.sqrt(12.0), noise / max(slope_T, 1e-9)))
    slip = d["omega_p"] - d["omega_1"]
    level = float(u[min(k_cmd + 5, t.size - 1)])
    return Onset(rec, float(t[k_cmd]), t_on - float(t[k_cmd]), t_se, p_c, p_c_se, level, base, noise,
                 float(np.median(slip[pre])))


# ---------------------------------------------------------------- friction versus slip


@dataclass
class SlipSamples:
    """Friction samples of the slip phase of one clutch run."""

    rec: Recording
    slip: np.ndarray  # rad/s
    mu: np.ndarray  # m
    p: np.ndarray  # Pa
    T_r: np.ndarray  # N m, measured
    factor: np.ndarray  # T_r per unit mu: eta / i * F_n * knee(F_n)
    offset: np.ndarray  # T_r of the oil drag, N m
    ratio: float
    t0: float
    t1: float


def measured_ratio(rec: Recording) -> tuple[float, float]:
    """CVT ratio ``omega_r / omega_1`` (median where ``omega_1`` is well measured) and its standard error."""
    w1, wr = rec.data["omega_1"], rec.data["omega_r"]
    ok = w1 > 20.0
    if np.count_nonzero(ok) < 20:
        return float("nan"), float("nan")
    r = wr[ok] / w1[ok]
    m = float(np.median(r))
    return m, float(1.2533 * np.std(r) / np.sqrt(r.size) * np.sqrt(_inflation(r - m)))


def slip_samples(rec: Recording, prior: Params, p_contact: float, on: Onset | None) -> SlipSamples | None:
    """Friction coefficient samples ``mu = T_c / (F_n knee(F_n))`` of the slip phase.

    ``T_c = T_r i / eta - d_drag slip`` with ``i`` the measured ratio, ``eta`` the
    prior efficiency (forward power flow: before synchronisation) and ``d_drag``
    the oil drag seen before the onset; ``F_n = (p - p_contact) A_p`` with the
    prior piston area. The model's friction drops at low normal force by the
    knee ``F_n / (F_n + F_knee)``; it is divided out with the prior ``F_knee``,
    and only samples with ``F_n > F_knee`` (knee factor above 1/2) are kept, so
    that an error in ``F_knee`` moves ``mu`` little. Also left out: slip below
    :data:`SLIP_MIN`, small or negative torque, and transients (fast changes of
    pressure or of the CVT input speed, which the sensors' filters smear).
    """
    if rec.config != "clutch":
        return None
    ratio, _ = measured_ratio(rec)
    if not np.isfinite(ratio):
        return None
    d = aligned(rec)
    t, p, T = rec.t, d["p_clutch"], d["T_r"]
    dr, h, fr = prior.driveline, prior.hydraulics, prior.friction
    slip = d["omega_p"] - d["omega_1"]
    n = max(1, int(round(0.01 / rec.dt)))
    dp = np.abs(np.gradient(_smooth(p, n), t))
    dw = np.abs(np.gradient(_smooth(d["omega_1"], n), t))
    # 50 ms either side of a transient is spoiled too
    span = 2 * int(round(0.05 / rec.dt)) + 1
    calm = (maximum_filter1d(dp, span) < 20.0 * BAR) & (maximum_filter1d(dw, span) < 500.0)
    f_n = (p - p_contact) * h.A_p
    noise = on.noise if on is not None else _robust_std(np.diff(T)) / np.sqrt(2.0)
    ok = calm & (slip > SLIP_MIN) & (f_n > max(fr.F_knee, 1.0)) & (T > max(10.0 * noise, 0.05 * np.max(T)))
    if on is not None:
        ok &= t > on.t_command + on.dead_time
    if np.count_nonzero(ok) < 20:
        return None
    drag = on.baseline * ratio / dr.eta / on.slip0 if on is not None and on.slip0 > SLIP_MIN else 0.0
    knee = f_n[ok] / (f_n[ok] + fr.F_knee)
    factor = dr.eta / ratio * f_n[ok] * knee
    offset = dr.eta / ratio * drag * slip[ok]
    mu = (T[ok] - offset) / factor
    return SlipSamples(rec, slip[ok], mu, p[ok], T[ok], factor, offset, ratio, float(t[ok][0]), float(t[ok][-1]))


def fit_mu(samples: Sequence[SlipSamples], order: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Least-squares ``mu(slip)`` polynomial (highest power first), its covariance and the residual RMS."""
    slip = np.concatenate([s.slip for s in samples])
    mu = np.concatenate([s.mu for s in samples])
    if slip.size <= order + 1:
        raise WetclutchError(f"too few slip samples ({slip.size}) for a mu polynomial of order {order}")
    X = np.vander(slip, order + 1)
    coef, *_ = np.linalg.lstsq(X, mu, rcond=None)
    resid = mu - X @ coef
    # residuals are correlated in time within each file (filtered sensors): inflate per file
    infl = float(np.mean(np.concatenate([np.full(s.slip.size, _inflation(s.mu - np.vander(s.slip, order + 1) @ coef))
                                         for s in samples])))
    s2 = float(resid @ resid) / (slip.size - order - 1)
    cov = s2 * infl * np.linalg.pinv(X.T @ X)
    return coef, cov, float(np.sqrt(np.mean(resid**2)))


def friction(samples: Sequence[SlipSamples], order: int = 2) -> Estimate:
    """``mu(slip)`` polynomial with standard errors, plus ``mu`` binned by pressure and by oil temperature."""
    coef, cov, rms = fit_mu(samples, order)
    p = np.concatenate([s.p for s in samples])
    mu = np.concatenate([s.mu for s in samples])
    edges = np.arange(np.floor(p.min() / (0.5 * BAR)), np.ceil(p.max() / (0.5 * BAR)) + 1) * 0.5 * BAR
    which = np.digitize(p, edges) - 1
    by_p = [{"p_bar": [float(edges[k] / BAR), float(edges[k + 1] / BAR)], "mu": float(mu[which == k].mean()),
             "se": float(mu[which == k].std() / np.sqrt(np.count_nonzero(which == k))), "n": int(np.count_nonzero(which == k))}
            for k in range(edges.size - 1) if np.count_nonzero(which == k) >= 20]
    temps = np.concatenate([np.full(s.mu.size, 5.0 * round(s.rec.oil_temp_C / 5.0)) for s in samples])
    by_t = [{"oil_temp_C": float(T), "mu": float(mu[temps == T].mean()),
             "se": float(mu[temps == T].std() / np.sqrt(np.count_nonzero(temps == T))), "n": int(np.count_nonzero(temps == T))}
            for T in np.unique(temps)]
    return Estimate(
        [float(c) for c in coef], [float(s) for s in np.sqrt(np.diag(cov))], "m (slip in rad/s, highest power first)",
        [_source(s.rec, s.t0, s.t1) for s in samples],
        {"order": order, "residual_rms": rms, "n_samples": int(mu.size),
         "slip_range": [float(min(s.slip.min() for s in samples)), float(max(s.slip.max() for s in samples))],
         "covariance": cov.tolist(), "by_pressure": by_p, "by_temperature": by_t},
    )


# ---------------------------------------------------------------- static gains, hysteresis


def static_gain(points: Sequence[Plateau], order: int) -> Estimate | None:
    """Polynomial of static pressure (bar) versus command over plateaus, mid-range only.

    Left out: plateaus below 0.2 bar (the pressure sensor is too insensitive there,
    spec 6) and a saturated top, where several commands give the same pressure
    (within 3 %) as the highest (the valve wide open).
    """
    p = np.array([q.p for q in points]) / BAR
    u = np.array([q.u for q in points])
    if p.size == 0:
        return None
    top = p >= 0.97 * p.max()
    keep = (p > 0.2) & ~(top if np.unique(np.round(u[top], 6)).size > 1 else np.zeros_like(top))
    order = min(order, np.unique(np.round(u[keep], 6)).size - 1)
    if order < 1:
        return None
    se = np.maximum(np.array([q.se for q in points])[keep] / BAR, 1e-4)
    coef, cov = np.polyfit(u[keep], p[keep], order, w=1.0 / se, cov="unscaled") if keep.sum() > order + 1 else (
        np.polyfit(u[keep], p[keep], order), np.full((order + 1, order + 1), np.nan))
    resid = p[keep] - np.polyval(coef, u[keep])
    # the plateaus' own noise understates the scatter about a smooth curve: scale by the fit's chi^2 if larger
    dof = keep.sum() - order - 1
    if dof > 0:
        cov = cov * max(1.0, float(np.sum((resid / se) ** 2)) / dof)
    return Estimate([float(c) for c in coef], [float(s) for s in np.sqrt(np.diag(cov))], "bar per command^k",
                    [_source(q.rec, q.t0, q.t1) for q in np.array(points, dtype=object)[keep]],
                    {"order": int(order), "points": [[float(a), float(b)] for a, b in zip(u[keep], p[keep])],
                     "range_bar": [float(p.min()), float(p.max())]})


def hysteresis(points: Sequence[Plateau]) -> Estimate | None:
    """Largest and mean difference between up and down plateaus at the same command (bar)."""
    up = [q for q in points if q.direction in ("up", "first")]
    down = [q for q in points if q.direction == "down"]
    span = max((q.u for q in points), default=0.0) - min((q.u for q in points), default=0.0)
    pairs = [(a, b) for a in up for b in down if a.rec is b.rec and abs(a.u - b.u) <= 1e-3 * max(span, 1e-9)]
    if not pairs:
        return None
    diff = np.array([(a.p - b.p) / BAR for a, b in pairs])
    ses = np.array([np.hypot(a.se, b.se) / BAR for a, b in pairs])
    k = int(np.argmax(np.abs(diff)))
    return Estimate(float(abs(diff[k])), float(ses[k]), "bar",
                    [_source(a.rec, min(a.t0, b.t0), max(a.t1, b.t1)) for a, b in pairs],
                    {"mean_bar": float(np.mean(diff)), "at_command": float(pairs[k][0].u),
                     "pairs": [[float(a.u), float(a.p / BAR), float(b.p / BAR)] for a, b in pairs]})


# ---------------------------------------------------------------- pressure dynamics


def _step_poles(poles: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit step and impulse response of ``prod(-p) / prod(s - p)`` (distinct poles) at ``t >= 0``.

    Partial fractions: ``h(t) = sum r_k e^(p_k t)``, step ``1 + sum r_k / p_k e^(p_k t)``.
    """
    poles = np.asarray(poles, dtype=complex)
    diff = poles[:, None] - poles[None, :]
    np.fill_diagonal(diff, 1.0)
    residues = np.prod(-poles) / np.prod(diff, axis=1)
    e = np.exp(np.outer(t, poles))
    return 1.0 + (e @ (residues / poles)).real, (e @ residues).real


def _poles(order: int, x: np.ndarray) -> np.ndarray:
    """Poles of the model parameters ``x`` (after gain and dead time): tau; w, zeta; tau_coil, w, zeta."""
    if order == 1:
        return np.array([-1.0 / x[0]])
    w, z = x[-2], x[-1]
    # a tiny offset keeps the two poles distinct at critical damping
    root = np.sqrt(complex(z * z - 1.0 + 1e-9))
    pair = np.array([-z * w + w * root, -z * w - w * root])
    return pair if order == 2 else np.concatenate([[-1.0 / x[0] * (1 + 1e-7)], pair])


MODEL_NAMES = {1: "first order plus dead time", 2: "second order plus dead time", 3: "third order plus dead time (valve)"}


@dataclass
class StepModel:
    """A low-order pressure model ``K e^(-theta s) G(s)`` (``G(0) = 1``) fitted to one step or relaxation."""

    rec: Recording
    order: int
    gain: float  # Pa per command unit
    theta: float  # s
    params: dict[str, float]
    se: dict[str, float]
    vaf: float  # %
    t0: float
    t1: float
    fit: tuple[np.ndarray, np.ndarray, np.ndarray] = field(repr=False, default=None)  # t, measured, model

    def lti(self) -> control.TransferFunction:
        """``K G(s)`` as a python-control transfer function (the dead time is :attr:`theta`)."""
        poles = _poles(self.order, np.array(list(self.params.values())))
        den = np.real(np.poly(poles))
        return control.tf([self.gain * den[-1]], den)

    def as_json(self) -> dict[str, Any]:
        sys_ = self.lti()
        return {"model": MODEL_NAMES[self.order], "gain_bar_per_unit": self.gain / BAR, "dead_time_s": self.theta,
                **self.params, "se": self.se, "vaf_percent": self.vaf,
                "num": np.ravel(sys_.num[0][0]).tolist(), "den": np.ravel(sys_.den[0][0]).tolist(),
                "source": _source(self.rec, self.t0, self.t1)}


def step_models(rec: Recording, orders: Sequence[int] | None = None) -> list[StepModel]:
    """Fit first and second order plus dead time (and third order for the valve alone) to a step or relaxation.

    The window runs from the command change until 0.5 s after the response's rise
    (at most 4 s); the fit is nonlinear least squares on the
    pressure change, and the standard errors come from its Jacobian.
    """
    if rec.experiment not in ("step", "relaxation"):
        return []
    t, u, p = rec.t, rec.data["u"], rec.data["p_clutch"]
    changes = command_changes(t, u)
    if changes.size == 0:
        return []
    k = int(changes[0])
    pre = t < t[k]
    end = np.flatnonzero(t <= t[k] + 4.0)[-1] + 1
    if np.count_nonzero(pre) < 10 or end - k < 50:
        return []
    p0, u0, u1 = float(np.median(p[pre][-200:])), float(np.median(u[pre])), float(np.median(u[k:end]))
    tt, yy = t[k:end] - t[k], p[k:end] - p0
    du = u1 - u0
    y_end = float(np.median(yy[-(end - k) // 5:]))
    orders = orders or ((1, 2) if rec.config == "clutch" else (1, 2, 3))
    # start values from the data, as for a first-order lag: t(f) = theta + tau ln(1 / (1 - f)) at 30 % and 80 %
    reach = lambda f: float(tt[np.argmax(np.abs(yy) > f * abs(y_end))]) if abs(y_end) > 0 else 0.0  # noqa: E731
    tau0 = float(np.clip((reach(0.8) - reach(0.3)) / np.log(0.7 / 0.2), 2e-3, 5.0))
    theta0 = max(reach(0.3) - tau0 * np.log(1 / 0.7), 0.0)
    # the rise and its settling at full rate: on a coarser grid the cost would be flat between dead times
    span = tt < theta0 + 10.0 * tau0 + 0.5
    stride = max(1, int(np.count_nonzero(span)) // 300)
    tt, yy = tt[span][::stride], yy[span][::stride]
    out = []
    for order in orders:
        # z = [gain, dead time, log of the positive shape parameters]: unconstrained, so that the fast
        # Levenberg-Marquardt solver applies (a fit per step in a campaign of hundreds)
        def model(z: np.ndarray, order: int = order) -> np.ndarray:
            return z[0] * _step_poles(_poles(order, np.exp(z[2:])), np.maximum(tt - z[1], 0.0))[0]

        def jac(z: np.ndarray, order: int = order) -> np.ndarray:
            # gain and dead time analytically (the impulse response), the shape by forward differences
            s = np.maximum(tt - z[1], 0.0)
            step, impulse = _step_poles(_poles(order, np.exp(z[2:])), s)
            cols = [step, -z[0] * impulse * (s > 0)]
            for j in range(2, z.size):
                dz = np.zeros_like(z)
                dz[j] = 1e-6
                cols.append(z[0] * (_step_poles(_poles(order, np.exp(z[2:] + dz[2:])), s)[0] - step) / 1e-6)
            return np.column_stack(cols)

        res = None
        # a well-damped and, if that fits poorly, a ringing start: the dead time makes the cost surface bumpy
        for zeta0 in (0.7, 0.15) if order > 1 else (None,):
            shape = {1: [tau0], 2: [2.0 / tau0, zeta0], 3: [tau0 / 4, 3.0 / tau0, zeta0]}[order]
            try:
                r = least_squares(lambda z: model(z) - yy, np.array([y_end, theta0, *np.log(shape)]), jac=jac,
                                  method="lm", x_scale="jac", ftol=1e-6, xtol=1e-6, max_nfev=400)
            except (ValueError, np.linalg.LinAlgError):
                continue
            if np.all(np.isfinite(r.x)) and (res is None or r.cost < res.cost):
                res = r
            if res is not None and res.cost < 0.05 * 0.5 * float(np.sum((yy - yy.mean()) ** 2)):
                break  # VAF above 95 %: the ringing start would not pay
        if res is None:
            continue
        resid = res.fun
        vaf = float(100.0 * (1.0 - np.var(resid) / max(np.var(yy), 1e-30)))
        dof = max(tt.size - res.x.size, 1)
        cov = np.linalg.pinv(res.jac.T @ res.jac) * float(resid @ resid) / dof * _inflation(resid)
        se = np.sqrt(np.abs(np.diag(cov)))
        shape = np.exp(res.x[2:])
        names = {1: ["tau_s"], 2: ["omega_n_rad_s", "zeta"], 3: ["tau_coil_s", "omega_n_rad_s", "zeta"]}[order]
        params = dict(zip(names, (float(v) for v in shape)))
        ses = {"gain_bar_per_unit": float(se[0] / BAR / abs(du)) if du else None, "dead_time_s": float(se[1]),
               **dict(zip(names, (float(v) for v in shape * se[2:])))}  # d exp(z) = exp(z) dz
        out.append(StepModel(rec, order, float(res.x[0] / du) if du else float("nan"), float(res.x[1]), params, ses,
                             vaf, float(t[k]), float(t[end - 1]), (tt + t[k], yy + p0, model(res.x) + p0)))
    return out


@dataclass
class FrequencyResponse:
    """Frequency response command -> pressure of one broadband run, and a parametric fit to it."""

    rec: Recording
    freq: np.ndarray  # Hz
    H: np.ndarray  # Pa per command unit
    coherence: np.ndarray
    rel_se: np.ndarray  # standard error of |H| relative to |H|
    model: control.TransferFunction
    theta: float
    model_params: dict[str, float]
    model_se: dict[str, float]

    def frd(self) -> control.FrequencyResponseData:
        """The measured frequency response as a python-control FRD object (rad/s)."""
        return control.frd(self.H, 2 * np.pi * self.freq)

    def model_response(self, f: np.ndarray) -> np.ndarray:
        return np.asarray(self.model(2j * np.pi * f)) * np.exp(-2j * np.pi * f * self.theta)

    def as_json(self) -> dict[str, Any]:
        return {"freq_Hz": self.freq.tolist(), "magnitude_bar_per_unit": (np.abs(self.H) / BAR).tolist(),
                "phase_deg": np.degrees(np.unwrap(np.angle(self.H))).tolist(), "coherence": self.coherence.tolist(),
                "magnitude_rel_se": self.rel_se.tolist(),
                "model": {"form": "K e^(-theta s) w^2 / (s^2 + 2 zeta w s + w^2)", **self.model_params,
                          "se": self.model_se, "num": np.ravel(self.model.num[0][0]).tolist(),
                          "den": np.ravel(self.model.den[0][0]).tolist()},
                "source": _source(self.rec, self.rec.t[0], self.rec.t[-1])}


def frequency_response(rec: Recording, f_min: float = 0.2, f_max: float = 20.0) -> FrequencyResponse | None:
    """H1 estimate ``P_up / P_uu`` (Welch, 8 s segments) of a noise, multisine or chirp run, 0.2 to 20 Hz.

    Frequencies with coherence below 0.5 are dropped. The standard error of ``|H|``
    relative to ``|H|`` is ``sqrt((1 - g^2) / (2 n g^2))`` for ``n`` averages
    (Bendat and Piersol). A second-order model with dead time is fitted to the
    complex response, weighted by those errors.
    """
    if rec.experiment not in BROADBAND:
        return None
    t, u, p = rec.t, rec.data["u"], rec.data["p_clutch"]
    run = t >= t[0] + 1.0  # the rig holds the command constant for the first second
    u, p = u[run] - u[run].mean(), p[run] - p[run].mean()
    fs = 1.0 / rec.dt
    nper = min(u.size, int(8.0 * fs))
    if nper < 64:
        return None
    f, Puu = signal.welch(u, fs, nperseg=nper)
    _, Ppp = signal.welch(p, fs, nperseg=nper)
    _, Pup = signal.csd(u, p, fs, nperseg=nper)
    coh = np.abs(Pup) ** 2 / np.maximum(Puu * Ppp, 1e-300)
    n_avg = max(1, int(2 * u.size / nper) - 1)
    keep = (f >= f_min) & (f <= f_max) & (coh > 0.5) & (Puu > 0)
    if np.count_nonzero(keep) < 5:
        return None
    f, H, coh = f[keep], Pup[keep] / Puu[keep], coh[keep]
    rel = np.sqrt((1 - coh) / (2 * n_avg * coh))
    s = 2j * np.pi * f

    def resid(x: np.ndarray) -> np.ndarray:
        K, th, w, z = x
        m = K * w * w / (s * s + 2 * z * w * s + w * w) * np.exp(-s * th)
        e = (m - H) / (np.abs(H) * np.maximum(rel, 1e-3))
        return np.concatenate([e.real, e.imag])

    x0 = np.array([max(float(np.abs(H[0])), 1e-9), 0.01, 2 * np.pi * min(max(f[-1] / 2, 1.0), 300.0), 0.7])
    try:
        res = least_squares(resid, x0, bounds=([0, 0, 0.1, 0.02], [np.inf, 1.0, 2000.0, 10.0]), x_scale="jac")
    except (ValueError, np.linalg.LinAlgError):  # a response no second-order model can follow
        return None
    dof = max(2 * f.size - 4, 1)
    cov = np.linalg.pinv(res.jac.T @ res.jac) * float(res.fun @ res.fun) / dof
    se = np.sqrt(np.abs(np.diag(cov)))
    K, th, w, z = res.x
    names = ("gain_bar_per_unit", "dead_time_s", "omega_n_rad_s", "zeta")
    scale = (1 / BAR, 1.0, 1.0, 1.0)
    return FrequencyResponse(rec, f, H, coh, rel, control.tf([K * w * w], [1.0, 2 * z * w, w * w]), float(th),
                             {n: float(v * c) for n, v, c in zip(names, res.x, scale)},
                             {n: float(v * c) for n, v, c in zip(names, se, scale)})


# ---------------------------------------------------------------- driveline resonance


@dataclass
class Ringing:
    """Free oscillation of ``T_r`` after the last synchronisation of one clutch run."""

    rec: Recording
    freq: float  # damped frequency, Hz
    freq_se: float
    zeta: float
    zeta_se: float
    t0: float
    t1: float
    fit: tuple[np.ndarray, np.ndarray, np.ndarray] = field(repr=False, default=None)


def resonance(rec: Recording, slip_tol: float = 2.0, min_window: float = 0.8) -> Ringing | None:
    """Damped sinusoid ``c0 + c1 t + A exp(-s t) cos(w t + phi)`` fitted to ``T_r`` after synchronisation.

    Synchronisation is the start of the final stretch of ``|slip| < slip_tol``;
    the fit starts 0.1 s later (the lock-up transient) and needs at least
    ``min_window`` seconds. The start values come from the zero-crossing
    frequency (:func:`wetclutch.driveline.ring_frequency`).
    """
    if rec.config != "clutch":
        return None
    d = aligned(rec)
    t = rec.t
    slip = np.abs(d["omega_p"] - d["omega_1"])
    moving = np.flatnonzero(slip >= slip_tol)
    if moving.size == 0 or moving[-1] + 1 >= t.size:
        return None
    # windows by sample count, not by comparing times: rounding of the time stamps must not move them
    start = moving[-1] + 1 + int(round(0.1 / rec.dt))
    if start >= t.size or t[-1] - t[start] < min_window:
        return None
    stride = max(1, int(round(0.004 / rec.dt)))
    tt, yy = t[start::stride], d["T_r"][start::stride]
    tau = tt - tt[0]
    f0 = ring_frequency(tt, yy - np.polyval(np.polyfit(tau, yy, 1), tau))
    if not np.isfinite(f0) or f0 <= 0:
        return None
    def model(x: np.ndarray) -> np.ndarray:
        c0, c1, a, s, om, ph = x
        return c0 + c1 * tau + a * np.exp(-s * tau) * np.cos(om * tau + ph)

    # start values: for a fixed decay and frequency the model is linear in offset, trend, a cos(ph), a sin(ph)
    s0, om0 = 0.5, 2 * np.pi * f0
    env = np.exp(-s0 * tau)
    A = np.column_stack([np.ones_like(tau), tau, env * np.cos(om0 * tau), -env * np.sin(om0 * tau)])
    lin = np.linalg.lstsq(A, yy, rcond=None)[0]
    x0 = [lin[0], lin[1], float(np.hypot(lin[2], lin[3])), s0, om0, float(np.arctan2(lin[3], lin[2]))]
    best = least_squares(lambda x: model(x) - yy, x0, x_scale="jac", max_nfev=300)
    s, om = best.x[3], abs(best.x[4])  # decay rate and angular frequency; the sign of om is the phase's
    resid = best.fun
    cov = np.linalg.pinv(best.jac.T @ best.jac) * float(resid @ resid) / max(tt.size - 6, 1) * _inflation(resid)
    se = np.sqrt(np.abs(np.diag(cov)))
    zeta = s / np.hypot(s, om)
    # d zeta / d s and d zeta / d om of zeta = s / sqrt(s^2 + om^2)
    g = np.array([om * om, -s * om]) / np.hypot(s, om) ** 3
    zeta_se = float(np.sqrt(g @ cov[3:5, 3:5] @ g))
    return Ringing(rec, float(om / (2 * np.pi)), float(se[4] / (2 * np.pi)), float(zeta), zeta_se,
                   float(tt[0]), float(tt[-1]), (tt, yy, model(best.x)))


# ---------------------------------------------------------------- the whole identification


@dataclass
class Identification:
    """All estimates from a set of recordings."""

    recordings: list[Recording]
    prior: Params
    estimates: dict[str, Estimate]
    onsets: list[Onset]
    slips: list[SlipSamples]
    plateaus: list[Plateau]
    steps: list[StepModel]
    responses: list[FrequencyResponse]
    ringings: list[Ringing]
    validation: list[dict[str, Any]]
    identified: Params

    def as_json(self) -> dict[str, Any]:
        """The content of ``identified.json``: flat, named entries, each with value, se and sources."""
        e = self.estimates
        out: dict[str, Any] = {"files": [{"file": str(r.path), "experiment": r.experiment, "config": r.config,
                                          "input_mode": r.input_mode, "oil_temp_C": r.oil_temp_C,
                                          "duration_s": float(r.t[-1] - r.t[0])} for r in self.recordings]}
        for name, est in e.items():
            out[name] = est.as_json()
        out["dead_time_s"] = [{"oil_temp_C": o.rec.oil_temp_C, "input": o.level, "value": o.dead_time,
                               "se": o.dead_time_se, "source": _source(o.rec, o.t_command, o.t_command + o.dead_time)}
                              for o in self.onsets]
        out["pressure_step_models"] = [m.as_json() for m in self.steps]
        out["frequency_responses"] = [r.as_json() for r in self.responses]
        out["validation"] = [{k: v for k, v in e.items() if k != "trace"} for e in self.validation]
        for key in REPORTED:  # always present, so that a reader can tell "not identified" from a typo
            out.setdefault(key, {"value": None, "se": None, "note": "not identified: no suitable runs", "sources": []})
        return out


def identify(recordings: Sequence[Recording], prior: Params | None = None, mu_order: int = 2,
             progress: Callable[[str], None] | None = None) -> Identification:
    """Run every estimator the recordings support (see the module docstring).

    Parameters
    ----------
    recordings
        Checked recordings (:func:`wetclutch.channels.load`).
    prior
        Parameters not identified here (piston area, efficiency, friction knee,
        inertias ...) and the base of the identified parameter set; defaults if None.
    mu_order
        Order of the ``mu(slip)`` polynomial.
    progress
        Called with a short description before each file's work.

    Raises
    ------
    WetclutchError
        No recordings, or an order out of range.
    """
    from .validation import validate

    prior = prior or Params()
    if not recordings:
        raise WetclutchError("no measurement files to identify")
    if not 0 <= mu_order <= 7:
        raise WetclutchError(f"--mu-order must be 0..7 (got {mu_order})")
    est: dict[str, Estimate] = {}
    onsets, steps, responses, ringings, points = [], [], [], [], []
    for rec in recordings:
        if progress:
            progress(rec.path.name)
        if (o := onset(rec)) is not None:
            onsets.append(o)
        steps += step_models(rec)
        if (fr := frequency_response(rec)) is not None:
            responses.append(fr)
        if (rg := resonance(rec)) is not None:
            ringings.append(rg)
        points += plateaus(rec)

    if onsets:
        m, se = _weighted_mean(np.array([o.p_contact for o in onsets]), np.array([o.p_contact_se for o in onsets]))
        est["contact_pressure_Pa"] = Estimate(m, se, "Pa", [_source(o.rec, o.t_command, o.t_command + o.dead_time)
                                                            for o in onsets])
    p_contact = est["contact_pressure_Pa"].value if onsets else clutch.p_contact(prior)
    by_rec = {id(o.rec): o for o in onsets}
    slips = [s for rec in recordings if (s := slip_samples(rec, prior, p_contact, by_rec.get(id(rec)))) is not None]
    if slips:
        est["mu_slip_poly"] = friction(slips, mu_order)
    ratios = [(measured_ratio(r), r) for r in recordings if r.config == "clutch"]
    ratios = [(v, r) for v, r in ratios if np.isfinite(v[0])]
    if ratios:
        m, se = _weighted_mean(np.array([v[0] for v, _ in ratios]), np.array([v[1] for v, _ in ratios]))
        est["ratio"] = Estimate(m, se, "-", [_source(r, r.t[0], r.t[-1]) for _, r in ratios])
    drags = [(o, s) for o in onsets for s in slips if s.rec is o.rec and o.slip0 > SLIP_MIN]
    if drags:
        # open-clutch oil drag: T_r before the onset, back through the CVT, per rad/s of slip
        est["oil_drag_Nms"] = Estimate(
            [float(o.baseline * s.ratio / prior.driveline.eta / o.slip0) for o, s in drags],
            [float(o.noise * s.ratio / prior.driveline.eta / o.slip0 / np.sqrt(500.0)) for o, s in drags],
            "N m s (one value per run, in file order)", [_source(o.rec, o.t_command - 0.5, o.t_command) for o, _ in drags],
            {"oil_temp_C": [o.rec.oil_temp_C for o, _ in drags]})
    for key, (config, mode, order) in GAIN_GROUPS.items():
        group = [q for q in points if q.rec.config == config and q.rec.input_mode == mode]
        if (g := static_gain(group, order)) is not None:
            est[key] = g
        if config == "valve-only" and mode == "pwm" and (h := hysteresis(group)) is not None:
            est["valve_hysteresis_bar"] = h
    if "valve_gain_poly" in est:
        v = est["valve_gain_poly"]
        est["valve_gain"] = Estimate({"slope_bar_per_duty": v.value[0], "offset_bar": v.value[1]},
                                     {"slope_bar_per_duty": v.se[0], "offset_bar": v.se[1]}, "bar", v.sources)
    if ringings:
        f, fse = _weighted_mean(np.array([r.freq for r in ringings]), np.array([r.freq_se for r in ringings]))
        z, zse = _weighted_mean(np.array([r.zeta for r in ringings]), np.array([r.zeta_se for r in ringings]))
        src = [_source(r.rec, r.t0, r.t1) for r in ringings]
        est["resonance_Hz"] = Estimate(f, fse, "Hz (damped)", src)
        est["damping_ratio"] = Estimate(z, zse, "-", src)
    temps = [r.oil_temp_C for r in recordings if r.config == "clutch"] or [r.oil_temp_C for r in recordings]
    est["oil_temp_C"] = Estimate(float(np.median(temps)), float(np.std(temps)), "C (median over the runs)",
                                 [_source(r, r.t[0], r.t[-1]) for r in recordings])
    identified = identified_params(prior, est)
    result = Identification(list(recordings), prior, est, onsets, slips, points, steps, responses, ringings, [],
                            identified)
    result.validation = validate(result)
    return result


#: static gain entries: (configuration, input mode, polynomial order)
GAIN_GROUPS = {
    "valve_gain_poly": ("valve-only", "pwm", 1),
    "clutch_gain_poly_bar_per_V": ("clutch", "dc", 2),
    "clutch_gain_poly_bar_per_duty": ("clutch", "pwm", 2),
    "valve_gain_poly_bar_per_V": ("valve-only", "dc", 2),
}


def reduced_inertias(p: Params, ratio: float) -> tuple[float, float]:
    """Two-mass inertias at the axle with power flowing forward and back through the CVT (see :mod:`wetclutch.params`)."""
    d = p.driveline
    j_a = d.J_p + d.J_1
    red = lambda j: j * d.J_s / (j + d.J_s)  # noqa: E731
    return red(d.eta * j_a / ratio**2), red(j_a / (d.eta * ratio**2))


def identified_params(prior: Params, est: dict[str, Estimate]) -> Params:
    """The prior parameters with the identified values put in.

    ``friction.mu_slip_poly`` (``mu_scale`` 1), ``driveline.ratio``, ``rig.oil_temp_C``,
    ``hydraulics.x_contact`` (from the contact pressure, keeping the prior prestress,
    spring and piston area), ``driveline.k_a`` and ``d_a`` (from resonance and damping
    with the prior inertias, the relation in :mod:`wetclutch.params`).
    """
    from .params import load

    sets: dict[str, Any] = {}
    if "mu_slip_poly" in est:
        sets["friction.mu_slip_poly"] = list(est["mu_slip_poly"].value)
        sets["friction.mu_scale"] = 1.0
    ratio = est["ratio"].value if "ratio" in est else prior.driveline.ratio
    if "ratio" in est:
        sets["driveline.ratio"] = ratio
    if "oil_temp_C" in est:
        sets["rig.oil_temp_C"] = float(np.clip(est["oil_temp_C"].value, -30.0, 150.0))
    h = prior.hydraulics
    if "contact_pressure_Pa" in est and est["contact_pressure_Pa"].value > h.p_prestress:
        sets["hydraulics.x_contact"] = (est["contact_pressure_Pa"].value - h.p_prestress) * h.A_p / h.k_reset
    if "resonance_Hz" in est:
        j_f, j_b = reduced_inertias(prior, ratio)
        k_a = (est["resonance_Hz"].value * np.pi * (np.sqrt(j_f) + np.sqrt(j_b))) ** 2
        sets["driveline.k_a"] = float(k_a)
        if "damping_ratio" in est:
            sets["driveline.d_a"] = float(2.0 * est["damping_ratio"].value * np.sqrt(k_a * 0.5 * (j_f + j_b)))
    try:
        return load(None, sets, base=prior)
    except WetclutchError as err:
        raise WetclutchError(f"identified values make no valid parameter set: {err}") from None
