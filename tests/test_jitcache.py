"""The compiled core's cache is cleared wherever numba keeps it when the package's sources change.

numba checks a cached function against its own source file only; a change in a function it
inlines from another module would go unseen. The package clears its cache files on import when
the hash of all compiled sources differs from the recorded one: in the source tree and under
``NUMBA_CACHE_DIR`` alike (numba places the cache there when it is set).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

_CALL = """
import json, sys
import wetclutch
from wetclutch import _jitcache
from wetclutch.physics import actuator
actuator.magnet_force(0.2, actuator.pack(wetclutch.Params(), 85.0))
print(json.dumps([[str(stamp), [str(d) for d in dirs]] for stamp, dirs in _jitcache.cache_places()]))
"""


def _run(code: str, cache_dir: Path) -> str:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache_dir)}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return out.stdout


def test_a_stale_cache_under_numba_cache_dir_is_cleared(tmp_path: Path) -> None:
    places = json.loads(_run(_CALL, tmp_path).strip().splitlines()[-1])
    cached = sorted(tmp_path.rglob("*.nbi"))
    assert cached, "numba wrote no cache files under NUMBA_CACHE_DIR"
    # the place the package checks is where numba put them
    dirs = {Path(d) for stamp, ds in places if Path(stamp).is_relative_to(tmp_path) for d in ds}
    assert all(f.parent in dirs for f in cached)
    stamp = next(Path(s) for s, _ in places if Path(s).is_relative_to(tmp_path))
    digest = stamp.read_text()

    # the same sources: the cache stays
    _run("import wetclutch", tmp_path)
    assert sorted(tmp_path.rglob("*.nbi")) == cached

    # sources other than those the cache was made from: its files go, the new hash is recorded
    stamp.write_text("made from other sources")
    _run("import wetclutch", tmp_path)
    assert not list(tmp_path.rglob("*.nb[ic]"))
    assert stamp.read_text() == digest
