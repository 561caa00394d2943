"""Shared fixtures. Runs of the default rig are computed once per test session."""

from __future__ import annotations

import subprocess
from collections.abc import Callable, Sequence
from pathlib import Path

import pytest

import wetclutch as wc
from inprocess import invoke

REFERENCE = Path(__file__).resolve().parents[2] / "shared" / "reference"


@pytest.hookimpl(trylast=True)  # after the terminal reporter's, whose writer says what the pause is
def pytest_configure(config: pytest.Config) -> None:
    """With pytest-xdist's workers (``-n``), compile the numba core once in the controlling process before they start:
    on a cold cache every worker would otherwise compile the same functions into the same cache at the same time."""
    if hasattr(config, "workerinput") or not getattr(config.option, "numprocesses", None):
        return
    from wetclutch.launch import Conditions
    from wetclutch.launch import simulate as launch
    from wetclutch.rig import experiments as rig

    config.get_terminal_writer().line("compiling the numba core once for the workers (a minute or two on a cold cache)")
    try:
        wc.simulate("engage")
        rig.run("step", input_mode="pwm", t_end=1.5)
        for kind in ("launch", "baseline"):
            launch(wc.Params(), kind, Conditions(t_max=1.6))
    except Exception:  # a broken core fails its own tests, by their names, not the whole session here
        pass


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
