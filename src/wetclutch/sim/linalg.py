"""Dense LU factorisation with partial pivoting, for the small constraint systems of the core.

numba's ``np.linalg`` calls LAPACK and allocates; the core allocates nothing and its
systems have a handful of rows, so a plain loop is both possible and faster.
"""

from .compiled import jit_inline


@jit_inline
def lu_factor(A, piv, n):
    """LU-factor ``A[:n,:n]`` in place with partial pivoting; False if singular."""
    for col in range(n):
        p = col
        best = abs(A[col, col])
        for r in range(col + 1, n):
            v = abs(A[r, col])
            if v > best:
                best = v
                p = r
        if best < 1e-300:
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
