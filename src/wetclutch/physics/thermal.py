"""The clutch pack's heat: one lumped thermal state, heated by the slip power, cooled by the oil flow.

    C dT/dt = P_slip - h (T - T_oil)          plate temperature T (C)
    dQ/dt   = h (T - T_oil)                   heat carried off by the oil (J)

``C`` is the heat capacity of the plates (steel separator plates and the friction plates'
steel cores, with the oil held between them), ``h`` the heat transfer from the plates to the
cooling oil flowing through the pack, ``T_oil`` the oil temperature of the run. The slip power
``P_slip = T_c * slip`` is what the engine already integrates as the clutch's dissipation, so
``C (T - T_0) + Q`` equals the clutch's dissipated energy: the energy balance still closes,
with the heat counted where it went.

Friction may depend on the plate temperature: the clutch's capacity is multiplied by
``1 + mu_temp (T - T_mu_ref)`` (never below zero); ``mu_temp`` is 0 by default, since the study
found hardly any relation between friction and temperature.

This module owns the flat thermal record: it names the offsets, and :func:`pack` alone fills
one (the engine adds where its states sit). The engine calls :func:`rates` and
:func:`friction_factor` from its right-hand side.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..params import Params

# layout of the flat thermal record (indices into ``th``)
(
    STATE,  # index of the plate temperature in the state vector (the heat to the oil follows)
    CLUTCH,  # index of the clutch whose slip heats the pack
    HEAT_CAP,  # C, J/K
    H_OIL,  # h, W/K
    T_OIL,  # oil temperature, C
    T_START,  # plate temperature at the start of the run, C
    MU_TEMP,  # relative change of friction per kelvin of plate temperature, 1/K
    T_MU_REF,  # plate temperature at which friction is the nominal one, C
    N_TH,
) = range(9)

N_STATES = 2
PLATE_TEMP, HEAT_OIL = range(N_STATES)


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def rates(x, th, p_slip, dx):
    """Plate temperature and heat-to-oil rates into ``dx`` for slip power ``p_slip`` (W)."""
    i0 = int(th[STATE])
    q = th[H_OIL] * (x[i0 + PLATE_TEMP] - th[T_OIL])
    dx[i0 + PLATE_TEMP] = (p_slip - q) * (1.0 / th[HEAT_CAP])
    dx[i0 + HEAT_OIL] = q


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def friction_factor(x, th):
    """Multiplier on the clutch's capacity at the current plate temperature (1 with ``mu_temp`` 0)."""
    return max(1.0 + th[MU_TEMP] * (x[int(th[STATE]) + PLATE_TEMP] - th[T_MU_REF]), 0.0)


def pack(params: Params, temp_C: float, plate_temp_C: float | None = None) -> np.ndarray:
    """The thermal record at oil temperature ``temp_C``; the plates start at ``plate_temp_C`` (the oil's if None).

    The wiring (:data:`STATE`, :data:`CLUTCH`) is set by :meth:`wetclutch.sim.network.Network.thermal`.
    """
    t = params.thermal
    r = np.zeros(N_TH)
    r[HEAT_CAP], r[H_OIL], r[T_OIL] = t.C_pack, t.h_oil, temp_C
    r[T_START] = temp_C if plate_temp_C is None else plate_temp_C
    r[MU_TEMP], r[T_MU_REF] = t.mu_temp, t.T_mu_ref_C
    return r


def initial_states(record: np.ndarray) -> np.ndarray:
    """The thermal block of the initial state vector: plate temperature, no heat given to the oil yet."""
    return np.array([record[T_START], 0.0])


def wire(record: np.ndarray, *, state: int, clutch: int) -> np.ndarray:
    """A copy of ``record`` placed in a compiled network (first state index, heated clutch)."""
    r = np.asarray(record, dtype=np.float64).copy()
    r[STATE], r[CLUTCH] = state, clutch
    return r


def closed_form(t, p_slip: float, record: np.ndarray):
    """Plate temperature (C) under constant slip power from the start: ``T_oil + dT_inf + (T_0 - T_oil - dT_inf) e^(-t/tau)``.

    ``dT_inf = P / h`` and ``tau = C / h``; the reference for tests and for sizing a sequence of launches.
    """
    h, c = record[H_OIL], record[HEAT_CAP]
    dt_inf = p_slip / h
    return record[T_OIL] + dt_inf + (record[T_START] - record[T_OIL] - dt_inf) * np.exp(-h * np.asarray(t) / c)
