"""Tests of the ATF property model (wetclutch.physics.oil)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wetclutch.physics import oil
from wetclutch.errors import ParameterError

CST = 1e-6  # m^2/s per cSt


def test_reference_viscosities_reproduced():
    m = oil.DEFAULT
    assert oil.kinematic_viscosity(40.0) == pytest.approx(m.nu_40_cSt * CST, rel=1e-6)
    assert oil.kinematic_viscosity(100.0) == pytest.approx(m.nu_100_cSt * CST, rel=1e-6)


def test_custom_model_reference_points():
    m = oil.OilModel(nu_40_cSt=30.0, nu_100_cSt=6.0)
    nu = oil.kinematic_viscosity(np.array([40.0, 100.0]), model=m)
    np.testing.assert_allclose(nu, [30.0 * CST, 6.0 * CST], rtol=1e-6)


def test_viscosity_decreases_monotonically():
    t = np.linspace(-20.0, 150.0, 341)
    assert np.all(np.diff(oil.kinematic_viscosity(t)) < 0.0)
    assert np.all(np.diff(oil.dynamic_viscosity(t)) < 0.0)


def test_viscosity_ratio_typical_atf():
    ratio = oil.kinematic_viscosity(41.0) / oil.kinematic_viscosity(85.0)
    assert 2.5 < ratio < 5.0


def test_pressure_raises_dynamic_viscosity_by_barus_factor():
    mu0, mu1 = oil.dynamic_viscosity(60.0), oil.dynamic_viscosity(60.0, 1e7)
    rho_ratio = oil.density(60.0, 1e7) / oil.density(60.0)
    assert mu1 / mu0 == pytest.approx(rho_ratio * math.exp(oil.DEFAULT.alpha_barus * 1e7), rel=1e-12)


def test_density_reference_and_trends():
    assert oil.density(15.0, 0.0) == pytest.approx(oil.DEFAULT.rho_15, rel=1e-12)
    assert oil.density(85.0) < oil.density(20.0)
    assert oil.density(20.0, 1e7) > oil.density(20.0)


def test_bulk_modulus_trends():
    t = np.linspace(oil.T_MIN_C, oil.T_MAX_C, 49)
    for x in (0.0, 0.005):
        assert np.all(np.diff(oil.bulk_modulus(t, 5e6, air_fraction=x)) < 0.0)
    p = np.linspace(0.0, 5e7, 101)
    k = oil.bulk_modulus(40.0, p)  # default: with entrained air
    assert np.all(np.diff(k) > 0.0)
    assert k[-1] < oil.bulk_modulus(40.0, 5e7, air_fraction=0.0)  # air always softens
    # pure oil: K_20 at 20 C, slope dK_dT there
    assert oil.bulk_modulus(20.0, air_fraction=0.0) == pytest.approx(oil.DEFAULT.K_20, rel=1e-12)
    h = 1e-3
    slope = (oil.bulk_modulus(20.0 + h, air_fraction=0.0) - oil.bulk_modulus(20.0 - h, air_fraction=0.0)) / (2 * h)
    assert slope == pytest.approx(oil.DEFAULT.dK_dT, rel=1e-6)


FUNCS = [
    (oil.kinematic_viscosity, False),
    (oil.density, True),
    (oil.dynamic_viscosity, True),
    (oil.bulk_modulus, True),
]
TEMPS = np.linspace(oil.T_MIN_C, oil.T_MAX_C, 37)


@pytest.mark.parametrize(("func", "has_p"), FUNCS)
def test_scalar_and_array_identical(func, has_p):
    args = (3e6,) if has_p else ()
    arr = func(TEMPS, *args)
    assert isinstance(arr, np.ndarray) and arr.shape == TEMPS.shape
    scalars = [func(float(t), *args) for t in TEMPS]
    assert all(type(s) is float for s in scalars)
    np.testing.assert_array_equal(arr, scalars)


@pytest.mark.parametrize("air", [0.0, 0.005, 0.02])
@pytest.mark.parametrize("temp", [20.0, 85.0])
def test_compiled_compliance_is_the_mixtures_bulk_modulus(air, temp):
    # the actuator kernel uses the compiled compliance with the pure-oil modulus and the air fraction; checked against
    # the definition K = -V dp/dV of the mixture's volume: oil of constant modulus plus air compressed
    # polytropically from the atmosphere (central difference; the model neglects the oil's own compression in the
    # volume fractions, 0.2 % at 3 MPa, hence the tolerance)
    k_oil = oil.bulk_modulus(temp, air_fraction=0.0)

    def volume(p):
        return (1.0 - air) * np.exp(-p / k_oil) + air * (oil.P_ATM / (oil.P_ATM + p)) ** (1.0 / oil.KAPPA_AIR)

    for p in (0.0, 2e5, 3e6):
        h = 1e-3 * (oil.P_ATM + p)
        k_def = -volume(p) * 2.0 * h / (volume(p + h) - volume(p - h))
        k_compiled = 1.0 / oil.compliance_nb(p, k_oil, air)
        assert k_compiled == pytest.approx(k_def, rel=3e-3)
        assert oil.bulk_modulus(temp, p, air_fraction=air) == pytest.approx(k_def, rel=3e-3)


def test_broadcast_temperature_and_pressure():
    k = oil.bulk_modulus(TEMPS[:, None], np.array([0.0, 1e6, 1e7]))
    assert k.shape == (TEMPS.size, 3)
    assert k[5, 2] == oil.bulk_modulus(TEMPS[5], 1e7)


@pytest.mark.parametrize("func", [f for f, _ in FUNCS])
@pytest.mark.parametrize("temp", [oil.T_MIN_C - 0.1, oil.T_MAX_C + 0.5, float("nan"), np.array([20.0, 250.0])])
def test_out_of_range_temperature_raises(func, temp):
    with pytest.raises(ParameterError, match="temp_C") as info:
        func(temp)
    assert "\n" not in str(info.value)


def test_bad_pressure_and_air_fraction_raise():
    with pytest.raises(ParameterError, match="p "):
        oil.density(20.0, -2e5)
    with pytest.raises(ParameterError, match="air_fraction"):
        oil.bulk_modulus(20.0, air_fraction=1.5)
    with pytest.raises(ParameterError, match="nu_40_cSt"):
        oil.OilModel(nu_40_cSt=5.0)


def test_range_edges_accepted():
    assert oil.kinematic_viscosity(oil.T_MIN_C) > oil.kinematic_viscosity(oil.T_MAX_C) > 2.0 * CST


@settings(max_examples=200, deadline=None)
@given(
    temp=st.floats(min_value=oil.T_MIN_C, max_value=oil.T_MAX_C),
    p=st.floats(min_value=0.0, max_value=1e8),
    air=st.floats(min_value=0.0, max_value=0.2),
)
def test_properties_finite_and_positive(temp, p, air):
    values = [
        oil.kinematic_viscosity(temp),
        oil.density(temp, p),
        oil.dynamic_viscosity(temp, p),
        oil.bulk_modulus(temp, p),
        oil.bulk_modulus(temp, p, air_fraction=air),
    ]
    assert all(math.isfinite(v) and v > 0.0 for v in values)
