"""The package's outputs equal the pinned ones (see ``tests/pins.py``)."""

import json

import pytest

import pins


@pytest.mark.slow
def test_outputs_equal_the_pinned_ones():
    computed = pins.outputs()
    pinned = json.loads(pins.PIN_FILE.read_text())
    assert computed.keys() == pinned["outputs"].keys()
    for name, v in pinned["outputs"].items():
        # a closed loop with stick/slip and noise amplifies rounding: its figures are compared more loosely
        rel = 1e-2 if name == "launch" else 1e-6
        for key, value in v["figures"].items():
            assert computed[name]["figures"][key] == pytest.approx(value, rel=rel, abs=1e-9), (name, key)
    # bit for bit on the CPU the pins were recorded on; another CPU may round differently (fused
    # multiply-adds), which the figures above tolerate
    if pins.host_cpu() == pinned["cpu"]:
        assert {k: v["hash"] for k, v in computed.items()} == {k: v["hash"] for k, v in pinned["outputs"].items()}
