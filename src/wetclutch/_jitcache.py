"""Keep numba's on-disk cache consistent across the compiled modules.

numba invalidates a cached function when *its own* source file changes, but not
when a jitted function it calls (and inlines) from another module changes: the
integrator would then run stale actuator code. At import, the sources of every
module of the package that uses numba are hashed together; if the hash differs
from the one recorded beside the cache, the package's numba cache files are
removed so that everything is compiled afresh once.
"""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

_PKG = Path(__file__).resolve().parent


#: a module compiles something if it calls numba's njit or decorates a function with a jit decorator
_COMPILES = re.compile(rb"njit\(|^\s*@\w*jit\w*\b", re.MULTILINE)


def compiled_modules() -> list[Path]:
    """The package's modules that compile functions with numba, in a fixed order."""
    return sorted(p for p in _PKG.rglob("*.py") if "__pycache__" not in p.parts and _COMPILES.search(p.read_bytes()))


def ensure_consistent() -> None:
    h = hashlib.sha256()
    for m in compiled_modules():
        h.update(str(m.relative_to(_PKG)).encode())
        h.update(m.read_bytes())
    digest = h.hexdigest()
    cache = _PKG / "__pycache__"
    stamp = cache / "wetclutch-core.sha256"
    try:
        if stamp.read_text() == digest:
            return
    except OSError:
        pass
    try:
        cache.mkdir(exist_ok=True)
        for f in _PKG.rglob("__pycache__/*.nb[ic]"):
            f.unlink(missing_ok=True)
        stamp.write_text(digest)
    except OSError:
        # a read-only install: numba then caches elsewhere or not at all
        pass
