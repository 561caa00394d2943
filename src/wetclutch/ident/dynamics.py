"""Pressure dynamics: low-order models of steps and relaxations, and frequency responses of broadband runs."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import control
import numpy as np
from scipy import signal
from scipy.optimize import least_squares

from .estimate import BAR, inflation, source
from .recordings import Recording, command_changes
from .static import BROADBAND


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
                "source": source(self.rec, self.t0, self.t1)}


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
                # a trial shape far out (the exponential of a large log) makes a pole 0 or infinite and the
                # residuals non-finite: the solver steps back from it, and a result that stays there is dropped
                with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
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
        x, jac_x = res.x, res.jac
        if x[1] < 0.0:
            # a dead time before the command is no dead time (a response with an instant part, as the chamber's
            # fill spike, pulls a lag's fit there): fit again with none, which then has no standard error
            def at_zero(z: np.ndarray) -> np.ndarray:
                return np.insert(z, 1, 0.0)

            try:
                with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                    r = least_squares(lambda z: model(at_zero(z)) - yy, np.delete(x, 1),
                                      jac=lambda z: np.delete(jac(at_zero(z)), 1, axis=1), method="lm",
                                      x_scale="jac", ftol=1e-6, xtol=1e-6, max_nfev=400)
            except (ValueError, np.linalg.LinAlgError):
                continue
            if not (np.all(np.isfinite(r.x)) and np.all(np.isfinite(r.fun))):
                continue
            x, jac_x = at_zero(r.x), np.insert(r.jac, 1, 0.0, axis=1)
            res = r
        resid = res.fun
        vaf = float(100.0 * (1.0 - np.var(resid) / max(np.var(yy), 1e-30)))
        dof = max(tt.size - x.size, 1)
        cov = np.linalg.pinv(jac_x.T @ jac_x) * float(resid @ resid) / dof * inflation(resid)
        se = np.sqrt(np.abs(np.diag(cov)))
        shape = np.exp(x[2:])
        names = {1: ["tau_s"], 2: ["omega_n_rad_s", "zeta"], 3: ["tau_coil_s", "omega_n_rad_s", "zeta"]}[order]
        params = dict(zip(names, (float(v) for v in shape)))
        ses = {"gain_bar_per_unit": float(se[0] / BAR / abs(du)) if du else None, "dead_time_s": float(se[1]),
               **dict(zip(names, (float(v) for v in shape * se[2:])))}  # d exp(z) = exp(z) dz
        out.append(StepModel(rec, order, float(x[0] / du) if du else float("nan"), float(x[1]), params, ses,
                             vaf, float(t[k]), float(t[end - 1]), (tt + t[k], yy + p0, model(x) + p0)))
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
                "source": source(self.rec, self.rec.t[0], self.rec.t[-1])}


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
