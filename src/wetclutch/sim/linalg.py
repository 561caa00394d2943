"""Dense LU factorisation with partial pivoting and a one-sided Jacobi SVD, for the small constraint
systems of the core.

numba's ``np.linalg`` calls LAPACK and allocates; the core allocates nothing and its
systems have a handful of rows, so a plain loop is both possible and faster. The SVD is
the fallback for a rank-deficient system (redundant locks): it gives the least-norm
solution and the null space.
"""

import numpy as np

from .compiled import jit_inline


@jit_inline
def lu_factor(A, piv, n, tiny=1e-300):
    """LU-factor ``A[:n,:n]`` in place with partial pivoting; False if a pivot is ``<= tiny`` (singular)."""
    for col in range(n):
        p = col
        best = abs(A[col, col])
        for r in range(col + 1, n):
            v = abs(A[r, col])
            if v > best:
                best = v
                p = r
        if best <= tiny:
            return False
        piv[col] = p
        if p != col:
            for c in range(n):
                tmp = A[col, c]
                A[col, c] = A[p, c]
                A[p, c] = tmp
        inv = 1.0 / A[col, col]
        for r in range(col + 1, n):
            A[r, col] *= inv
            f = A[r, col]
            if f != 0.0:
                for c in range(col + 1, n):
                    A[r, c] -= f * A[col, c]
    return True


@jit_inline
def lu_solve(A, piv, b, n):
    """Solve with the factors of :func:`lu_factor`; the result replaces ``b``."""
    for col in range(n):
        p = piv[col]
        if p != col:
            tmp = b[col]
            b[col] = b[p]
            b[p] = tmp
    for r in range(1, n):
        acc = b[r]
        for c in range(r):
            acc -= A[r, c] * b[c]
        b[r] = acc
    for r in range(n - 1, -1, -1):
        acc = b[r]
        for c in range(r + 1, n):
            acc -= A[r, c] * b[c]
        b[r] = acc / A[r, r]


@jit_inline
def svd_jacobi(A, o_u, o_v, n):
    """One-sided Jacobi SVD of the square matrix in rows ``o_u .. o_u + n`` of ``A`` (columns ``:n``).

    In place: on return those rows hold ``U S`` (column ``j`` is the left singular vector
    times the singular value ``s_j``), rows ``o_v .. o_v + n`` the right singular vectors
    ``V`` (column ``j``), and row ``o_v + n`` the singular values. Accurate to the last bits for
    the small, well-scaled systems of the core, rank-deficient ones included.
    """
    for i in range(n):
        for j in range(n):
            A[o_v + i, j] = 1.0 if i == j else 0.0
    for _ in range(80):
        rotated = False
        for p in range(n - 1):
            for q in range(p + 1, n):
                alpha = 0.0
                beta = 0.0
                gamma = 0.0
                for k in range(n):
                    up = A[o_u + k, p]
                    uq = A[o_u + k, q]
                    alpha += up * up
                    beta += uq * uq
                    gamma += up * uq
                if gamma == 0.0 or abs(gamma) <= 1e-15 * np.sqrt(alpha * beta):
                    continue
                rotated = True
                zeta = (beta - alpha) / (2.0 * gamma)
                if abs(zeta) > 1e150:
                    t = 0.5 / zeta
                else:
                    t = (1.0 if zeta >= 0.0 else -1.0) / (abs(zeta) + np.sqrt(1.0 + zeta * zeta))
                c = 1.0 / np.sqrt(1.0 + t * t)
                s = c * t
                for k in range(n):
                    up = A[o_u + k, p]
                    uq = A[o_u + k, q]
                    A[o_u + k, p] = c * up - s * uq
                    A[o_u + k, q] = s * up + c * uq
                    vp = A[o_v + k, p]
                    vq = A[o_v + k, q]
                    A[o_v + k, p] = c * vp - s * vq
                    A[o_v + k, q] = s * vp + c * vq
        if not rotated:
            break
    for j in range(n):
        acc = 0.0
        for k in range(n):
            acc += A[o_u + k, j] * A[o_u + k, j]
        A[o_v + n, j] = np.sqrt(acc)
