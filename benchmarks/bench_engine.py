"""Speed of the engine against a straightforward scipy baseline, in one process.

Prints the wall time per run (median of repeats, after JIT warm-up) of

* the engine on ``engage`` (8 s simulated, 1 ms output),
* the engine on ``coupled-clutches`` (1.5 s, 1 ms output),
* ``benchmarks/scipy_engage.py`` (solve_ivp, events, rtol 1e-8) on the same ``engage``,
* the engine again with as many output points as the baseline returns (its own steps),

the speed ratios and the agreement of ``t_sync``. Output costs the engine one
right-hand-side evaluation per row, so the like-for-like ratio compares equal output
density; the 1 ms figure is what ``wetclutch simulate`` writes. Targets: engage < 5 ms and
>= 100x faster than the baseline; coupled-clutches < 5 ms.

Usage: ``python benchmarks/bench_engine.py [--repeats N]``
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import median_time  # noqa: E402

import wetclutch as wc  # noqa: E402
from scipy_engage import engage_scipy  # noqa: E402
from wetclutch.plant.scenarios import SCENARIOS  # noqa: E402
from wetclutch.sim.network import integrate  # noqa: E402




def scipy_params(p: wc.Params) -> dict:
    d, e = p.driveline, p.engage
    return dict(
        J_p=d.J_p, J_1=d.J_1, J_s=d.J_s, b_1=d.b_1, b_2=d.b_2, i=d.ratio, eta=d.eta, k_a=d.k_a, d_a=d.d_a,
        omega_p0=d.omega_p0, T_cap=e.T_cap, t_start=e.t_start, t_ramp=e.t_ramp, T_load=e.T_load, peak=p.clutch.peak,
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=50)
    args = ap.parse_args()
    p = wc.Params()
    net_engage = SCENARIOS["engage"].build(p)
    net_cc = SCENARIOS["coupled-clutches"].build(p)

    t_eng, tr = median_time(lambda: integrate(net_engage, 8.0), args.repeats)
    t_sim, _ = median_time(lambda: wc.simulate("engage"), max(5, args.repeats // 5))
    t_cc, _ = median_time(lambda: integrate(net_cc, 1.5), args.repeats)
    t_sp, sp = median_time(lambda: engage_scipy(scipy_params(p), t_end=8.0, rtol=1e-8), 5)
    n_sp = sp["t"].size
    dt_match = 8.0 / n_sp
    t_match, _ = median_time(lambda: integrate(net_engage, 8.0, dt_out=dt_match), args.repeats)

    ts_eng, ts_sp = tr.first_lock("clutch"), sp["t_sync"]
    print(f"machine: {os.cpu_count()} cores, python {sys.version.split()[0]}")
    print(f"engine   engage (8 s, 1 ms output, 8001 rows)  {t_eng * 1e3:8.3f} ms/run  (target < 5 ms)")
    print(f"engine   engage (8 s, {n_sp} rows like scipy)    {t_match * 1e3:8.3f} ms/run")
    print(f"simulate engage (+ DataFrame, summary)         {t_sim * 1e3:8.3f} ms/run")
    print(f"engine   coupled-clutches (1.5 s, 1 ms)        {t_cc * 1e3:8.3f} ms/run  (target < 5 ms)")
    print(f"scipy    solve_ivp engage (rtol 1e-8, {n_sp} rows) {t_sp * 1e3:8.1f} ms/run")
    print(f"speed ratio scipy / engine, equal output rows  {t_sp / t_match:8.0f} x     (target >= 100 x)")
    print(f"speed ratio scipy / engine at 1 ms output      {t_sp / t_eng:8.0f} x")
    print(f"t_sync engine {ts_eng:.9f} s, scipy {ts_sp:.9f} s, relative difference {abs(ts_eng - ts_sp) / ts_sp:.2e}")
    print(f"engine stats: {tr.stats}")

if __name__ == "__main__":
    main()
