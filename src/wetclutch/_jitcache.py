"""Keep numba's on-disk cache consistent across the compiled modules.

numba invalidates a cached function when *its own* source file changes, but not
when a jitted function it calls (and inlines) from another module changes: the
engine would then run stale actuator code. At import, the compiled modules'
sources are hashed together; if the hash differs from the one recorded beside
the cache, the package's numba cache files are removed so that everything is
compiled afresh once.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

_PKG = Path(__file__).resolve().parent
#: modules whose jitted functions call each other
CORE = ("signals.py", "oil.py", "actuator.py", "engine.py", "control.py", "launch.py")


def ensure_consistent() -> None:
    cache = _PKG / "__pycache__"
    digest = hashlib.sha256(b"".join((_PKG / m).read_bytes() for m in CORE)).hexdigest()
    stamp = cache / "wetclutch-core.sha256"
    try:
        if stamp.read_text() == digest:
            return
    except OSError:
        pass
    try:
        cache.mkdir(exist_ok=True)
        for f in cache.glob("*.nb[ic]"):
            f.unlink(missing_ok=True)
        stamp.write_text(digest)
    except OSError:
        # a read-only install: numba then caches elsewhere or not at all
        pass
