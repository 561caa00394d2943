"""The study's driveline as a network.

::

    primary J_p --clutch--> J_1 --CVT (i, eta)--> r --axle (k_a, d_a)--> J_s --brake--> ground

Bodies: ``p`` (primary flywheel, air drag ``b_1``), ``1`` (clutch output and CVT
input, small inertia ``J_1``), ``r`` (CVT output, massless: the CVT ties it
rigidly to ``1``) and ``s`` (secondary flywheel, air drag ``b_2``). The
eddy-current brake is a Coulomb brake on ``s`` whose capacity is the road
load, so a car at rest stays at rest until the axle torque overcomes it.

Measured quantities of the rig: ``T_r`` is the axle torque right of the CVT,
``T_c`` the clutch torque, ``omega_1`` / ``omega_r`` the speeds left and right of
the CVT.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..sim.network import Network, Trajectory
from ..params import Params
from ..physics import thermal
from ..sim.signals import Signal

#: column -> unit of the driveline signals table
COLUMNS = {
    "time": "s",
    "omega_p": "rad/s",
    "omega_1": "rad/s",
    "omega_r": "rad/s",
    "omega_s": "rad/s",
    "T_c": "N m",
    "T_r": "N m",
    "T_cap": "N m",
    "locked": "-",
    "slip": "rad/s",
    "T_brake": "N m",
    "brake_locked": "-",
    "T_plate": "C",
}


def build(params: Params, capacity: Signal | float, road_load: Signal | float | None = None, *,
          temp_C: float | None = None, plate_temp_C: float | None = None, ratio_rate: Signal | None = None) -> Network:
    """The driveline network with clutch capacity ``capacity(t)`` (N m) and road load (N m).

    The clutch pack heats up with its slip power and is cooled by the oil at ``temp_C``
    (``rig.oil_temp_C`` if None); its plates start at ``plate_temp_C`` (the oil's if None).
    With ``ratio_rate`` (1/s) the CVT's ratio moves at that commanded rate within the limits
    ``driveline.ratio_min``, ``ratio_max`` and ``ratio_rate``; without it the ratio is constant.
    """
    d = params.driveline
    net = Network()
    p = net.body("p", d.J_p, w0=d.omega_p0, drag=d.b_1)
    one = net.body("1", d.J_1)
    r = net.body("r", 0.0)
    s = net.body("s", d.J_s, drag=d.b_2)
    ci = net.clutch("clutch", p, one, capacity, peak=params.clutch.peak)
    net.thermal(ci, thermal.pack(params, params.rig.oil_temp_C if temp_C is None else temp_C, plate_temp_C))
    net.brake("brake", s, params.engage.T_load if road_load is None else road_load)
    if ratio_rate is None:
        net.gear("cvt", one, r, d.ratio, d.eta)
    else:
        net.gear("cvt", one, r, d.ratio, d.eta, rate=ratio_rate, ratio_range=(d.ratio_min, d.ratio_max),
                 rate_max=d.ratio_rate)
    net.spring("axle", r, s, d.k_a, d.d_a)
    return net


def frame(tr: Trajectory) -> pd.DataFrame:
    """The driveline signals table (columns :data:`COLUMNS`, SI units)."""
    w_p, w_1 = tr.speed("p"), tr.speed("1")
    return pd.DataFrame(
        {
            "time": tr.t,
            "omega_p": w_p,
            "omega_1": w_1,
            "omega_r": tr.speed("r"),
            "omega_s": tr.speed("s"),
            "T_c": tr.clutch_torque("clutch"),
            "T_r": tr.spring_torque("axle"),
            "T_cap": tr.capacity("clutch"),
            "locked": tr.locked("clutch"),
            "slip": w_p - w_1,
            "T_brake": tr.clutch_torque("brake"),
            "brake_locked": tr.locked("brake"),
            "T_plate": tr.plate_temperature(),
        }
    )


def summary(tr: Trajectory) -> dict:
    """Figures of one driveline run: synchronisation, peak torque, energy account."""
    e = tr.energies()
    T_r = tr.spring_torque("axle")
    return {
        "t_sync": tr.sync_time("clutch"),
        "T_r_peak": float(np.max(np.abs(T_r))),
        "E_clutch": float(e["dissipated_clutch"][-1]),
        "E_brake": float(e["dissipated_brake"][-1]),
        "E_drag": float(e["dissipated_drag"][-1]),
        "E_damper": float(e["dissipated_damper"][-1]),
        "E_cvt": float(e["dissipated_gear"][-1]),
        "E_initial": float(e["kinetic"][0] + e["spring"][0]),
        "E_heat_plates": float(e["heat_plates_clutch"][-1]),
        "E_heat_oil": float(e["heat_oil_clutch"][-1]),
        "T_plate_peak": float(np.max(tr.plate_temperature())),
        "T_plate_end": float(tr.plate_temperature()[-1]),
        "energy_residual": tr.energy_residual(),
        "mode_switches": tr.stats["mode_switches"],
        "steps": tr.stats["steps"],
        "events": tr.stats["events"],
    }


def reduced_inertias(p: Params, ratio: float) -> tuple[float, float]:
    """Two-mass inertias at the axle with power flowing forward and back through the CVT (the primary side seen
    through ``eta`` and ``1/eta``), kg m^2."""
    d = p.driveline
    j_a = d.J_p + d.J_1
    red = lambda j: j * d.J_s / (j + d.J_s)  # noqa: E731
    return red(d.eta * j_a / ratio**2), red(j_a / (d.eta * ratio**2))


def axle_for(p: Params, ratio: float, freq_hz: float, zeta: float | None = None) -> tuple[float, float | None]:
    """Axle stiffness (N m/rad) that makes the locked driveline ring at ``freq_hz``, and the damping (N m s/rad)
    for damping ratio ``zeta`` (None if not given).

    With power flowing alternately forward and back through the CVT, the half periods use
    the two reduced inertias ``J_f``, ``J_b`` of :func:`reduced_inertias`:
    ``k_a = (f pi (sqrt(J_f) + sqrt(J_b)))^2``.
    """
    j_f, j_b = reduced_inertias(p, ratio)
    k_a = (freq_hz * np.pi * (np.sqrt(j_f) + np.sqrt(j_b))) ** 2
    d_a = None if zeta is None else float(2.0 * zeta * np.sqrt(k_a * 0.5 * (j_f + j_b)))
    return float(k_a), d_a


def ring_frequency(t: np.ndarray, y: np.ndarray) -> float:
    """Frequency (Hz) of an oscillation from the mean spacing of its upward crossings of its mean.

    Used on ``T_r`` after synchronisation, where the driveline rings freely.
    """
    y = y - np.mean(y)
    i = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0))
    if i.size < 2:
        return float("nan")
    tc = t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])
    return float((tc.size - 1) / (tc[-1] - tc[0]))
