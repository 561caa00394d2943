"""The main job's report: nominal launches, the verification of design and baseline, ``report.md``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..launch import metrics
from ..launch.campaign import MainJob
from ..output import atomic_dir, write_json
from .plots import plot_launch
from .verify import plot_histograms, verify_table


def write(job: MainJob, out: str | Path) -> dict[str, Any]:
    """Write the main job's report into ``out`` (atomically); returns the content of ``summary.json``."""
    launches, ver, base = job.launches, job.verify, job.verify_baseline
    with atomic_dir(out) as d:
        for i, (res, base_res) in enumerate(launches):
            plot_launch(res.signals, res.truth, res.summary, d / f"launch_{i}.png", extra=base_res.signals,
                        extra_label="PI baseline")
        plot_histograms(ver, d / "verify_launch.png")
        plot_histograms(base, d / "verify_pi.png")
        write_json(d / "verify_launch.json", ver)
        write_json(d / "verify_pi.json", base)
        summary = {"nominal": [{"design": a.summary, "baseline": b.summary} for a, b in launches],
                   "verify": {k: ver[k] for k in ("pass_rate", "pass_rate_per_requirement", "cases", "percentiles")},
                   "verify_baseline": {k: base[k] for k in ("pass_rate", "pass_rate_per_requirement", "cases", "percentiles")}}
        write_json(d / "summary.json", summary)
        (d / "report.md").write_text(_report_md(launches, ver, base))
    return summary


def _fmt(v: Any, f: str) -> str:
    return "-" if v is None else format(v, f)


def _report_md(launches: list, ver: dict[str, Any], base: dict[str, Any]) -> str:
    ok = lambda b: "pass" if b else "**FAIL**"  # noqa: E731
    lines = [
        "# wetclutch: torque control of a launch from standstill",
        "",
        "Requirements, on the axle torque `T_r` in the slip phase: steady-state error "
        f"<= {metrics.REQ_ESS_PCT:g} %, 95 % response time < {metrics.REQ_T95_S:g} s, and a response that stays nearly the "
        "same when the system changes (here: t95 within "
        f"{metrics.ROBUST_DT95:g} s of the nominal launch's, overshoot at most {metrics.ROBUST_OVERSHOOT:g} points above it). "
        "Metric definitions: `wetclutch.launch.metrics`.",
        "",
        f"**Verdict.** Over {ver['cases']} launches with oil at 20-85 C, friction spread 0.034-0.052, fill and "
        "dead-time, CVT ratio 0.4-0.8, efficiency 0.90-0.97, axle stiffness +-30 %, road load 0-30 N m, requests "
        f"50-150 N m and sensor noise x0.5-2, the launch controller meets all three requirements in "
        f"**{100 * ver['pass_rate']:.1f} %** of cases; the plain PI baseline in {100 * base['pass_rate']:.1f} % "
        f"(of {base['cases']}).",
        "",
        "## Nominal launches (default rig)",
        "",
        "| oil C | request N m | controller | ess % | t95 s | overshoot % | t_sync s | ess | t95 | robust |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for a, b in launches:
        for res in (a, b):
            s = res.summary
            r = s["requirements"]
            lines.append(f"| {s['oil_temp_C']:g} | {s['t_ref_Nm']:g} | {s['controller']} | {_fmt(s['steady_state_error_pct'], '.2f')} | "
                         f"{_fmt(s['t95_s'], '.3f')} | {_fmt(s['overshoot_pct'], '.1f')} | {_fmt(s['t_sync_s'], '.2f')} | "
                         f"{ok(r['steady_state_error'])} | {ok(r['response_time'])} | {ok(r['robustness'])} |")
    lines += ["", "![launch at 41 C, 100 N m](launch_1.png)", "",
              "## Verification: launch controller", "", verify_table(ver), "", "![histograms](verify_launch.png)", "",
              "## Verification: PI baseline (no fill, no feedforward)", "", verify_table(base), "",
              "![histograms](verify_pi.png)", "",
              "## How the controller works", "",
              "See `wetclutch.launch.controller`: fill and hold at the kiss point while waiting, feedforward through the "
              "inverse static map scheduled on oil temperature, an online friction factor, PI on pressure, "
              "integral on torque, anti-windup, lock-up at synchronisation.", ""]
    return "\n".join(lines)
