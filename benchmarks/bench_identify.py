"""Speed of identification on one hour of 1 kHz measurements, all channels.

Runs four experiments on the virtual rig (clutch steps at 41 C and 85 C, a PWM
staircase and a noise run on the valve alone), then measures their true signals
again with fresh sensor noise as often as it takes to fill one hour of recordings
(as many files as a test campaign would give), and times
:func:`wetclutch.ident.identify` on them (median of repeats after a warm-up).
Reading files is timed separately, per second of data, from the MDF 4 and MAT
files of the four runs. Target: identification of one hour under 10 s.

Usage: ``python benchmarks/bench_identify.py [--repeats N] [--hours H]``
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import median_time  # noqa: E402

from wetclutch import ident, params  # noqa: E402
from wetclutch.ident import recordings as channels  # noqa: E402
from wetclutch.report import rig as rig_report  # noqa: E402
from wetclutch.rig import experiments as rig  # noqa: E402
from wetclutch.rig import sensors  # noqa: E402

RUNS = {
    "step41": dict(experiment="step", level=1.5, oil_temp_C=41.0),
    "step85": dict(experiment="step", level=2.5, oil_temp_C=85.0),
    "stair": dict(experiment="staircase", config="valve-only", input_mode="pwm", level=0.15, from_=0.0),
    "noise": dict(experiment="noise", config="valve-only", input_mode="pwm", level=0.15, from_=0.0),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--hours", type=float, default=1.0)
    args = ap.parse_args()
    p = params.load(overrides={"friction.mu_slip_poly": [-1.2e-6, 2.2e-4, 3.0e-2], "driveline.ratio": 0.6})
    base = {}
    with tempfile.TemporaryDirectory() as tmp:
        read_s, read_n = 0.0, 0
        for name, kw in RUNS.items():
            kw = dict(kw)
            res = rig.run(kw.pop("experiment"), p, **kw)
            rig_report.write(res, Path(tmp) / name)
            base[name] = res
            for ext in ("mf4", "mat"):
                t0 = time.perf_counter()
                channels.load(Path(tmp) / name / f"measured.{ext}")
                read_s += time.perf_counter() - t0
                read_n += len(res.measured)

    recordings: list[channels.Recording] = []
    seconds, k = 0.0, 0
    while seconds < 3600.0 * args.hours:
        for name, res in base.items():
            s = res.meta["settings"]
            cols = [c for c in rig.MEASURED_UNITS if c in res.truth.columns]
            m = sensors.measure(res.truth[cols], 1000.0, seed=1000 + k)
            data = {c: m[c].to_numpy() for c in m.columns}
            recordings.append(channels.Recording(Path(f"synthetic/{name}_{k:04d}.mf4"), data, res.meta["experiment"],
                                                 s["config"], s["input_mode"]))
            seconds += float(data["time"][-1] - data["time"][0])
            k += 1
    samples = sum(r.t.size for r in recordings)

    elapsed, result = median_time(lambda: ident.identify(recordings), args.repeats)
    e = result.estimates
    print(f"machine: {os.cpu_count()} cores, python {sys.version.split()[0]}")
    print(f"data: {len(recordings)} files, {seconds / 3600:.3f} h, {samples} samples x {len(rig.MEASURED_UNITS)} channels "
          "at 1 kHz")
    print(f"identify (all estimators + leave-one-out validation)  {elapsed:8.3f} s   (target < 10 s per hour)")
    print(f"reading files (MDF 4 and MAT, checks, units)         {read_s / read_n * 3.6e6:8.3f} s per hour of data")
    print(f"found: mu_slip_poly {[f'{c:.4g}' for c in e['mu_slip_poly'].value]}, "
          f"contact pressure {e['contact_pressure_Pa'].value / 1e5:.4f} bar, resonance {e['resonance_Hz'].value:.4f} Hz, "
          f"J_p {e['J_p'].value:.4f}, J_s {e['J_s'].value:.4f} kg m^2, "
          f"{len(result.onsets)} onsets, {len(result.steps)} step models, {len(result.responses)} frequency responses")


if __name__ == "__main__":
    main()
