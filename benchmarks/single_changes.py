"""Pass rates of the default launch design on clutches with one change it is not told about.

Each row is a verification of the design made on the built-in rig, run on that rig with one
parameter changed (kiss point, fill volume, stem damping, clutch output inertia, friction
curve's slope, the magnet play's sharpness and width), over what varies in operation rather
than between clutches: oil temperature 10-100 C, request 25-200 N m, CVT ratio 0.4-1.0, road
load 0-30 N m, sensor noise x0.5-2.
Each sample is a sequence of launches of one clutch (the adaptation carried over); the table
gives the pass rate of all requirements on the last launch and on the first, the slams, the
largest ripple and the largest oscillation (the ripple about the torque's straight line over the
steady window, ``oscillation_pct``: a sustained oscillation shows there, a sag at the clutch's
capacity does not) and how many failures had the valve input at the top of its range (the clutch
at its capacity: ``failures_at_capacity``).

With ``--ranges shipped`` the shipped verification ranges vary around the changed plant instead (what varies
between clutches and over a clutch's life on top of the change: a stem damped twice as much then spans x1-4,
a clutch output ten times as heavy x10-100).

Not a timing: the figures are the acceptance of robustness to single changes (>= 95 % each).

Usage: ``python benchmarks/single_changes.py [--samples N] [--seed S] [--sequence K] [--ranges operation|shipped]``
"""

from __future__ import annotations

import argparse

from wetclutch.launch import design, ranges, verify
from wetclutch.params import Params, load

OPERATION = {
    "oil_temp": {"target": "oil_temp_C", "how": "abs", "low": 10.0, "high": 100.0},
    "request": {"target": "t_ref", "how": "abs", "low": 25.0, "high": 200.0},
    "cvt_ratio": {"target": "driveline.ratio", "how": "abs", "low": 0.4, "high": 1.0},
    "road_load": {"target": "engage.T_load", "how": "abs", "low": 0.0, "high": 30.0},
    "sensor_noise": {"target": "noise_scale", "how": "abs", "low": 0.5, "high": 2.0},
}


def changes(p: Params) -> dict[str, dict[str, float]]:
    """The single plant changes, as parameter overrides of ``p``."""
    h, v, d, f = p.hydraulics, p.valve, p.driveline, p.friction
    return {
        "none": {},
        "kiss point +0.1 bar": {"hydraulics.p_prestress": h.p_prestress + 0.1e5},
        "kiss point +0.2 bar": {"hydraulics.p_prestress": h.p_prestress + 0.2e5},
        "kiss point -0.2 bar": {"hydraulics.p_prestress": h.p_prestress - 0.2e5},
        "fill volume +30 %": {"hydraulics.x_contact": 1.3 * h.x_contact},
        "valve stem damping x2": {"valve.d_stem": 2.0 * v.d_stem},
        "clutch output inertia x3": {"driveline.J_1": 3.0 * d.J_1},
        "clutch output inertia x5": {"driveline.J_1": 5.0 * d.J_1},
        "clutch output inertia x10": {"driveline.J_1": 10.0 * d.J_1},
        "friction curve twice as steep": {"friction.mu_slope": 2.0 * f.mu_slope},
        "magnet play four times as sharp": {"valve.play_exponent": 4.0 * v.play_exponent},
        "magnet play 0.08 A (x1.8)": {"valve.I_hyst": 0.08},
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--sequence", type=int, default=3)
    ap.add_argument("--ranges", choices=("operation", "shipped"), default="operation")
    a = ap.parse_args()
    base = Params()
    d = design.cached(base, "launch")
    rs = ranges.parse(OPERATION, "operation") if a.ranges == "operation" else ranges.load()
    print(f"| plant change | all requirements, launch {a.sequence} | first launch | slams | largest ripple (%) | "
          "largest oscillation (%) | failures at capacity |")
    print("|---|---|---|---|---|---|---|")
    for name, over in changes(base).items():
        plant = load(overrides=over)
        r = verify.run(d, plant=plant, n=a.samples, seed=a.seed, ranges=rs, corners=False, progress=False,
                       sequence=a.sequence)
        ripple, osc = (max((x["metrics"].get(k) or 0.0) for x in r["results"]) for k in ("ripple_pct", "oscillation_pct"))
        print(f"| {name} | {100 * r['pass_rate']:.1f} % | {100 * r['pass_rate_first_launch']:.1f} % | "
              f"{r.get('slams', 0)} | {ripple:.1f} | {osc:.1f} | {r['failures_at_capacity']} of "
              f"{sum(not x['all_pass'] for x in r['results'])} |", flush=True)


if __name__ == "__main__":
    main()
