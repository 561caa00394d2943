"""The Dormand-Prince 5(4) pair: tableau, stages, error estimate and Shampine's dense output.

The scheme of scipy's ``RK45``, written for the core: the tableau as scalars that numba
folds into the code, each stage one straight vectorisable loop.
"""

import numpy as np

from .compiled import jit_inline

C = np.array([0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0])
_A = np.array(
    [
        [0.0, 0.0, 0.0, 0.0, 0.0],
        [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0],
        [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0],
        [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0],
        [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0],
        [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0],
    ]
)
_B = np.array([35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0])
_E = np.array(
    [-71.0 / 57600.0, 0.0, 71.0 / 16695.0, -71.0 / 1920.0, 17253.0 / 339200.0, -22.0 / 525.0, 1.0 / 40.0]
)
# Shampine's 4th-order continuous extension (as in scipy's RK45)
_P = np.array(
    [
        [1.0, -8048581381.0 / 2820520608.0, 8663915743.0 / 2820520608.0, -12715105075.0 / 11282082432.0],
        [0.0, 0.0, 0.0, 0.0],
        [0.0, 131558114200.0 / 32700410799.0, -68118460800.0 / 10900136933.0, 87487479700.0 / 32700410799.0],
        [0.0, -1754552775.0 / 470086768.0, 14199869525.0 / 1410260304.0, -10690763975.0 / 1880347072.0],
        [0.0, 127303824393.0 / 49829197408.0, -318862633887.0 / 49829197408.0, 701980252875.0 / 199316789632.0],
        [0.0, -282668133.0 / 205662961.0, 2019193451.0 / 616988883.0, -1453857185.0 / 822651844.0],
        [0.0, 40617522.0 / 29380423.0, -110615467.0 / 29380423.0, 69997945.0 / 29380423.0],
    ]
)


# the tableau as scalars: numba folds them into the code, and each stage becomes one
# straight vectorisable loop instead of a loop over stages inside a loop over states
(_A10,) = _A[1, :1]
_A20, _A21 = _A[2, :2]
_A30, _A31, _A32 = _A[3, :3]
_A40, _A41, _A42, _A43 = _A[4, :4]
_A50, _A51, _A52, _A53, _A54 = _A[5, :5]
_B0, _B1, _B2, _B3, _B4, _B5 = _B
_E0, _E1, _E2, _E3, _E4, _E5, _E6 = _E


@jit_inline
def stage(y0, K, h, s, out):
    """State at stage ``s`` (1..5) of a Dormand-Prince step; ``s == 6`` is the 5th-order solution."""
    n = y0.shape[0]
    if s == 1:
        for i in range(n):
            out[i] = y0[i] + h * (_A10 * K[0, i])
    elif s == 2:
        for i in range(n):
            out[i] = y0[i] + h * (_A20 * K[0, i] + _A21 * K[1, i])
    elif s == 3:
        for i in range(n):
            out[i] = y0[i] + h * (_A30 * K[0, i] + _A31 * K[1, i] + _A32 * K[2, i])
    elif s == 4:
        for i in range(n):
            out[i] = y0[i] + h * (_A40 * K[0, i] + _A41 * K[1, i] + _A42 * K[2, i] + _A43 * K[3, i])
    elif s == 5:
        for i in range(n):
            out[i] = y0[i] + h * (_A50 * K[0, i] + _A51 * K[1, i] + _A52 * K[2, i] + _A53 * K[3, i] + _A54 * K[4, i])
    else:
        for i in range(n):
            out[i] = y0[i] + h * (_B0 * K[0, i] + _B2 * K[2, i] + _B3 * K[3, i] + _B4 * K[4, i] + _B5 * K[5, i])


@jit_inline
def error_norm(y0, y1, K, h, rtol, atol, buf):
    """RMS of the embedded error estimate scaled by ``atol + rtol |y|`` (``atol`` per state); ``buf`` is scratch.

    The squares go through ``buf`` so that the divisions run as one vector loop apart from
    the (ordered, hence serial) sum: 25 instead of 45 ns per step.
    """
    n = y0.shape[0]
    for i in range(n):
        e = _E0 * K[0, i] + _E2 * K[2, i] + _E3 * K[3, i] + _E4 * K[4, i] + _E5 * K[5, i] + _E6 * K[6, i]
        sc = atol[i] + rtol * max(abs(y0[i]), abs(y1[i]))
        r = h * e / sc
        buf[i] = r * r
    acc = 0.0
    for i in range(n):
        acc += buf[i]
    return np.sqrt(acc / n)


@jit_inline
def weights(theta, bw):
    """The dense output's stage weights at ``theta`` (0..1 of the step) into ``bw``."""
    for s in range(7):
        th = theta
        v = 0.0
        for j in range(4):
            v += _P[s, j] * th
            th *= theta
        bw[s] = v


@jit_inline
def component(y0, K, h, bw, i):
    """State ``i`` of the dense output at the weights ``bw`` (:func:`weights`)."""
    acc = 0.0
    for s in range(7):
        acc += bw[s] * K[s, i]
    return y0[i] + h * acc


@jit_inline
def dense(y0, K, h, theta, out, bw):
    weights(theta, bw)
    for i in range(y0.shape[0]):
        out[i] = component(y0, K, h, bw, i)
