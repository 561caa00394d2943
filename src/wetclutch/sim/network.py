"""Describe a rotational network in Python and integrate it with the compiled engine.

A :class:`Network` is a list of bodies (inertias) joined at their flanges by
clutches, brakes, gears (CVT), spring-dampers and torque sources, much like
Modelica's ``Mechanics.Rotational`` components. :func:`integrate` compiles it
to flat arrays (:class:`NetArrays`, which this module alone packs) and runs
:func:`wetclutch.sim.integrator.advance`, returning a :class:`Trajectory` sampled
on a uniform output grid.

Example
-------
>>> from wetclutch.sim.network import Network, integrate
>>> net = Network()
>>> a = net.body("a", J=1.0, w0=10.0)
>>> b = net.body("b", J=1.0)
>>> net.clutch("c", a, b, capacity=5.0)
0
>>> tr = integrate(net, t_end=2.0)
>>> round(tr.first_lock("c"), 6)  # 10 / (5 * (1/1 + 1/1))
1.0
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from ..errors import SimulationError, WetclutchError
from ..physics import actuator as act_mod
from ..physics import thermal as th_mod
from . import coldstart
from . import workspace as wsp
from .integrator import advance
from .signals import Signal, as_signal, compile_signals, sine_step_limit

GROUND = -1


class NetArrays(NamedTuple):
    """Flat, compiled description of a network (see :class:`Network`)."""

    J: np.ndarray  # (nb,) inertias, kg m^2 (0 allowed if rigidly tied to an inertia)
    drag: np.ndarray  # (nb,) quadratic drag coefficients, N m s^2
    cl_a: np.ndarray  # (nc,) int
    cl_b: np.ndarray  # (nc,) int, -1 = ground (brake)
    cl_sig: np.ndarray  # (nc,) int signal index of the capacity
    cl_peak: np.ndarray  # (nc,) static / sliding capacity ratio
    cl_poly: np.ndarray  # (nc, P) capacity multiplier polynomial in |slip|, highest power first
    cl_oneway: np.ndarray  # (nc,) int, 1: one-way clutch (freewheel), b may overrun a, a never overruns b
    gr_in: np.ndarray  # (ng,) int
    gr_out: np.ndarray  # (ng,) int
    gr_ratio: np.ndarray  # (ng,) w_out / w_in (the initial one of a moving ratio)
    gr_eta: np.ndarray  # (ng,) efficiency
    gr_state: np.ndarray  # (ng,) int state index of a moving ratio, -1: constant
    gr_rate_sig: np.ndarray  # (ng,) int signal index of a moving ratio's commanded rate (1/s), -1: constant
    gr_lim: np.ndarray  # (ng, 3) a moving ratio's least and greatest ratio and its rate limit (1/s)
    sp_a: np.ndarray  # (ns,) int
    sp_b: np.ndarray  # (ns,) int, -1 = ground
    sp_k: np.ndarray  # (ns,) N m / rad
    sp_d: np.ndarray  # (ns,) N m s / rad
    src_body: np.ndarray  # (nsrc,) int
    src_sig: np.ndarray  # (nsrc,) int
    sig: np.ndarray  # (nsig, ROW) compiled signals
    tab: np.ndarray  # (2, ntab) table samples
    bps: np.ndarray  # sorted breakpoint times
    act: np.ndarray  # flat actuator record (see wetclutch.physics.actuator), empty without one
    th: np.ndarray  # flat thermal record of a clutch pack (see wetclutch.physics.thermal), empty without one


@dataclass
class _Body:
    name: str
    J: float
    w0: float
    drag: float


@dataclass
class _Clutch:
    name: str
    a: int
    b: int
    capacity: Signal
    peak: float
    mu_poly: tuple[float, ...]
    oneway: bool = False


@dataclass
class _Gear:
    name: str
    a: int
    b: int
    ratio: float
    eta: float
    rate: Signal | None = None  # commanded ratio rate, 1/s (None: constant ratio)
    ratio_range: tuple[float, float] = (np.nan, np.nan)
    rate_max: float = np.inf


@dataclass
class _Spring:
    name: str
    a: int
    b: int
    k: float
    d: float
    phi0: float


@dataclass
class _Source:
    name: str
    body: int
    torque: Signal


@dataclass
class _Actuator:
    stem: int
    spring: int
    clutch: int
    u: Signal
    record: np.ndarray
    pwm: bool
    pwm_freq: float


@dataclass
class Network:
    """A network of rotating bodies and the elements that join them."""

    bodies: list[_Body] = field(default_factory=list)
    clutches: list[_Clutch] = field(default_factory=list)
    gears: list[_Gear] = field(default_factory=list)
    springs: list[_Spring] = field(default_factory=list)
    sources: list[_Source] = field(default_factory=list)
    act: _Actuator | None = None
    heat: tuple[int, np.ndarray] | None = None  # (clutch, thermal record)

    # -------------------------------------------------------------- building
    def body(self, name: str, J: float, w0: float = 0.0, drag: float = 0.0) -> int:
        """Add an inertia ``J`` (kg m^2, >= 0) spinning at ``w0`` rad/s with quadratic drag
        ``drag * w |w|`` (N m s^2). A zero inertia is allowed only where a gear or locked
        clutch ties the body to one with inertia. Returns the body's index."""
        if J < 0.0:
            raise ValueError(f"body {name!r}: inertia must be >= 0")
        self.bodies.append(_Body(name, float(J), float(w0), float(drag)))
        return len(self.bodies) - 1

    def clutch(
        self,
        name: str,
        a: int,
        b: int,
        capacity: Signal | float,
        peak: float = 1.0,
        mu_poly: tuple[float, ...] = (1.0,),
    ) -> int:
        """Coulomb clutch from body ``a`` to body ``b`` (``GROUND`` makes it a brake).

        Sliding torque ``capacity(t) * poly(|slip|)``; it sticks while the constraint
        torque stays within ``peak * capacity(t) * poly(0)``; it is free while the
        capacity is <= 0. ``mu_poly`` is highest power first, slip in rad/s.
        """
        if peak < 1.0:
            raise ValueError(f"clutch {name!r}: peak must be >= 1")
        self.clutches.append(_Clutch(name, a, b, as_signal(capacity), float(peak), tuple(mu_poly)))
        return len(self.clutches) - 1

    def one_way_clutch(
        self,
        name: str,
        a: int,
        b: int,
        capacity: Signal | float = 0.0,
        peak: float = 1.0,
        mu_poly: tuple[float, ...] = (1.0,),
    ) -> int:
        """One-way clutch (freewheel in series with a friction clutch), as Modelica's ``OneWayClutch``.

        Body ``b`` may overrun ``a`` (slip ``w_a - w_b < 0``), sliding with the clutch's
        torque ``capacity(t) * poly(|slip|)`` (none with the default capacity 0: a pure
        freewheel); ``a`` never overruns ``b``: when the slip would turn positive it locks,
        and locked it transmits any torque that drives ``b`` forward, and up to
        ``peak * capacity * poly(0)`` the other way before ``b`` breaks loose forward.
        """
        j = self.clutch(name, a, b, capacity, peak, mu_poly)
        self.clutches[j].oneway = True
        return j

    def brake(self, name: str, a: int, capacity: Signal | float, peak: float = 1.0) -> int:
        """A clutch from body ``a`` to the ground."""
        return self.clutch(name, a, GROUND, capacity, peak)

    def gear(self, name: str, a: int, b: int, ratio: float, eta: float = 1.0, *, rate: Signal | float | None = None,
             ratio_range: tuple[float, float] | None = None, rate_max: float = np.inf) -> int:
        """Ideal gear / CVT with ``w_b = ratio * w_a`` and efficiency ``eta`` in either direction.

        With ``rate`` (1/s) the ratio moves: it starts at ``ratio`` and changes at the commanded
        rate, limited to ``rate_max`` either way and held within ``ratio_range`` (least, greatest;
        one sign); reaching a limit is an event. Without it the ratio is constant.
        """
        if ratio == 0.0:
            raise ValueError(f"gear {name!r}: ratio must be non-zero")
        if not 0.0 < eta <= 1.0:
            raise ValueError(f"gear {name!r}: efficiency must be in (0, 1]")
        gear = _Gear(name, a, b, float(ratio), float(eta))
        if rate is not None:
            if ratio_range is None:
                raise ValueError(f"gear {name!r}: a moving ratio needs its ratio_range")
            lo, hi = float(ratio_range[0]), float(ratio_range[1])
            if not (lo <= ratio <= hi and (lo > 0.0 or hi < 0.0)):
                raise ValueError(f"gear {name!r}: ratio_range must hold the ratio and not contain 0")
            if not rate_max > 0.0:
                raise ValueError(f"gear {name!r}: rate_max must be > 0")
            gear.rate, gear.ratio_range, gear.rate_max = as_signal(rate), (lo, hi), float(rate_max)
        self.gears.append(gear)
        return len(self.gears) - 1

    def spring(self, name: str, a: int, b: int, k: float, d: float = 0.0, phi0: float = 0.0) -> int:
        """Linear spring-damper from ``a`` to ``b`` (``GROUND`` allowed): torque on ``b`` is
        ``k phi + d (w_a - w_b)`` with ``phi' = w_a - w_b``, ``phi(0) = phi0``."""
        if k < 0.0 or d < 0.0:
            raise ValueError(f"spring {name!r}: stiffness and damping must be >= 0")
        self.springs.append(_Spring(name, a, b, float(k), float(d), float(phi0)))
        return len(self.springs) - 1

    def source(self, name: str, body: int, torque: Signal | float) -> int:
        """Torque ``torque(t)`` (N m) on ``body``, reacting on the ground."""
        self.sources.append(_Source(name, body, as_signal(torque)))
        return len(self.sources) - 1

    def actuator(
        self,
        stem: int,
        spring: int,
        clutch: int,
        u: Signal | float,
        record: np.ndarray,
        pwm: bool = False,
        pwm_freq: float = 1000.0,
    ) -> None:
        """Attach the hydraulic actuator (:mod:`wetclutch.physics.actuator`).

        Parameters
        ----------
        stem, spring
            The valve stem body and its spring to the ground (whose deflection is the
            stem position).
        clutch
            The clutch whose capacity becomes ``F_n * friction_factor(F_n)`` (N); its
            ``mu_poly`` then holds the friction coefficient (m) versus slip.
        u
            Input: voltage (DC) or duty cycle (PWM).
        record
            Physical parameters, :func:`wetclutch.physics.actuator.pack`.
        """
        if self.act is not None:
            raise ValueError("a network has at most one actuator")
        self.act = _Actuator(stem, spring, clutch, as_signal(u), np.asarray(record, float), pwm, float(pwm_freq))

    def thermal(self, clutch: int, record: np.ndarray) -> None:
        """Give clutch ``clutch`` a heated pack (:mod:`wetclutch.physics.thermal`): its slip power
        heats the plates, the oil cools them; ``record`` from :func:`wetclutch.physics.thermal.pack`."""
        if self.heat is not None:
            raise ValueError("a network has at most one heated clutch pack")
        if not 0 <= clutch < len(self.clutches):
            raise ValueError(f"thermal: clutch index {clutch} does not exist")
        self.heat = (clutch, np.asarray(record, float))

    # -------------------------------------------------------------- layout
    @property
    def n_state(self) -> int:
        return self.ratio_state + len(self._moving())

    @property
    def ratio_state(self) -> int:
        """Index of the first moving ratio in the state vector (after the heated pack's states)."""
        return self.thermal_state + (th_mod.N_STATES if self.heat is not None else 0)

    def _moving(self) -> list[int]:
        """Indices of the gears whose ratio moves, in the order of their states."""
        return [k for k, g in enumerate(self.gears) if g.rate is not None]

    @property
    def thermal_state(self) -> int:
        """Index of the plate temperature in the state vector (after the actuator's states)."""
        return self.actuator_state + (act_mod.N_STATES if self.act is not None else 0)

    @property
    def actuator_state(self) -> int:
        """Index of the actuator's first state in the state vector (the order of :mod:`wetclutch.physics.actuator`)."""
        return len(self.bodies) + len(self.springs) + len(self.clutches) + wsp.N_ENERGY_EXTRA

    def compile(self) -> tuple[NetArrays, np.ndarray, np.ndarray]:
        """Flatten to ``(NetArrays, x0, ext)`` for the numba core."""
        nb = len(self.bodies)
        for el in [*self.clutches, *self.gears, *self.springs]:
            for idx in (el.a, el.b):
                if not (idx == GROUND or 0 <= idx < nb):
                    raise ValueError(f"{el.name!r}: body index {idx} does not exist")
        for g in self.gears:
            if GROUND in (g.a, g.b):
                raise ValueError(f"gear {g.name!r}: both flanges must be bodies")
        for c in self.clutches:
            if c.a == GROUND:
                raise ValueError(f"clutch {c.name!r}: flange a must be a body")
        moving = self._moving()
        signals: list[Signal] = ([c.capacity for c in self.clutches] + [s.torque for s in self.sources]
                                 + [self.gears[k].rate for k in moving])
        if self.act is not None:
            signals.append(self.act.u)
        sig, tab, bps, ext = compile_signals(signals)
        act = np.zeros(0)
        if self.act is not None:
            a = self.act
            act = act_mod.wire(a.record, state=self.actuator_state, stem_body=a.stem, stem_spring_state=nb + a.spring,
                               clutch=a.clutch, u_signal=len(signals) - 1, pwm=a.pwm,
                               pwm_slot=ext.size,  # one more external slot: the PWM level
                               pwm_freq=a.pwm_freq)
            ext = np.concatenate([ext, [0.0]])
        th = np.zeros(0)
        if self.heat is not None:
            th = th_mod.wire(self.heat[1], state=self.thermal_state, clutch=self.heat[0])
        nc = len(self.clutches)
        npoly = max([len(c.mu_poly) for c in self.clutches], default=1)
        poly = np.zeros((max(nc, 0), npoly))
        for j, c in enumerate(self.clutches):
            poly[j, npoly - len(c.mu_poly) :] = c.mu_poly
        ints = lambda v: np.asarray(v, dtype=np.int64)  # noqa: E731
        floats = lambda v: np.asarray(v, dtype=np.float64)  # noqa: E731
        nsrc = len(self.sources)
        gr_state = np.full(len(self.gears), -1, dtype=np.int64)
        gr_rate_sig = np.full(len(self.gears), -1, dtype=np.int64)
        gr_lim = np.zeros((len(self.gears), 3))
        for i, k in enumerate(moving):
            g = self.gears[k]
            gr_state[k], gr_rate_sig[k] = self.ratio_state + i, nc + nsrc + i
            gr_lim[k] = (*g.ratio_range, g.rate_max)
        net = NetArrays(
            J=floats([b.J for b in self.bodies]),
            drag=floats([b.drag for b in self.bodies]),
            cl_a=ints([c.a for c in self.clutches]),
            cl_b=ints([c.b for c in self.clutches]),
            cl_sig=ints(range(nc)),
            cl_peak=floats([c.peak for c in self.clutches]),
            cl_poly=poly,
            cl_oneway=ints([int(c.oneway) for c in self.clutches]),
            gr_in=ints([g.a for g in self.gears]),
            gr_out=ints([g.b for g in self.gears]),
            gr_ratio=floats([g.ratio for g in self.gears]),
            gr_eta=floats([g.eta for g in self.gears]),
            gr_state=gr_state,
            gr_rate_sig=gr_rate_sig,
            gr_lim=gr_lim,
            sp_a=ints([s.a for s in self.springs]),
            sp_b=ints([s.b for s in self.springs]),
            sp_k=floats([s.k for s in self.springs]),
            sp_d=floats([s.d for s in self.springs]),
            src_body=ints([s.body for s in self.sources]),
            src_sig=ints(range(nc, nc + nsrc)),
            sig=sig,
            tab=tab,
            bps=bps,
            act=act,
            th=th,
        )
        x0 = np.zeros(self.n_state)
        x0[:nb] = [b.w0 for b in self.bodies]
        x0[nb : nb + len(self.springs)] = [s.phi0 for s in self.springs]
        if self.heat is not None:
            x0[self.thermal_state : self.ratio_state] = th_mod.initial_states(th)
        x0[self.ratio_state :] = [self.gears[k].ratio for k in moving]
        return net, x0, ext


