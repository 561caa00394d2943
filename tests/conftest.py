"""Shared fixtures. Runs of the default rig are computed once per test session."""

from __future__ import annotations

from pathlib import Path

import pytest

import wetclutch as wc

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
