"""Shared fixtures. Runs of the default rig are computed once per test session."""

from __future__ import annotations

import subprocess
from collections.abc import Callable, Sequence
from pathlib import Path

import pytest

import wetclutch as wc
from inprocess import invoke

REFERENCE = Path(__file__).resolve().parents[2] / "shared" / "reference"


@pytest.fixture(scope="session")
def reference() -> Path:
    """The shared reference data (../shared/reference beside the checkout); missing data fails."""
    if not REFERENCE.is_dir():
        raise FileNotFoundError(f"reference data not found at {REFERENCE}")
    return REFERENCE


@pytest.fixture(scope="session")
def engage_default() -> wc.Result:
    return wc.simulate("engage")


def _refused(args: Sequence[str], fragment: str, out: Path) -> subprocess.CompletedProcess:
    r = invoke([*args, "--out", str(out)])
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and fragment in lines[0], r.stderr
    assert not out.exists()
    return r


@pytest.fixture(scope="session")
def cli_refuses() -> Callable[[Sequence[str], str, Path], subprocess.CompletedProcess]:
    """``cli_refuses(args, fragment, out)``: ``wetclutch ARGS --out OUT`` exits 2 with one line of error
    naming ``fragment`` and writes nothing; returns the finished process for further checks."""
    return _refused