@dataclass
class Trajectory:
    """Output of :func:`integrate`: states and element torques on a uniform grid.

    Attributes
    ----------
    t : (n,) time, s
    x : (n, nx) states (speeds rad/s, deflections rad, energy accumulators J, actuator states)
    aux : (n, naux) element torques, N m, in the blocks of :func:`wetclutch.sim.workspace.aux_offsets`
    modes : (n, nc) clutch modes (0 free, +1/-1 sliding, 2 locked)
    events : (m, 3) mode changes: time, clutch index, new mode (the first
        :data:`~wetclutch.sim.workspace.EVENT_LOG`)
    locks : (nc, 2) first and last time each clutch locked (-1: never)
    stats : integrator counters
    """

    network: Network
    t: np.ndarray
    x: np.ndarray
    aux: np.ndarray
    modes: np.ndarray
    events: np.ndarray
    locks: np.ndarray
    stats: dict[str, int]

    @classmethod
    def from_run(cls, network: Network, ws: wsp.Workspace, out_t: np.ndarray, out_x: np.ndarray, out_aux: np.ndarray,
                 out_mode: np.ndarray, n: int | None = None) -> Trajectory:
        """The trajectory of a finished run: its first ``n`` output rows (all that were written if None)."""
        m = int(ws.istate[wsp.IS_N_OUT]) if n is None else min(n, int(ws.istate[wsp.IS_N_OUT]))
        n_ev = min(int(ws.istate[wsp.IS_N_LOG]), ws.evlog.shape[0])
        return cls(network=network, t=out_t[:m], x=out_x[:m], aux=out_aux[:m], modes=out_mode[:m],
                   events=ws.evlog[:n_ev].copy(),
                   locks=ws.fstate[wsp.FS_LOCKS:wsp.fs_ratio.py_func(len(network.clutches))].reshape(-1, 2).copy(),
                   stats={"steps": int(ws.istate[wsp.IS_STEPS]), "rejected": int(ws.istate[wsp.IS_REJECTED]),
                          "events": int(ws.istate[wsp.IS_EVENTS]), "mode_switches": int(ws.istate[wsp.IS_SWITCHES]),
                          "turns": int(ws.istate[wsp.IS_TURNS])})

    def _idx(self, items: list, name: str) -> int:
        for i, it in enumerate(items):
            if it.name == name:
                return i
        # a name of another kind of element, or a typo: one line with the names there are
        kind = type(items[0]).__name__.strip("_").lower() if items else "element"
        raise WetclutchError(f"no {kind} named {name!r} in the network (its {kind} names: "
                             f"{', '.join(it.name for it in items) or 'none'})")

    def _aux(self, block: int, index: int) -> np.ndarray:
        net = self.network
        return self.aux[:, wsp.aux_offsets.py_func(len(net.clutches), len(net.gears), len(net.springs))[block] + index]

    def speed(self, body: str) -> np.ndarray:
        return self.x[:, self._idx(self.network.bodies, body)]

    def clutch_torque(self, clutch: str) -> np.ndarray:
        return self._aux(0, self._idx(self.network.clutches, clutch))

    def capacity(self, clutch: str) -> np.ndarray:
        return np.maximum(self._aux(1, self._idx(self.network.clutches, clutch)), 0.0)

    def locked(self, clutch: str) -> np.ndarray:
        return (self.modes[:, self._idx(self.network.clutches, clutch)] == wsp.LOCKED).astype(np.int8)

    def gear_torque(self, gear: str) -> np.ndarray:
        return self._aux(2, self._idx(self.network.gears, gear))

    def ratio(self, gear: str) -> np.ndarray:
        """The gear's ratio ``w_out / w_in`` over time (constant unless it moves)."""
        net = self.network
        k = self._idx(net.gears, gear)
        moving = net._moving()
        if k not in moving:
            return np.full(self.t.size, net.gears[k].ratio)
        return self.x[:, net.ratio_state + moving.index(k)]

    def spring_torque(self, spring: str) -> np.ndarray:
        return self._aux(3, self._idx(self.network.springs, spring))

    def spring_deflection(self, spring: str) -> np.ndarray:
        return self.x[:, len(self.network.bodies) + self._idx(self.network.springs, spring)]

    def dissipated(self, clutch: str) -> np.ndarray:
        """Energy dissipated in the clutch so far, J."""
        net = self.network
        return self.x[:, len(net.bodies) + len(net.springs) + self._idx(net.clutches, clutch)]

    def actuator_state(self, k: int) -> np.ndarray:
        """The actuator's state ``k`` (:data:`wetclutch.physics.actuator.PRESSURE` ...)."""
        return self.x[:, self.network.actuator_state + k]

    def plate_temperature(self) -> np.ndarray:
        """Temperature of the heated clutch pack's plates, C (:meth:`Network.thermal`)."""
        if self.network.heat is None:
            raise KeyError("the network has no heated clutch pack")
        return self.x[:, self.network.thermal_state + th_mod.PLATE_TEMP]

    def first_lock(self, clutch: str) -> float | None:
        """Time the clutch first locks after sliding, or None."""
        t = self.locks[self._idx(self.network.clutches, clutch), wsp.LOCK_FIRST]
        return float(t) if t >= 0.0 else None

    def sync_time(self, clutch: str) -> float | None:
        """Time the clutch locks for good (stays locked to the end of the run), or None.

        A hard engagement can stick and break loose several times before the two sides
        synchronise; this is the last lock."""
        j = self._idx(self.network.clutches, clutch)
        if self.modes.size == 0 or self.modes[-1, j] != wsp.LOCKED:
            return None
        t = self.locks[j, wsp.LOCK_LAST]
        return float(t) if t >= 0.0 else None

    # -------------------------------------------------------------- energy
    def energies(self) -> dict[str, np.ndarray]:
        """Energy terms over time, J: stored (kinetic, spring), dissipated, supplied."""
        net = self.network
        nb, ns, nc = len(net.bodies), len(net.springs), len(net.clutches)
        J = np.array([b.J for b in net.bodies])
        k = np.array([s.k for s in net.springs])
        e0 = nb + ns
        out = {
            "kinetic": 0.5 * (self.x[:, :nb] ** 2) @ J,
            "spring": 0.5 * (self.x[:, nb:e0] ** 2) @ k if ns else np.zeros_like(self.t),
        }
        for j, c in enumerate(net.clutches):
            out[f"dissipated_{c.name}"] = self.x[:, e0 + j]
        out["dissipated_drag"] = self.x[:, e0 + nc + wsp.E_DRAG]
        out["dissipated_damper"] = self.x[:, e0 + nc + wsp.E_DAMPER]
        out["dissipated_gear"] = self.x[:, e0 + nc + wsp.E_GEAR]
        out["source_work"] = self.x[:, e0 + nc + wsp.E_SOURCE]
        if net.heat is not None:
            # where the heated clutch's dissipation went: into the plates and out with the oil
            j, rec = net.heat
            i0 = net.thermal_state
            out[f"heat_plates_{net.clutches[j].name}"] = rec[th_mod.HEAT_CAP] * (self.x[:, i0 + th_mod.PLATE_TEMP]
                                                                              - rec[th_mod.T_START])
            out[f"heat_oil_{net.clutches[j].name}"] = self.x[:, i0 + th_mod.HEAT_OIL]
        return out

    def energy_residual(self) -> float:
        """Largest |stored + dissipated - initial - supplied| over the run, relative to
        the largest of the initial, stored and supplied energy."""
        e = self.energies()
        if self.network.heat is not None:
            # count the heated clutch's dissipation as the heat it became (plates + oil)
            name = self.network.clutches[self.network.heat[0]].name
            e[f"dissipated_{name}"] = e.pop(f"heat_plates_{name}") + e.pop(f"heat_oil_{name}")
        stored = e["kinetic"] + e["spring"]
        dissipated = sum(v for key, v in e.items() if key.startswith("dissipated_"))
        balance = stored + dissipated - stored[0] - e["source_work"]
        scale = max(float(np.max(np.abs(stored))), float(np.max(np.abs(e["source_work"]))), 1e-300)
        return float(np.max(np.abs(balance)) / scale)


