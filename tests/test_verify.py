"""Verification runs: sampling, determinism, replay."""

import shlex

import numpy as np
import pytest

from wetclutch import cli
from wetclutch.launch import verify
from wetclutch.errors import WetclutchError


def test_samples_cover_the_ranges_and_are_deterministic():
    a = verify.samples(200, seed=7)
    b = verify.samples(200, seed=7)
    assert [s.values for s in a] == [s.values for s in b]
    assert len(a) == 200 + 2 ** len(verify.CORNERS)
    rnd = [s for s in a if not s.corner]
    for name, (_, lo, hi, _) in verify.RANGES.items():
        v = np.array([s.values[name] for s in rnd])
        assert lo <= v.min() and v.max() <= hi
        assert v.max() - v.min() > 0.8 * (hi - lo)  # spread over the range
    assert verify.samples(5, seed=8)[-1].values != a[-1].values


def test_sample_parameters_scale_or_set():
    s = verify.samples(1, seed=1)[-1]
    p = s.params()
    assert p.friction.mu_scale == s.values["friction.mu_scale"]
    assert p.driveline.k_a == pytest.approx(480.0 * s.values["driveline.k_a"])


def test_small_run_is_deterministic_and_replayable(tmp_path):
    a = verify.run(2, seed=5, workers=1, corners=False, progress=False)
    b = verify.run(2, seed=5, workers=1, corners=False, progress=False)
    assert [r["metrics"] for r in a["results"]] == [r["metrics"] for r in b["results"]]
    assert set(a) >= {"pass_rate", "pass_rate_per_requirement", "results", "percentiles", "worst"}
    # the replay command reproduces the sample's launch
    r = a["results"][0]
    argv = shlex.split(r["replay"])[1:]
    argv[argv.index("--out") + 1] = str(tmp_path / "replay")
    assert cli.main(argv) == 0
    import json

    summary = json.loads((tmp_path / "replay" / "summary.json").read_text())
    for key in ("t95_s", "steady_state_error_pct", "overshoot_pct"):
        assert summary[key] == pytest.approx(r["metrics"][key], rel=1e-9)


def test_bad_options():
    with pytest.raises(WetclutchError, match="--samples"):
        verify.run(-1, progress=False)
    with pytest.raises(WetclutchError, match="--workers"):
        verify.run(1, workers=0, progress=False)
