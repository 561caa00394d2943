"""The plate friction law: normal force, the friction knee, and its inverse.

The clutch's torque capacity is

    T_max = mu(slip) * F_n * F_n / (F_n + F_knee),    F_n = A_p (p - p_contact) for p > p_contact, else 0

``mu(slip)`` lumps the number of friction faces, their effective radius and the
friction coefficient (metres; the study's fit ``-1.7e-6 w^2 + 2.7e-4 w + 2.6e-2``,
``w`` in rad/s), and the knee ``F_n / (F_n + F_knee)`` is the drop of friction at
low normal force that the study saw below 1 V ("plates barely pressed"). A
rational knee rather than ``1 - exp(-F_n/F_knee)``: the same shape to within the
study's scatter, without a transcendental function in every evaluation.

A clutch's curve differs from the study's fit in level (``mu_scale``) and in steepness
(``mu_slope``: the change of ``mu`` with slip scaled about its mean over a launch's slip
range, so that a steeper curve has the same mean friction); :func:`curve` makes the
polynomial the model runs on.

Each function is compiled for the numerical core (inlined there) and, being plain
arithmetic, also runs on floats and numpy arrays through ``.py_func`` for
identification and post-processing, so the law is written once.
"""

from __future__ import annotations

import numpy as np
from numba import njit

_inline = njit(cache=True, error_model="numpy", _nrt=False, inline="always")


@_inline
def normal_force(p, p_contact, a_p):
    """Plate normal force (N) at clutch pressure ``p`` (Pa): zero until the plates touch."""
    return a_p * np.maximum(p - p_contact, 0.0)


@_inline
def knee(f_n, f_knee):
    """Share of the full friction at normal force ``f_n``: ``f_n / (f_n + f_knee)`` (1 without a knee)."""
    return f_n / (f_n + f_knee) if f_knee > 0.0 else 1.0


@_inline
def force_for(f_eff, f_knee):
    """The normal force whose knee-reduced force ``f_n^2 / (f_n + f_knee)`` is ``f_eff`` (the inverse of the knee)."""
    return 0.5 * (f_eff + np.sqrt(f_eff * f_eff + 4.0 * f_eff * f_knee))


@_inline
def mu(coef, slip):
    """``mu`` at ``|slip|`` (rad/s) from polynomial coefficients ``coef``, highest power first (Horner)."""
    s = abs(slip)
    v = 0.0
    for c in coef:
        v = v * s + c
    return v