_STATUS = {
    wsp.ERR_SINGULAR: "the motion is not determined",
    wsp.ERR_ZENO: "events pile up at one instant (Zeno behaviour); check the network",
}


def _event_source(network: Network, e: int, n_events: int) -> str:
    """Which element event function ``e`` of ``n_events`` belongs to (for error messages); the layout is
    :func:`wetclutch.sim.workspace.n_events`'s, the valve amplifier's last."""
    nc = len(network.clutches)
    if 0 <= e < 2 * nc:
        return f"clutch {network.clutches[e // 2].name!r}"
    ng = len(network.gears)
    if network.act is not None and e == n_events - 1:
        return ("the valve actuator (its amplifier's regulating range, its coil current's turns, the clutch piston's "
                "stop and contact)")
    if e >= 2 * nc + 2 * ng:
        return f"gear {network.gears[e - 2 * nc - 2 * ng].name!r} (its ratio limits)"
    if e >= 2 * nc:
        return f"gear {network.gears[(e - 2 * nc) // 2].name!r}"
    return "unknown element"


def failure(network: Network, ws: wsp.Workspace, status: int) -> SimulationError:
    """The error to raise for a run that ended with ``status``."""
    msg = _STATUS.get(status, f"integration failed (status {status})")
    if status == wsp.ERR_ZENO:
        source = _event_source(network, int(ws.istate[wsp.IS_LAST_EVENT]), ws.g_old.shape[0])
        msg += f" (at t = {ws.fstate[wsp.FS_T]:.6g} s, {source})"
    elif status == wsp.ERR_SINGULAR:
        k = int(ws.istate[wsp.IS_BAD_BODY])
        who = f"body {network.bodies[k].name!r}" if 0 <= k < len(network.bodies) else "a body"
        if 0 <= k < len(network.bodies) and network.bodies[k].J > 0.0:
            # a body with inertia is determined by itself: what leaves its motion open is the constraints on it
            msg = (f"{msg} at t = {ws.fstate[wsp.FS_T]:.6g} s: the locks and gears on {who} admit no single motion "
                   "(two paths between the same bodies whose constraints the engine cannot reconcile in their present "
                   "modes: a lossy gear whose ratio moves, beside a locked clutch or another gear)")
        else:
            msg = (f"{msg} at t = {ws.fstate[wsp.FS_T]:.6g} s: {who} has no inertia and no lock, gear or "
                   "other body with inertia holds it (give it an inertia, or tie it rigidly)")
    return SimulationError(msg)


