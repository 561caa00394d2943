"""Driveline resonance and damping from the free oscillation after synchronisation."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from ..plant.driveline import ring_frequency
from .estimate import aligned, inflation
from .recordings import Recording


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


def _spectral_peak(tau: np.ndarray, y: np.ndarray) -> float:
    """Frequency (Hz) of the largest periodogram value of ``y`` on the even grid ``tau`` (the constant left out)."""
    power = np.abs(np.fft.rfft(y)) ** 2
    freqs = np.fft.rfftfreq(y.size, tau[1] - tau[0])
    return float(freqs[1 + int(np.argmax(power[1:]))]) if y.size > 2 else float("nan")


def resonance(rec: Recording, slip_tol: float = 2.0, min_window: float = 0.8) -> Ringing | None:
    """Damped sinusoid ``c0 + c1 t + A exp(-s t) cos(w t + phi)`` fitted to ``T_r`` after synchronisation.

    Synchronisation is the start of the final stretch of ``|slip| < slip_tol``;
    the fit starts 0.1 s later (the lock-up transient) and needs at least
    ``min_window`` seconds. The fit starts from two frequencies, the zero crossings'
    (:func:`wetclutch.plant.driveline.ring_frequency`) and the periodogram's peak, and the
    one with the smaller residual is kept: a ringing that decays within a fraction of a
    long window leaves a quiet tail whose noise crosses the mean far more often than the
    ringing does.
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
    detrended = yy - np.polyval(np.polyfit(tau, yy, 1), tau)
    # start frequencies: the zero crossings' (noise crossing the mean in a long, quiet tail counts too) and the
    # periodogram's peak (the ringing's energy, however soon it decays); the better of the two fits is kept
    starts = [f for f in (ring_frequency(tt, detrended), _spectral_peak(tau, detrended)) if np.isfinite(f) and f > 0]
    if not starts:
        return None

    def model(x: np.ndarray) -> np.ndarray:
        c0, c1, a, s, om, ph = x
        with np.errstate(over="ignore", invalid="ignore"):  # the solver's trial steps may grow the envelope
            return c0 + c1 * tau + a * np.exp(-s * tau) * np.cos(om * tau + ph)

    best = None
    for f0 in starts:
        # start values: for a fixed decay and frequency the model is linear in offset, trend, a cos(ph), a sin(ph)
        s0, om0 = 0.5, 2 * np.pi * f0
        env = np.exp(-s0 * tau)
        A = np.column_stack([np.ones_like(tau), tau, env * np.cos(om0 * tau), -env * np.sin(om0 * tau)])
        lin = np.linalg.lstsq(A, yy, rcond=None)[0]
        x0 = [lin[0], lin[1], float(np.hypot(lin[2], lin[3])), s0, om0, float(np.arctan2(lin[3], lin[2]))]
        with np.errstate(over="ignore", invalid="ignore"):  # the solver's cost of such a trial step overflows too
            fit = least_squares(lambda x: model(x) - yy, x0, x_scale="jac", max_nfev=300)
        if best is None or fit.cost < best.cost:
            best = fit
    s, om = best.x[3], abs(best.x[4])  # decay rate and angular frequency; the sign of om is the phase's
    resid = best.fun
    cov = np.linalg.pinv(best.jac.T @ best.jac) * float(resid @ resid) / max(tt.size - 6, 1) * inflation(resid)
    se = np.sqrt(np.abs(np.diag(cov)))
    zeta = s / np.hypot(s, om)
    # d zeta / d s and d zeta / d om of zeta = s / sqrt(s^2 + om^2)
    g = np.array([om * om, -s * om]) / np.hypot(s, om) ** 3
    zeta_se = float(np.sqrt(g @ cov[3:5, 3:5] @ g))
    return Ringing(rec, float(om / (2 * np.pi)), float(se[4] / (2 * np.pi)), float(zeta), zeta_se,
                   float(tt[0]), float(tt[-1]), (tt, yy, model(best.x)))
