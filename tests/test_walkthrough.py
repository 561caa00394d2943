"""The worked example runs top to bottom and writes what it says it writes."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import jupytext

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "walkthrough.py"


def test_walkthrough_is_a_notebook_and_runs(tmp_path):
    nb = jupytext.read(EXAMPLE)  # opens as a notebook: markdown and code cells
    kinds = {c.cell_type for c in nb.cells}
    assert kinds == {"markdown", "code"} and len(nb.cells) >= 10
    out = tmp_path / "walk"
    r = subprocess.run([sys.executable, str(EXAMPLE), str(out)], capture_output=True, text=True, check=False,
                       cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "CVT ratio: identified" in r.stdout and "verify: 4 launches" in r.stdout
    ratio = float(r.stdout.split("CVT ratio: identified ")[1].split()[0])
    assert abs(ratio - 0.6) < 0.01  # the rig's true ratio, found from its files
    for f in ("rig/step41/measured.mf4", "identify/params.toml", "identify/report.html", "verify/verify.html",
              "launch.png", "step41.png"):
        assert (out / f).is_file(), f