def outputs(n: int, nx: int, naux: int, nc: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Empty output buffers for ``n`` rows: times, states, element torques, clutch modes."""
    return np.zeros(n), np.zeros((n, nx)), np.zeros((n, naux)), np.zeros((n, nc), dtype=np.int64)


def integrate(
    network: Network,
    t_end: float,
    dt_out: float = 1e-3,
    rtol: float = 1e-8,
    atol: float | np.ndarray = 1e-10,
    h_max: float = np.inf,
) -> Trajectory:
    """Integrate ``network`` from 0 to ``t_end``, sampling every ``dt_out`` seconds.

    Parameters
    ----------
    rtol, atol
        Local error tolerances of the Dormand-Prince 5(4) step control; ``atol`` is one for every
        state or one per state (:attr:`Network.n_state` of them).
    h_max
        Largest step, s. By default none, but a tenth of the shortest period of the network's sine signals: a
        locked clutch's event function is checked at the ends of each step, and a sine load that rises beyond the
        capacity and falls back within one step would go unseen (a stuck body driven by ``6 sin(2 pi t)`` against a
        5 N m brake broke away at no step of up to a second). A load that exceeds a capacity for a shorter time
        still needs a smaller ``h_max``.
    """
    if not t_end > 0.0:
        raise ValueError("t_end must be > 0")
    if not 0.0 < dt_out <= t_end:
        raise ValueError("dt_out must be in (0, t_end]")
    if not 0.0 < rtol < 1.0:  # a tolerance of 0 or below accepts every step: the run would go on, unchecked
        raise ValueError(f"rtol must be in (0, 1) (got {rtol!r})")
    if not h_max > 0.0:
        raise ValueError(f"h_max must be > 0 (got {h_max!r})")
    net, x0, ext = network.compile()
    if h_max == np.inf:
        h_max = sine_step_limit(net.sig)
    tol = np.asarray(atol, dtype=np.float64)
    if tol.ndim > 1 or tol.size not in (1, x0.size) or not np.all(tol > 0.0):
        raise ValueError(f"atol must be > 0, one value or one per state ({x0.size})")
    tol = np.full(x0.size, tol) if tol.ndim == 0 else tol.copy()
    ws = wsp.new_workspace(net, x0)
    coldstart.begin(net, ext, ws)
    out = outputs(int(round(t_end / dt_out)) + 1, x0.size, ws.aux.size, len(network.clutches))
    status = advance(net, ext, ws, float(t_end), float(dt_out), 0.0, rtol, tol, h_max, *out)
    if status != wsp.OK:
        raise failure(network, ws, status)
    return Trajectory.from_run(network, ws, *out)
