"""The integrator's records: modes, status codes, the workspace and the layouts of its arrays.

This module owns every flat record the integrator keeps besides the network itself: it
names the slots of the running state (``fstate``, ``istate``), the blocks of the element
torques (``aux``) and of the state vector's energy accumulators, and
:func:`new_workspace` alone allocates and fills a workspace.

State vector ``x``: body speeds (nb), spring deflections (ns), the energy accumulators
(the dissipation of each clutch (nc), then :data:`N_ENERGY_EXTRA` more: drag, damper and
gear losses and the work of the sources), then the actuator's states, if any, the heated
pack's, if any, and the ratios of the gears whose ratio moves (a CVT shifting), if any.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .compiled import jit_inline

# clutch modes; +1 / -1 are sliding forward / backward
FREE, LOCKED, UNDECIDED = 0, 2, 99
#: in ``Workspace.fact``: no constraint factors made yet
NO_MODE = -99
#: a gear held at standstill (+3 / -3: sign of the held output torque); +1 / -1: power flowing forward / back
STUCK = 3
#: a lossy gear that carries no torque (+2 / -2: the power flow it had): the locks and gears beside it hold its
#: constraint already (a lossy gear beside a locked clutch, two lossy gears in parallel), so its torque is not
#: determined, and this one of the distributions within every element's limits loses no power in it. Decided
#: afresh at each mode decision (:func:`wetclutch.sim.modes.settle`); an ideal gear has no modes at all (it stays +1)
IDLE = 2

# status codes returned by the core
OK, ERR_SINGULAR, ERR_ZENO = 0, 1, 2

# energy accumulators after the clutches' dissipation
E_DRAG, E_DAMPER, E_GEAR, E_SOURCE = range(4)
N_ENERGY_EXTRA = 4

# fstate: the float part of the running state
FS_T = 0  # current time
FS_H = 1  # proposed next step
FS_LOG_ERR = 2  # log of the previous accepted step's error (PI step control)
FS_PWM_NEXT = 3  # time of the next PWM edge (-inf: not started)
FS_PWM_START = 4  # start of the current PWM period
FS_PWM_H = 5  # + level (0 or 1): the first step after the last edge to that level (0: none yet)
FS_AMP = 7  # the valve amplifier's mode (actuator.REGULATE, SATURATED, FREEWHEEL; decided at restarts)
FS_AMP_G = 8  # the actuator's event function (amplifier, play and piston) at the last evaluation of the right-hand side
FS_PISTON = 9  # the clutch piston's mode (actuator.AT_STOP, STROKING, AT_PLATES; decided at restarts)
# the magnet's play at the current step's start (actuator.play_step; its magnetisation is the state's slot): the coil
# current, its direction (+1 rising, -1 falling; decided at restarts), the play's flow path and its lag there
FS_PLAY_CUR, FS_PLAY_DIR, FS_PLAY_TAU, FS_PLAY_G = 10, 11, 12, 13
FS_LOCKS = 14  # + 2 j + LOCK_FIRST / LOCK_LAST: first and last time clutch j locked (-1: never)
LOCK_FIRST, LOCK_LAST = 0, 1
N_FSTATE = FS_LOCKS  # without the lock times, which follow, two per clutch, the gears' slots (fs_ratio) and the
# clutches' grip margins (fs_grip)

# istate: the integer part
IS_SETTLE = 0  # what must be decided again before the next step: nothing (0), SETTLE_ALL or SETTLE_INPUT
#: every mode (a change of the state or of an input that may move a force at once)
SETTLE_ALL = 1
#: the valve amplifier's mode and the coil current's direction only: a jump of the valve's input alone moves no force
#: at once (the coil's inductance keeps its current, hence the magnet's force and all that follows, continuous), so
#: no clutch, brake, gear or piston can change its mode there; the workspace must be as the last ``advance`` left it
#: (its first stage is reused but for the coil current's rate)
SETTLE_INPUT = 2
IS_N_OUT = 1  # output rows written
IS_STEPS = 2  # accepted steps
IS_REJECTED = 3  # rejected steps
IS_EVENTS = 4  # located events
IS_SWITCHES = 5  # clutch mode changes
IS_N_LOG = 6  # mode changes logged (may exceed the log's length)
IS_LAST_EVENT = 7  # event function of the last event
IS_BAD_BODY = 8  # a body whose motion the network does not determine (-1: none)
IS_REDUNDANT = 9  # 1: the current constraint factors are the least-norm ones of redundant locks
IS_TURNS = 10  # located events that were the coil current turning (the engine's, for the magnet's play; in IS_EVENTS)
IS_CACHE_NEXT = 11  # the slot of the constraint solutions' cache (FACTOR_CACHE) that the next miss fills
N_ISTATE = 12
#: constraint solutions kept for this many mode and ratio combinations (rows of ``Workspace.A`` after its own): a
#: valve stem that sticks and slips with each edge of the input's dither switches between two, whose factors
#: would otherwise be remade at every switch
FACTOR_CACHE = 4

EVENT_LOG = 4096  # rows of the mode-change log (time, clutch, new mode); later changes are counted, not logged


@jit_inline
def aux_offsets(nc, ng, ns):
    """Start of each block of the element torques ``aux``: clutch torques (nc), capacities (nc),
    gear output torques (ng), spring torques (ns), gear input torques (ng)."""
    return 0, nc, 2 * nc, 2 * nc + ng, 2 * nc + ng + ns


@jit_inline
def fs_ratio(nc):
    """Start of the gears' slots in ``fstate``, ``ng`` each, after the lock times: the ratios the constraint
    factors were made with (+ g), whether a moving ratio is held at its least (-1) or greatest (+1) value
    while its command pushes beyond (+ ng + g: a mode, decided at restarts), and the latest commanded rate
    (+ 2 ng + g, for its event function)."""
    return FS_LOCKS + 2 * nc


@jit_inline
def fs_grip(nc, ng):
    """Start of the clutches' slots in ``fstate``, one each, after the gears': the relative margin by which a
    locked clutch's torque must exceed its static capacity to let go (0; :data:`GRIP` after a grazing
    breakaway, doubled with each further one in a row up to :data:`GRIP_MAX`, until the clutch lets go)."""
    return FS_LOCKS + 2 * nc + 3 * ng


#: the margin of a grazing breakaway: a lock whose torque touches its capacity and turns back (a valve stem
#: creeping to rest at its friction's limit) let go and stuck again at one instant, since slip and torque
#: margin sit below rounding there; holding the lock until the torque exceeds the capacity by this much makes
#: the breakaway a real one
GRIP = 1e-9
#: the most a grazing clutch's grip margin grows to, when its torque turns back beyond the capacity by more than GRIP
GRIP_MAX = 1e-6


def moving_gears(net) -> int:
    """Number of gears of the compiled network ``net`` whose ratio moves (a state)."""
    return int(np.count_nonzero(net.gr_state >= 0))


def n_events(net) -> int:
    """Number of event functions of the compiled network ``net``: two per clutch and per gear, one per moving
    ratio (its limits; none without moving ratios), one for a valve actuator (its amplifier's regulating range, its
    coil current's turns, its piston's stop and contact)."""
    nc, ng = net.cl_a.size, net.gr_in.size
    return 2 * nc + 2 * ng + (ng if moving_gears(net) else 0) + (1 if net.act.size else 0)


def aux_size(nc: int, ng: int, ns: int) -> int:
    return 2 * nc + 2 * ng + ns


class Workspace(NamedTuple):
    """Preallocated buffers and the integrator's running state for one network.

    Non-inlined core functions take it by value: a 26th array made every step of a run
    10 % slower, so new running state goes into the existing arrays' named slots.
    """

    x: np.ndarray  # current state
    clm: np.ndarray  # clutch modes
    grm: np.ndarray  # gear modes (+1 forward, -1 backward, +-STUCK held at standstill, +-IDLE carrying nothing)
    fstate: np.ndarray  # (N_FSTATE + 3 nc + 3 ng,) see FS_*, fs_ratio and fs_grip
    istate: np.ndarray  # (N_ISTATE,) see IS_*
    K: np.ndarray  # (7, nx) stages
    dx: np.ndarray
    aux: np.ndarray
    aux_new: np.ndarray
    g_old: np.ndarray
    g_new: np.ndarray
    A: np.ndarray  # (3 nmat + 1 + FACTOR_CACHE (nmat + 1), nmat) LU factors of the constraint matrix for the current
    # modes; the rows below are the SVD's scratch (U S, V, singular values) when the matrix is singular (redundant
    # locks), then the cache of solutions (:func:`wetclutch.sim.rhs.factors`)
    z: np.ndarray
    piv: np.ndarray
    sol: np.ndarray  # (nmat,) scratch: one column of the inverse constraint matrix
    G: np.ndarray  # (nmat, nb) torque-to-solution columns of the inverse constraint matrix; with moving ratios
    # (nmat, nb + ng): then also the columns of the gears' rows, which carry their velocity terms
    y_new: np.ndarray
    y_tmp: np.ndarray
    bw: np.ndarray  # (7,) dense-output weights
    y_old: np.ndarray  # state at the start of the current step
    clm_before: np.ndarray  # clutch modes before a restart
    released: np.ndarray  # (nc + ng) scratch for the mode decision
    fact: np.ndarray  # (nc + ng + 1) clutch and gear modes the factors in A, G were made for, then 0 once made
    evlog: np.ndarray  # (EVENT_LOG, 3): t, clutch index, new mode


def new_workspace(net, x0: np.ndarray, t0: float = 0.0, h0: float = 1e-4) -> Workspace:
    """Fresh integrator state for the compiled network ``net`` starting at ``(t0, x0)``; modes are
    decided on the first call."""
    nx = x0.size
    nb = net.J.size
    nc = net.cl_a.size
    ng = net.gr_in.size
    ns = net.sp_k.size
    nmat = nb + nc + 2 * ng
    naux = aux_size(nc, ng, ns)
    # a moving ratio adds an event function (its limits) and a velocity-term column per gear
    n_mov = ng if moving_gears(net) else 0
    fstate = np.zeros(N_FSTATE + 3 * nc + 3 * ng)
    fstate[FS_T], fstate[FS_H], fstate[FS_LOG_ERR] = t0, h0, np.log(1e-4)
    fstate[FS_PWM_NEXT], fstate[FS_PWM_START] = -np.inf, t0
    fstate[FS_PLAY_DIR] = 1.0
    fstate[FS_LOCKS:FS_LOCKS + 2 * nc] = -1.0
    fstate[FS_LOCKS + 2 * nc:FS_LOCKS + 2 * nc + ng] = np.nan  # no factors made yet
    istate = np.zeros(N_ISTATE, dtype=np.int64)
    istate[IS_SETTLE], istate[IS_LAST_EVENT], istate[IS_BAD_BODY] = SETTLE_ALL, -1, -1
    return Workspace(
        x=x0.astype(np.float64).copy(),
        clm=np.full(nc, UNDECIDED, dtype=np.int64),
        grm=np.ones(ng, dtype=np.int64),
        fstate=fstate,
        istate=istate,
        K=np.zeros((7, nx)),
        dx=np.zeros(nx),
        aux=np.zeros(max(naux, 1)),
        aux_new=np.zeros(max(naux, 1)),
        g_old=np.zeros(max(n_events(net), 1)),
        g_new=np.zeros(max(n_events(net), 1)),
        A=np.zeros((3 * max(nmat, 1) + 1 + FACTOR_CACHE * (max(nmat, 1) + 1), max(nmat, 1))),
        z=np.zeros(max(nmat, 1)),
        piv=np.zeros(max(nmat, 1), dtype=np.int64),
        sol=np.zeros(max(nmat, 1)),
        G=np.zeros((max(nmat, 1), max(nb + n_mov, 1))),
        y_new=np.zeros(nx),
        y_tmp=np.zeros(nx),
        bw=np.zeros(7),
        y_old=np.zeros(nx),
        clm_before=np.zeros(nc, dtype=np.int64),
        released=np.zeros(nc + ng, dtype=np.int64),
        fact=np.full(nc + ng + 1, NO_MODE, dtype=np.int64),  # the modes the factors were made for, then whether made
        evlog=np.zeros((EVENT_LOG, 3)),
    )
