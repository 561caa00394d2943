"""Automatic-transmission fluid (ATF) properties for the hydraulic actuator model.

SI units inside (Pa, kg/m^3, Pa s, m^2/s); ``temp_C`` in degrees C, ``p`` gauge pressure in Pa.

* Kinematic viscosity: Walther equation (ASTM D341), ``log10(log10(nu_cSt + 0.7)) = A - B log10(T_K)``,
  A, B through two points. Defaults are typical Dexron-III/Mercon data sheet values (about 35 cSt at
  40 C, 7.5 cSt at 100 C): typical of the class, not one product. The 0.7 form holds down to about
  2 cSt (reached near 200 C); below about -20 C it underestimates real ATFs.
* Dynamic viscosity: ``rho nu exp(alpha p)`` (Barus); alpha about 1.5e-8 1/Pa is typical of light
  mineral oils.
* Density: ``rho_15 (1 - beta (T - 15)) (1 + p / K_oil)``; beta about 7e-4 1/K for mineral oils.
* Bulk modulus: pure-oil isentropic modulus about 1.6 GPa at 20 C (mineral oils 1.4-1.8 GPa), falling
  about 0.5 %/K; exponential with slope ``dK_dT`` at 20 C so it stays positive up to 200 C. Entrained
  air is a series compliance (Merritt, *Hydraulic Control Systems*, 1967, sec. 2.5):
  ``1/K_eff = (1 - x)/K_oil + x/(kappa p_abs)``, the free-air volume shrinking polytropically,
  ``V_air = V_air0 (p_atm/p_abs)^(1/kappa)``, from ``air_fraction`` at atmospheric pressure;
  kappa = 1 (isothermal): finely dispersed bubbles exchange heat with the oil within the
  tens of milliseconds of a clutch fill (Merritt gives 1 <= kappa <= 1.4); it also keeps the
  compiled actuator free of a power function, which cost a fifth of its run time.

Each formula is written once as plain arithmetic valid for floats and numpy arrays: the public
functions run it with numpy; the compiled actuator kernel uses the compliance's ``numba.njit``
compilation (:data:`compliance_nb`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from ..errors import ParameterError
from ..params import OIL_TEMP_RANGE_C

P_ATM = 101325.0  #: atmospheric pressure, Pa
KAPPA_AIR = 1.0  #: polytropic index of entrained air (isothermal, see the module docstring)
T_MIN_C, T_MAX_C = OIL_TEMP_RANGE_C  #: temperatures the model is used at, C
_T0_K = 273.15


@dataclass(frozen=True)
class OilModel:
    """ATF coefficients (SI units; defaults: typical Dexron-III class ATF)."""

    rho_15: float = 850.0  #: density at 15 C and 0 Pa gauge, kg/m^3
    beta: float = 7.0e-4  #: volumetric thermal expansion coefficient, 1/K
    nu_40_cSt: float = 35.0  #: kinematic viscosity at 40 C, cSt (Walther point 1)
    nu_100_cSt: float = 7.5  #: kinematic viscosity at 100 C, cSt (Walther point 2)
    alpha_barus: float = 1.5e-8  #: Barus pressure-viscosity coefficient, 1/Pa
    K_20: float = 1.6e9  #: pure-oil isentropic bulk modulus at 20 C, Pa
    dK_dT: float = -8.0e6  #: dK/dT at 20 C, Pa/K (-0.5 %/K of K_20)
    air_fraction: float = 0.005  #: entrained-air volume fraction at atmospheric pressure

    def __post_init__(self):
        if not self.nu_40_cSt > self.nu_100_cSt > 2.0:
            raise ParameterError("nu_40_cSt > nu_100_cSt > 2 cSt required (Walther/ASTM D341 range)")
        for name in ("rho_15", "beta", "alpha_barus", "K_20"):  # dK_dT: any sign keeps K > 0
            if not getattr(self, name) > 0.0:
                raise ParameterError(f"{name} must be positive, got {getattr(self, name)}")
        _check_air(self.air_fraction)

    @property
    def walther(self) -> tuple[float, float]:
        """Walther coefficients ``(A, B)`` through the 40 C and 100 C points."""
        z40 = np.log10(np.log10(self.nu_40_cSt + 0.7))
        z100 = np.log10(np.log10(self.nu_100_cSt + 0.7))
        lt40, lt100 = np.log10(40.0 + _T0_K), np.log10(100.0 + _T0_K)
        b = (z40 - z100) / (lt100 - lt40)
        return float(z40 + b * lt40), float(b)


def _check_air(x):
    if not 0.0 <= x < 1.0:
        raise ParameterError(f"air_fraction must be in [0, 1), got {x}")


# --- formulas, written once: plain arithmetic for floats and numpy arrays ---
def _nu(temp_C, a, b):
    # Walther/ASTM D341 solved for nu; cSt -> m^2/s
    return (10.0 ** (10.0 ** (a - b * np.log10(temp_C + _T0_K))) - 0.7) * 1e-6


def _k_oil(temp_C, k_20, dk_dt):
    # exponential so the slope at 20 C is dk_dt but K never reaches zero at high temperature
    return k_20 * np.exp(dk_dt / k_20 * (temp_C - 20.0))


def _rho(temp_C, p, rho_15, beta, k_oil):
    return rho_15 * (1.0 - beta * (temp_C - 15.0)) * (1.0 + p / k_oil)


def _mu(nu, rho, p, alpha):
    return rho * nu * np.exp(alpha * p)  # Barus


def _compliance(p, k_oil, x0):
    # 1 / K_eff (the actuator's capacitance is volume x compliance: two divisions fewer per evaluation)
    inv_p = 1.0 / (P_ATM + p)  # absolute pressure
    v_air = x0 * (P_ATM * inv_p) ** (1.0 / KAPPA_AIR)  # air volume per unit atmospheric mixture volume
    x = v_air / (v_air + 1.0 - x0)  # current air fraction (oil compression negligible here)
    return (1.0 - x) * (1.0 / k_oil) + x * inv_p * (1.0 / KAPPA_AIR)


# the actuator's compiled kernel evaluates the compliance in every right-hand side
compliance_nb = numba.njit(cache=True)(_compliance)

DEFAULT = OilModel()


# --- public numpy API ---
def _args(temp_C, p=0.0):
    """Validated float arrays (at least 1-d, broadcast) and whether the input was scalar."""
    t, pp = np.asarray(temp_C, dtype=float), np.asarray(p, dtype=float)
    bad = ~((t >= T_MIN_C) & (t <= T_MAX_C))  # also catches NaN
    if bad.any():
        raise ParameterError(f"temp_C must be within [{T_MIN_C:g}, {T_MAX_C:g}] C, got {t[bad].flat[0]:g}")
    bad_p = ~(pp > -P_ATM)
    if bad_p.any():
        raise ParameterError(f"p (gauge, Pa) must exceed -{P_ATM:g} Pa, got {pp[bad_p].flat[0]:g}")
    scalar = t.ndim == 0 and pp.ndim == 0
    # scalars run through the same 1-element array path, so they equal the array results exactly
    t, pp = np.broadcast_arrays(np.atleast_1d(t), np.atleast_1d(pp))
    return t, pp, scalar


def _out(x, scalar):
    return float(x[0]) if scalar else x



def kinematic_viscosity(temp_C, *, model: OilModel = DEFAULT):
    """Kinematic viscosity at atmospheric pressure (Walther/ASTM D341), m^2/s.

    Parameters
    ----------
    temp_C : float or array_like
        Temperature, C, in :data:`T_MIN_C` .. :data:`T_MAX_C`. Arrays give arrays, floats give floats (all functions).
    model : OilModel, optional
        Coefficients; the default is a typical Dexron-III class ATF.
    """
    t, _, scalar = _args(temp_C)
    return _out(_nu(t, *model.walther), scalar)


def density(temp_C, p=0.0, *, model: OilModel = DEFAULT):
    """Density of the liquid oil, kg/m^3 (``temp_C`` in C, ``p`` gauge Pa; broadcast)."""
    t, pp, scalar = _args(temp_C, p)
    return _out(_rho(t, pp, model.rho_15, model.beta, _k_oil(t, model.K_20, model.dK_dT)), scalar)


def dynamic_viscosity(temp_C, p=0.0, *, model: OilModel = DEFAULT):
    """Dynamic viscosity with the Barus pressure factor, Pa s (``temp_C`` in C, ``p`` gauge Pa)."""
    t, pp, scalar = _args(temp_C, p)
    rho = _rho(t, pp, model.rho_15, model.beta, _k_oil(t, model.K_20, model.dK_dT))
    return _out(_mu(_nu(t, *model.walther), rho, pp, model.alpha_barus), scalar)


def drag_at(drag_20C: float, temp_C: float) -> float:
    """The open plates' viscous drag coefficient (N m s) at ``temp_C`` (C) from its value at 20 C: the oil's shear
    between the plates scales with its dynamic viscosity."""
    return drag_20C * dynamic_viscosity(temp_C) / dynamic_viscosity(20.0)


def bulk_modulus(temp_C, p=0.0, *, air_fraction: float | None = None, model: OilModel = DEFAULT):
    """Effective isentropic bulk modulus of oil with entrained air, Pa.

    Parameters
    ----------
    temp_C, p : float or array_like
        Temperature, C (:data:`T_MIN_C` .. :data:`T_MAX_C`); gauge pressure, Pa (> -101325). Broadcast together.
    air_fraction : float, optional
        Free-air volume fraction at atmospheric pressure; ``None``: ``model.air_fraction`` (0.005),
        0: pure oil.
    model : OilModel, optional
        Coefficients.
    """
    x0 = model.air_fraction if air_fraction is None else float(air_fraction)
    _check_air(x0)
    t, pp, scalar = _args(temp_C, p)
    return _out(1.0 / _compliance(pp, _k_oil(t, model.K_20, model.dK_dT), x0), scalar)
