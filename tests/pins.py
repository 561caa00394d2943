"""Pinned outputs: hashes of whole results, for changes that must not change them.

A restructuring of the code (moving modules, splitting functions, renaming) must leave
every number the package computes bit for bit as it was. This module computes five
representative outputs and hashes their full-precision values:

* ``engage``: the study's driveline run (signals and summary);
* ``coupled-clutches``: the Modelica benchmark network;
* ``rig-pwm-step``: a PWM step on the virtual rig (measured channels and true states);
* ``launch``: one closed-loop launch (measured signals, true signals, figures);
* ``identify``: identification from rig files (every estimate).

``python tests/pins.py`` prints the hashes; ``python tests/pins.py --write`` records them
in ``tests/data/pins.json`` together with the host's CPU (floating-point results are
reproducible on one CPU model; fused multiply-adds and library versions may differ on
another). A change that is meant to change results re-records the pins and says why in
its commit message.
"""

from __future__ import annotations

import hashlib
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

PIN_FILE = Path(__file__).resolve().parent / "data" / "pins.json"


def _digest(*parts: Any) -> str:
    h = hashlib.sha256()
    for part in parts:
        if isinstance(part, pd.DataFrame):
            h.update(",".join(map(str, part.columns)).encode())
            h.update(np.ascontiguousarray(part.to_numpy(dtype=np.float64)).tobytes())
        elif isinstance(part, np.ndarray):
            h.update(np.ascontiguousarray(part, dtype=np.float64).tobytes())
        else:
            h.update(json.dumps(part, sort_keys=True, default=repr).encode())
    return h.hexdigest()


def _scrub_paths(obj: Any, root: str) -> Any:
    if isinstance(obj, dict):
        return {k: _scrub_paths(v, root) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_scrub_paths(v, root) for v in obj]
    if isinstance(obj, str):
        return obj.replace(root, "<root>")
    return obj


def outputs() -> dict[str, dict[str, Any]]:
    """name -> {"hash": sha256 of the full output, "figures": a few headline numbers}."""
    import wetclutch as wc
    from wetclutch import ident, launch, rig
    from wetclutch.launch import metrics
    from wetclutch.params import Params
    from wetclutch.report import rig as rig_report

    out: dict[str, dict[str, Any]] = {}
    eng = wc.simulate("engage")
    out["engage"] = {"hash": _digest(eng.signals, eng.summary),
                     "figures": {"t_sync": eng.summary["t_sync"], "E_clutch": eng.summary["E_clutch"]}}
    cc = wc.simulate("coupled-clutches")
    out["coupled-clutches"] = {"hash": _digest(cc.signals, cc.summary),
                               "figures": {"J4_w_end": float(cc.signals["J4_w"].iloc[-1])}}
    step = rig.run("step", input_mode="pwm", level=0.2, oil_temp_C=41.0, seed=3)
    out["rig-pwm-step"] = {"hash": _digest(step.measured, step.truth, step.meta["t_sync"]),
                           "figures": {"t_sync": step.meta["t_sync"],
                                       "p_end_Pa": float(step.truth["p_clutch"].iloc[-1])}}
    la = launch.simulate(Params(), "launch", launch.Conditions(t_ref=100.0, oil_temp_C=85.0),
                         nominal=metrics.Response.empty())
    out["launch"] = {"hash": _digest(la.signals, la.truth, la.summary),
                     "figures": {k: la.summary[k] for k in ("t95_s", "overshoot_pct", "t_sync_s")}}
    with tempfile.TemporaryDirectory() as tmp:
        runs = {"dc85": dict(level=2.5, oil_temp_C=85.0, seed=2),
                "stair": dict(experiment="staircase", config="valve-only", input_mode="pwm", level=0.15, from_=0.0,
                              seed=3)}
        rig_report.write(step, Path(tmp) / "pwm41")
        recs = [ident.load(Path(tmp) / "pwm41" / "measured.csv")]
        for name, kw in runs.items():
            kw = dict(kw)
            res = rig.run(kw.pop("experiment", "step"), Params(), **kw)
            rig_report.write(res, Path(tmp) / name)
            recs.append(ident.load(Path(tmp) / name / "measured.csv"))
        found = ident.identify(recs)
        content = _scrub_paths(json.loads(json.dumps(found.as_json(), default=float)), tmp)
    out["identify"] = {"hash": _digest(content),
                       "figures": {"contact_pressure_Pa": found.estimates["contact_pressure_Pa"].value,
                                   "mu0": found.estimates["mu_slip_poly"].value[-1]}}
    return out


def host_cpu() -> str:
    import llvmlite.binding as llvm

    return llvm.get_host_cpu_name()


def main() -> None:
    res = outputs()
    for name, v in res.items():
        print(f"{name:18s} {v['hash']}  {v['figures']}")
    if "--write" in sys.argv[1:]:
        PIN_FILE.parent.mkdir(exist_ok=True)
        PIN_FILE.write_text(json.dumps({"cpu": host_cpu(), "outputs": res}, indent=2) + "\n")
        print(f"wrote {PIN_FILE}")


if __name__ == "__main__":
    main()
