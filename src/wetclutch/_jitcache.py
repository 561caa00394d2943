"""Keep numba's on-disk cache consistent across the compiled modules.

numba invalidates a cached function when *its own* source file changes, but not
when a jitted function it calls (and inlines) from another module changes: the
integrator would then run stale actuator code. At import, the sources of every
module of the package that uses numba are hashed together; if the hash differs
from the one recorded beside a cache, that cache's files of the package are
removed so that everything is compiled afresh once. numba keeps the cache in the
source tree, under ``NUMBA_CACHE_DIR`` when that is set, or in the user's cache
directory when the source tree is read-only: each place is checked.
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


STAMP = "wetclutch-core.sha256"


def _probe() -> None:
    """A function for numba's cache locators to place (they need one; only its file's directory matters)."""


def cache_places() -> list[tuple[Path, list[Path]]]:
    """Where numba may keep the package's machine code: for each place, the file that records the sources' hash
    and the directories of the compiled modules' cache files."""
    modules = compiled_modules()
    places = [(_PKG / "__pycache__" / STAMP, [m.parent / "__pycache__" for m in modules])]
    try:
        from numba.core import caching, config

        kinds = [caching.UserWideCacheLocator]
        if config.CACHE_DIR:
            kinds.append(caching.UserProvidedCacheLocator)
        for kind in kinds:
            stamp = Path(kind(_probe, str(_PKG / "__init__.py")).get_cache_path()) / STAMP
            places.append((stamp, [Path(kind(_probe, str(m)).get_cache_path()) for m in modules]))
    except (ImportError, AttributeError, TypeError):
        # a numba whose cache locators differ: the source tree's cache is still kept consistent
        pass
    return places


def ensure_consistent() -> None:
    h = hashlib.sha256()
    for m in compiled_modules():
        h.update(str(m.relative_to(_PKG)).encode())
        h.update(m.read_bytes())
    digest = h.hexdigest()
    for stamp, dirs in cache_places():
        try:
            if stamp.read_text() == digest:
                continue
        except OSError:
            pass
        try:
            for d in sorted(set(dirs)):
                for f in d.glob("*.nb[ic]"):
                    f.unlink(missing_ok=True)
            stamp.parent.mkdir(parents=True, exist_ok=True)
            stamp.write_text(digest)
        except OSError:
            # a read-only place: numba then caches elsewhere or not at all
            pass
