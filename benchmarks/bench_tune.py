"""Tuning of the default plant's launch controller: wall time, launches per second, what it gained.

Runs ``wetclutch tune --out DIR`` with its defaults (40 training plants of the shipped ranges,
8 generations of 8 candidates, 3 launches per plant, 200 held-out plants) on the built-in rig in
a fresh interpreter (warm numba cache), and prints the wall time, the number of launches the
run made (from its settings: the start and every candidate on the training plants, the
finalists on twice as many validation plants, the tuned and the untuned design on the held-out
plants) and so the launches per second, then the pass rates of the untuned and the tuned design
on the training and on the held-out plants (``tune.json``).

The baseline, measured in the same run: nominal launches one after another in this process; the
ratio of the two rates is what the tuning's parallel verifications make of the machine's cores.

Target: under 15 minutes on 2 cores.

``--set PATH=VALUE`` tunes for a plant other than the built-in rig (e.g. ``valve.I_hyst=0.08``, a valve whose
magnet play is wider than the defaults were tuned for). ``--check N`` then verifies the tuned and the untuned
design on N further plants (seed 11, as many launches each as the tuning) and compares them plant by plant with
McNemar's exact test (:func:`wetclutch.launch.tune.against_start`).

Usage: ``python benchmarks/bench_tune.py [--controller launch|baseline] [--set PATH=VALUE]... [--check N]``
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TARGET_S = 15 * 60


def launches(meta: dict, chosen_finalists: int) -> int:
    """Launches of a tuning run with the settings ``meta`` (``tune.json``) and that many finalists."""
    n, seq = meta["samples"], meta["sequence"]
    training = n * (1 + meta["generations"] * meta["popsize"])
    # finalists on twice as many validation plants; the search's mean also on the training plants
    validation = chosen_finalists * 2 * n + (n if "search mean" in meta["finalists"] else 0)
    return seq * (training + validation + 2 * meta["heldout_samples"])


def serial_rate(n: int = 20) -> float:
    """Launches per second of nominal launches one after another in this process (warm cache)."""
    from wetclutch.launch import loop, metrics
    from wetclutch.params import Params

    def one() -> None:
        loop.simulate(Params(), "launch", loop.Conditions(t_ref=100.0, oil_temp_C=85.0), nominal=metrics.Response.empty())

    one()
    t0 = time.perf_counter()
    for _ in range(n):
        one()
    return n / (time.perf_counter() - t0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--controller", default="launch", choices=("launch", "baseline"))
    ap.add_argument("--set", action="append", default=[], metavar="PATH=VALUE", help="the plant tuned for")
    ap.add_argument("--check", type=int, default=0, metavar="N", help="verify tuned and untuned on N more plants")
    a = ap.parse_args()
    exe = str(Path(sys.executable).with_name("wetclutch"))
    plant = [arg for kv in a.set for arg in ("--set", kv)]
    base = serial_rate()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "tune"
        t0 = time.perf_counter()
        subprocess.run([exe, "tune", "--controller", a.controller, "--out", str(out), "--quiet", *plant], check=True)
        wall = time.perf_counter() - t0
        meta = json.loads((out / "tune.json").read_text())
        checked = check(exe, a, plant, out / "controller.toml", meta["sequence"], Path(tmp)) if a.check else None
    n = launches(meta, len(meta["finalists"]))
    rates = meta["pass_rates"]
    print(f"machine: {os.cpu_count()} cores")
    print(f"tune {a.controller}{' (' + ', '.join(a.set) + ')' if a.set else ''}: {wall / 60:.1f} min, {n} launches, "
          f"{n / wall:.1f} launches/s ({n / wall / base:.2f} x one process's nominal launches, {base:.1f}/s, same run)")
    for split in ("training", "held-out"):
        print(f"  {split:9s} pass rate: untuned {100 * rates[split]['start']:.1f} %, tuned {100 * rates[split]['tuned']:.1f} %")
    print(f"  chosen: {meta['chosen']}")
    if checked:
        print(checked)
    print(f"target: under 15 min: {'met' if wall < TARGET_S else 'not met'}")


def check(exe: str, a: argparse.Namespace, plant: list[str], tuned: Path, sequence: int, tmp: Path) -> str:
    """The tuned and the untuned design verified on ``a.check`` further plants, compared plant by plant."""
    from wetclutch.launch.tune import against_start

    runs = {}
    for name, ctl in (("tuned", ["--controller-file", str(tuned)]), ("untuned", ["--controller", a.controller])):
        out = tmp / f"check-{name}"
        subprocess.run([exe, "verify", "--samples", str(a.check), "--seed", "11", "--sequence", str(sequence),
                        "--out", str(out), "--quiet", *ctl, *plant], check=True, stdout=subprocess.DEVNULL)
        runs[name] = json.loads((out / "verify.json").read_text())
    lines = [f"  check on {a.check} more plants (seed 11, {sequence} launches each):"]
    for key, label in (("all_pass", "last launch"), ("first_all_pass", "first launch")):
        t, u = ([r[key] for r in runs[n]["results"] if not r["corner"]] for n in ("tuned", "untuned"))
        b, c, p = against_start(t, u)
        lines.append(f"    {label}: untuned {100 * sum(u) / len(u):.1f} %, tuned {100 * sum(t) / len(t):.1f} %; "
                     f"plants only the tuned passes / only the untuned: {b} / {c}, one-sided p = {p:.2g}")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
