"""The whole chain on clutches unlike the built-in rig: rig runs -> identify -> design -> verify.

For each clutch below the virtual rig runs the experiments a user would run on their own clutch
(a clutch step at 41 C and at 85 C, a valve staircase in PWM), ``identify`` turns the recordings into
a parameter set, the launch controller is designed on it, and the design is verified over the
shipped ranges twice: on the identified plant (what the user's own verification shows) and on the
clutch itself (what the vehicle sees, including what the rig runs could not identify, such as the
clutch output inertia). Each sample is a sequence of launches with the adaptation carried over;
the table gives the pass rate of all requirements on the last launch and on the first.

Not a timing: the figures are the acceptance of the chain on other clutches (>= 95 %).

Usage: ``python benchmarks/other_clutches.py [--samples N] [--seed S] [--sequence K] [--only NAME ...]``
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from wetclutch import ident
from wetclutch.launch import design, verify
from wetclutch.params import load
from wetclutch.report import rig as rig_report
from wetclutch.rig import experiments as rig

#: the clutches (parameter overrides of the built-in rig) and what makes each unlike it
CLUTCHES = {
    "steeper friction, heavier parts": {
        "friction.mu_slip_poly": [-1.4e-6, 2.4e-4, 0.029], "friction.mu_scale": 1.05,
        "hydraulics.p_prestress": 0.62e5, "hydraulics.x_contact": 1.62e-3,
        "driveline.ratio": 0.75, "driveline.J_1": 2.5e-3, "driveline.J_p": 1.4, "driveline.J_s": 5.5},
    "high kiss point, low friction": {
        "friction.mu_scale": 0.88, "hydraulics.p_prestress": 1.1e5, "hydraulics.x_contact": 1.1e-3,
        "driveline.ratio": 0.6, "driveline.J_1": 1.5e-3, "driveline.J_p": 0.8, "driveline.J_s": 3.2,
        "valve.d_stem": 80.0},
    "low kiss point, long stroke": {
        "friction.mu_slope": 1.4, "hydraulics.p_prestress": 0.3e5, "hydraulics.x_contact": 1.9e-3,
        "hydraulics.leak_85C": 4e-12, "hydraulics.p_supply": 7.2e5,
        "driveline.ratio": 0.9, "driveline.J_1": 4e-3, "driveline.J_p": 1.8, "driveline.J_s": 9.0,
        "driveline.k_a": 380.0},
    "2 bar kiss point, overdrive ratio": {
        "friction.mu_scale": 1.15, "friction.drag_20C": 0.02, "hydraulics.p_prestress": 2e5,
        "hydraulics.x_contact": 1.4e-3, "hydraulics.p_supply": 1e6, "hydraulics.p_relief": 1e6,
        "hydraulics.A_p": 0.0105, "driveline.ratio": 1.25, "driveline.J_1": 2e-3, "driveline.J_p": 0.9,
        "driveline.J_s": 5.0, "valve.F_friction": 0.15, "valve.I_hyst": 0.06},
    "moderate changes": {
        "friction.mu_slip_poly": [-2.2e-6, 3.2e-4, 0.024], "hydraulics.p_prestress": 0.8e5,
        "hydraulics.x_contact": 1.1e-3, "driveline.ratio": 0.65, "driveline.J_1": 1.5e-3, "driveline.J_p": 1.0,
        "driveline.J_s": 7.5},
    "friction falling steeply at high slip": {
        "friction.mu_slip_poly": [-1.8e-6, 2.0e-4, 0.030], "friction.mu_scale": 0.92, "hydraulics.p_prestress": 0.45e5,
        "hydraulics.x_contact": 1.25e-3, "driveline.ratio": 0.55, "driveline.J_1": 1.2e-3, "driveline.J_p": 1.1,
        "driveline.J_s": 6.0},
    "1.4 bar prestress, short stroke, heavy output": {
        "friction.mu_scale": 0.95, "friction.mu_slope": 0.7, "hydraulics.p_prestress": 1.4e5,
        "hydraulics.x_contact": 0.9e-3, "driveline.ratio": 0.8, "driveline.J_1": 3e-3, "driveline.J_p": 0.7,
        "driveline.J_s": 4.0, "valve.d_stem": 45.0},
    "stiff axle, short ratio": {
        "friction.mu_scale": 1.1, "friction.mu_slope": 1.25, "hydraulics.p_prestress": 0.9e5,
        "hydraulics.x_contact": 1.6e-3, "driveline.ratio": 0.42, "driveline.J_1": 0.8e-3, "driveline.J_p": 1.6,
        "driveline.J_s": 8.0, "driveline.k_a": 600.0},
}

#: the rig runs of the chain: (name, experiment, settings)
RUNS = (("step41", "step", dict(level=1.5, oil_temp_C=41.0, seed=1)),
        ("step85", "step", dict(level=2.5, oil_temp_C=85.0, seed=2)),
        ("stair", "staircase", dict(config="valve-only", input_mode="pwm", level=0.15, from_=0.0, seed=3)))


def chain(overrides: dict, root: Path, samples: int, seed: int, sequence: int) -> dict:
    """Rig runs, identification, design and the two verifications of one clutch."""
    plant = load(overrides=overrides)
    recs = []
    for name, experiment, kw in RUNS:
        rig_report.write(rig.run(experiment, plant, **kw), root / name)
        recs.append(ident.load(root / name / "measured.csv"))
    found = ident.identify(recs).identified
    d = design.design(found, "launch")
    out = {}
    for which, p in (("identified", found), ("clutch", plant)):
        r = verify.run(d, p, n=samples, seed=seed, sequence=sequence, progress=False)
        out[which] = (r["pass_rate"], r["pass_rate_first_launch"])
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--sequence", type=int, default=3)
    ap.add_argument("--only", nargs="*", choices=list(CLUTCHES), default=list(CLUTCHES))
    a = ap.parse_args()
    print(f"{a.samples} samples of the shipped ranges, seed {a.seed}, {a.sequence} launches each; pass rate of all "
          "requirements, last launch / first launch\n")
    print("| clutch | on the identified plant | on the clutch itself |\n|---|---|---|")
    for name in a.only:
        t0 = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp:
            res = chain(CLUTCHES[name], Path(tmp), a.samples, a.seed, a.sequence)
        cells = [f"{100 * last:.1f} % / {100 * first:.1f} %" for last, first in res.values()]
        print(f"| {name} | {cells[0]} | {cells[1]} |  ({time.perf_counter() - t0:.0f} s)", flush=True)


if __name__ == "__main__":
    main()
