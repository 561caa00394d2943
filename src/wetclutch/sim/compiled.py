"""How the numerical core is compiled.

``error_model='numpy'``: IEEE division semantics, no Python zero-division checks in hot
loops. ``_nrt=False``: the core allocates nothing (every buffer lives in the
:class:`~wetclutch.sim.workspace.Workspace`), so numba's reference counting is pure
overhead; it cost about 60 % of a right-hand-side evaluation. ``fastmath``: fused
multiply-add contraction only; reassociation and signed-zero freedom changed the
actuator's flows (a pressure stuck at zero), and events rely on ``inf``.

``inline="always"`` functions are inlined into their callers at numba's IR level and
compiled with the callers' flags: the core's helpers are small named steps that take the
workspace whole, at no cost in speed. Each call site is a copy to compile, though (numba
copies and types the callee's whole inlined IR again, at a cost that grows faster than its
size), so the big right-hand side is inlined at one call site only, the integrator's stages,
and every other path calls one compiled copy of it (:data:`wetclutch.sim.rhs.rhs_call`).
"""

from numba import njit

FASTMATH = {"contract"}
jit = njit(cache=True, error_model="numpy", _nrt=False, fastmath=FASTMATH)
jit_inline = njit(cache=True, error_model="numpy", inline="always", _nrt=False, fastmath=FASTMATH)
