"""The virtual test rig: the study's experiments on the simulated clutch.

:func:`run` builds the input signal of an experiment, simulates the rig
(:mod:`wetclutch.plant.clutch`), records the true internal states on a fine grid and
passes the rig's channels through the sensor chain of :mod:`wetclutch.rig.sensors`.
:func:`wetclutch.report.rig.write` stores a run like a real rig would.

Experiments (the command ``u`` is a voltage in DC mode, a duty cycle in PWM mode):

``step``        ``from`` until 1 s, then ``level``
``relaxation``  ``level`` until 1 s, then ``from`` (high to low)
``staircase``   ``from`` up to ``level`` in equal steps, then back down (hysteresis)
``noise``       band-limited random input (0.1 to 10 Hz) around mid-range
``multisine``   sum of sines 0.2 to 20 Hz with Schroeder phases around mid-range
``chirp``       logarithmic sweep 0.1 to 20 Hz around mid-range

On the ``clutch`` configuration a run goes on until the clutch has synchronised
and the driveline has rung out for 1.5 s (or ``t_end``); on ``valve-only`` it
lasts a fixed time per experiment.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import pandas as pd

from ..errors import WetclutchError, check_flag, check_instance, check_integer, check_number, kind_of, named
from ..params import Params, check_oil_temp
from ..physics import actuator as A
from ..physics import friction
from ..plant import clutch
from ..sim.network import Trajectory, integrate
from ..sim.signals import Signal, Step, Table
from . import sensors

EXPERIMENTS = ("step", "relaxation", "staircase", "noise", "multisine", "chirp")
#: the longest run, s (also of ``wetclutch simulate``)
MAX_T_END_S = 600.0
INPUT_RANGE = {"dc": (0.2, 5.0), "pwm": (0.0, 1.0)}
DEFAULT_LEVEL = {"dc": 1.0, "pwm": 0.2}
T_STEP = 1.0  # s: a step starts after a settled first second
TRUTH_DT = 1e-4  # s: grid of the true signals, fine enough for the sensor filters

MEASURED_UNITS = {
    "time": "s",
    "u": "V",
    "p_clutch": "Pa",
    "T_r": "N m",
    "omega_p": "rad/s",
    "omega_1": "rad/s",
    "omega_r": "rad/s",
    "omega_s": "rad/s",
    "oil_temp": "C",
}


@dataclass(frozen=True)
class Settings:
    """One experiment on the rig (see the module docstring)."""

    experiment: str = "step"
    input_mode: str = "dc"
    level: float | None = None
    from_: float | None = None
    oil_temp_C: float | None = None
    config: str = "clutch"
    rate_hz: float = 1000.0
    seed: int = 0
    noise: bool = True
    t_end: float | None = None

    def checked(self, params: Params) -> Settings:
        """Fill defaults and refuse settings outside the rig's range (one-line errors naming the setting: its
        command-line option where the command line gave it, ``--level``, else the field, ``level``)."""
        def name(field: str) -> str:
            return named(field, _OPTIONS[field])

        if not isinstance(self.experiment, str) or self.experiment not in EXPERIMENTS:
            raise WetclutchError(f"unknown experiment '{self.experiment}' (choose from {', '.join(EXPERIMENTS)})")
        if not isinstance(self.input_mode, str) or self.input_mode not in INPUT_RANGE:
            raise WetclutchError(f"{name('input_mode')} must be dc or pwm (got '{self.input_mode}')")
        if not isinstance(self.config, str) or self.config not in clutch.CONFIGS:
            raise WetclutchError(f"{name('config')} must be clutch or valve-only (got '{self.config}')")
        lo, hi = INPUT_RANGE[self.input_mode]
        unit = "V" if self.input_mode == "dc" else "duty"
        level = DEFAULT_LEVEL[self.input_mode] if self.level is None else check_number(self.level, name("level"), unit)
        from_ = lo if self.from_ is None else check_number(self.from_, name("from_"), unit)
        for field, v in (("level", level), ("from_", from_)):
            if not lo <= v <= hi:
                raise WetclutchError(f"{name(field)} {v:g} is outside the rig's input range {lo:g}..{hi:g} {unit}")
        temp = params.rig.oil_temp_C if self.oil_temp_C is None else self.oil_temp_C
        temp = check_oil_temp(temp, name("oil_temp_C"))
        rate = check_number(self.rate_hz, name("rate_hz"), "Hz")
        if not 10.0 <= rate <= 1.0 / TRUTH_DT / 2:
            raise WetclutchError(f"{name('rate_hz')} must be in 10..{1.0 / TRUTH_DT / 2:g} Hz (got {rate:g})")
        if check_integer(self.seed, name("seed")) < 0:
            raise WetclutchError(f"{name('seed')} must be >= 0 (got {self.seed})")
        noise = check_flag(self.noise, "noise")
        t_end = None if self.t_end is None else check_number(self.t_end, name("t_end"), "s")
        if t_end is not None and not T_STEP < t_end <= MAX_T_END_S:
            raise WetclutchError(f"{name('t_end')} must be in ({T_STEP:g}, {MAX_T_END_S:g}] s (got {t_end:g})")
        return Settings(self.experiment, self.input_mode, level, from_, temp, self.config, rate,
                        int(self.seed), noise, t_end)


#: the command-line options of the settings, for the errors of ``wetclutch rig``
_OPTIONS = {"input_mode": "--input-mode", "config": "--config", "level": "--level", "from_": "--from",
            "oil_temp_C": "--oil-temp", "rate_hz": "--rate", "seed": "--seed", "t_end": "--t-end"}


@dataclass
class RigResult:
    """A rig run: what the sensors recorded, the true internal states, and the settings."""

    measured: pd.DataFrame
    truth: pd.DataFrame
    meta: dict[str, Any]
    trajectory: Trajectory


def input_signal(s: Settings) -> tuple[Signal, float]:
    """The command ``u(t)`` of an experiment and its default duration (s)."""
    lo, hi = INPUT_RANGE[s.input_mode]
    a, b = s.from_, s.level
    if s.experiment == "step":
        return Step(T_STEP, a, b), 6.0
    if s.experiment == "relaxation":
        return Step(T_STEP, b, a), 6.0
    if s.experiment == "staircase":
        n, dwell = 6, 1.5
        levels = np.concatenate([np.linspace(a, b, n + 1)[1:], np.linspace(b, a, n + 1)[1:]])
        u, t = staircase(levels, a, dwell)
        return u, float(t[-1] + dwell)
    mid, amp = 0.5 * (a + b), 0.5 * abs(b - a)
    duration = 20.0
    t = np.arange(0.0, duration + 1e-3, 1e-3)
    rng = np.random.default_rng(s.seed)
    if s.experiment == "noise":
        from scipy import signal as ss

        sos = ss.butter(2, [0.1, 10.0], btype="band", fs=1000.0, output="sos")
        w = ss.sosfilt(sos, rng.standard_normal(t.size))
        x = w / (3.0 * np.std(w))
    elif s.experiment == "multisine":
        f = np.geomspace(0.2, 20.0, 12)
        k = np.arange(1, f.size + 1)
        phase = -np.pi * k * (k - 1) / f.size  # Schroeder phases keep the crest factor low
        x = np.sum(np.sin(2 * np.pi * f[:, None] * t[None, :] + phase[:, None]), axis=0)
        x /= np.max(np.abs(x))
    else:  # chirp
        from scipy.signal import chirp

        x = chirp(t, f0=0.1, t1=duration, f1=20.0, method="logarithmic")
    u = np.clip(mid + amp * x, lo, hi)
    u[t < T_STEP] = mid
    return Table(t, u), duration


def staircase(levels: np.ndarray, start: float, dwell: float) -> tuple[Table, np.ndarray]:
    """A command at ``start`` until :data:`T_STEP`, then each of ``levels`` for ``dwell`` seconds.

    Returns the command and the times its steps begin. Each step is a 1 ms ramp: a command
    cannot jump faster than the DAQ updates it.
    """
    before = np.concatenate([[start], levels[:-1]])
    t = T_STEP + dwell * np.arange(levels.size)
    tt = np.concatenate([[0.0], np.ravel(np.column_stack([t, t + 1e-3]))])
    vv = np.concatenate([[start], np.ravel(np.column_stack([before, levels]))])
    return Table(tt, vv, kinks_are_breakpoints=True), t


def _truth(tr: Trajectory, rn: clutch.RigNetwork, s: Settings, u: Signal) -> pd.DataFrame:
    net = rn.network
    act = net.act.record
    p = tr.x[:, rn.i_pressure]
    x_p = A.piston_positions(p, act)
    f_n = friction.normal_force.py_func(p, act[A.P_CONTACT], act[A.A_P])
    cols: dict[str, np.ndarray] = {
        "time": tr.t,
        "u": _sample(u, tr.t),
        "coil_current": tr.x[:, rn.i_current],
        "x_stem": tr.x[:, len(net.bodies) + [sp.name for sp in net.springs].index(clutch.STEM_SPRING)],
        "x_piston": x_p,
        "p_clutch": p,
        "F_n": f_n,
        "V_in": tr.x[:, rn.i_pressure + 1],
        "V_out": tr.x[:, rn.i_pressure + 2],
        "oil_temp": np.full(tr.t.size, s.oil_temp_C),
    }
    if s.config == "clutch":
        cols.update(
            T_c=tr.clutch_torque("clutch"),
            T_cap=tr.capacity("clutch"),
            locked=tr.locked("clutch"),
            T_r=tr.spring_torque("axle"),
            omega_p=tr.speed("p"),
            omega_1=tr.speed("1"),
            omega_r=tr.speed("r"),
            omega_s=tr.speed("s"),
            T_plate=tr.plate_temperature(),
        )
    return pd.DataFrame(cols)


def _sample(u: Signal, t: np.ndarray) -> np.ndarray:
    if isinstance(u, Table):
        return np.interp(t, u.time, u.value)
    assert isinstance(u, Step)
    return np.where(t >= u.t0, u.after, u.before)


def run(experiment: str = "step", params: Params | None = None, **settings: Any) -> RigResult:
    """Run one experiment on the virtual rig.

    Parameters
    ----------
    experiment
        One of :data:`EXPERIMENTS`.
    params
        Rig parameters (the study's defaults if None).
    **settings
        Fields of :class:`Settings`: ``input_mode``, ``level``, ``from_``,
        ``oil_temp_C``, ``config``, ``rate_hz``, ``seed``, ``noise``, ``t_end``.

    Returns
    -------
    RigResult
        ``measured`` (the rig's channels, SI; ``u`` in V or duty, ``oil_temp`` in C)
        and ``truth`` (noise-free internal states on a 0.1 ms grid).
    """
    if not isinstance(experiment, str):
        raise WetclutchError(f"experiment must be an experiment's name ({', '.join(EXPERIMENTS)}), not "
                             f"{kind_of(experiment)}")
    if params is not None:
        check_instance(params, Params, "params", "a parameter set (wetclutch.load_params(...)) or None")
    p = params if params is not None else Params()
    unknown = set(settings) - set(Settings.__dataclass_fields__)
    if unknown:
        raise WetclutchError(f"unknown rig setting '{sorted(unknown)[0]}'")
    s = Settings(experiment=experiment, **settings).checked(p)
    u, duration = input_signal(s)
    rn = clutch.build(p, u, pwm=s.input_mode == "pwm", config=s.config, temp_C=s.oil_temp_C)
    t_end = s.t_end if s.t_end is not None else duration
    tr = integrate(rn.network, t_end, dt_out=TRUTH_DT)
    if s.config == "clutch" and s.t_end is None:
        # go on until synchronisation plus the ring-out, as the study's runs did
        while (t_sync := tr.sync_time("clutch")) is None or t_sync + 1.5 > t_end:
            if t_end >= 120.0:
                break
            t_end = min(120.0, max(2.0 * t_end, (t_sync or 0.0) + 1.5))
            tr = integrate(rn.network, t_end, dt_out=TRUTH_DT)
    truth = _truth(tr, rn, s, u)
    channels = [c for c in MEASURED_UNITS if c in truth.columns]
    measured = sensors.measure(truth[channels], s.rate_hz, seed=s.seed, noise=s.noise)
    meta = {
        "experiment": s.experiment,
        "settings": {k: v for k, v in asdict(s).items()},
        "t_sync": tr.sync_time("clutch") if s.config == "clutch" else None,
        "units": {c: MEASURED_UNITS[c] if c != "u" else ("V" if s.input_mode == "dc" else "duty") for c in channels},
        "params": p.model_dump(),
    }
    return RigResult(measured, truth, meta, tr)
