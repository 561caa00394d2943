"""Reports of launches and verification runs: tables, histograms, and the main job's report."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from . import launch, metrics, verify
from .output import atomic_dir, write_json
from .params import Params

_METRICS = (("steady_state_error_pct", "steady-state error [%]", metrics.REQ_ESS_PCT),
            ("t95_s", "t95 [s]", metrics.REQ_T95_S),
            ("overshoot_pct", "overshoot [%]", None),
            ("jerk_max", "max torque rate [N m/s]", None))


def plot_histograms(result: dict[str, Any], path: Path) -> None:
    """Histograms of the launch metrics over a verification run, with the requirement limits."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(_METRICS), figsize=(13, 3.2))
    for ax, (key, label, limit) in zip(axes, _METRICS):
        v = np.array([r["metrics"].get(key) for r in result["results"] if r["metrics"].get(key) is not None], dtype=float)
        v = v[np.isfinite(v)]
        ax.hist(v, bins=40, color="tab:blue", alpha=0.8)
        if limit is not None:
            ax.axvline(limit, color="tab:red", lw=1.5, label="requirement")
            ax.legend(fontsize=7)
        ax.set_xlabel(label, fontsize=9)
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("launches")
    fig.suptitle(f"verify {result['controller']}: {result['cases']} launches, all requirements met in "
                 f"{100 * result['pass_rate']:.1f} %", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def verify_table(result: dict[str, Any]) -> str:
    """Markdown: pass rates, metric percentiles, worst cases."""
    rate = result["pass_rate_per_requirement"]
    lines = [f"**{result['controller']}**: {result['cases']} launches ({result['samples']} random, "
             f"{result['cases'] - result['samples']} corners), seed {result['seed']}",
             "",
             "| requirement | pass rate |", "|---|---|",
             f"| steady-state error <= {metrics.REQ_ESS_PCT:g} % | {100 * rate['steady_state_error']:.1f} % |",
             f"| t95 < {metrics.REQ_T95_S:g} s | {100 * rate['response_time']:.1f} % |",
             f"| robust (t95 within {metrics.ROBUST_DT95:g} s, overshoot at most {metrics.ROBUST_OVERSHOOT:g} points above nominal) "
             f"| {100 * rate['robustness']:.1f} % |",
             f"| **all three** | **{100 * result['pass_rate']:.1f} %** |", "",
             "| metric | p5 | p50 | p95 | p99 | max |", "|---|---|---|---|---|---|"]
    for key, label, _ in _METRICS:
        p = result["percentiles"].get(key) or {}
        if p:
            lines.append(f"| {label} | " + " | ".join(f"{p[q]:.4g}" for q in ("p5", "p50", "p95", "p99", "max")) + " |")
    lines += ["", "Worst cases (replay with the command):", ""]
    for w in result["worst"][:5]:
        m = w["metrics"]
        fails = [k for k, ok in w["requirements"].items() if not ok]
        if not m or m.get("steady_state_error_pct") is None:
            figs = "no steady state"
        else:
            t95 = f"{m['t95_s']:.3f} s" if m.get("t95_s") is not None else "95 % never reached"
            ovs = f"{m['overshoot_pct']:.1f} %" if m.get("overshoot_pct") is not None else "n/a"
            figs = f"ess {m['steady_state_error_pct']:.2f} %, t95 {t95}, overshoot {ovs}"
        lines.append(f"- #{w['index']}: {figs}; fails: {', '.join(fails) or 'none'}  \n  `{w['replay']}`")
    return "\n".join(lines)


def write_verify(result: dict[str, Any], out: str | Path) -> None:
    """``verify.json``, ``verify.md``, ``samples.csv`` and ``histograms.png``, written atomically."""
    import pandas as pd

    with atomic_dir(out) as d:
        write_json(d / "verify.json", result)
        (d / "verify.md").write_text("# Verification\n\n" + verify_table(result) + "\n\n![histograms](histograms.png)\n")
        rows = [{"index": r["index"], "corner": r["corner"], **r["values"], **r["metrics"], **r["requirements"],
                 "all_pass": r["all_pass"]} for r in result["results"]]
        pd.DataFrame(rows).to_csv(d / "samples.csv", index=False)
        plot_histograms(result, d / "histograms.png")


def main_job(out: str | Path, samples: int = 1000, baseline_samples: int = 200, seed: int = 0,
             workers: int | None = None, progress: bool = True) -> dict[str, Any]:
    """The main job: nominal launches (design vs baseline), verification of both, one report."""
    from .plotting import plot_launch

    # refuse bad options before minutes of launches, not after
    verify.check_options(samples, seed, workers)
    verify.check_options(baseline_samples, seed, workers, "--baseline-samples")
    p = Params()
    launches = []
    for temp in (41.0, 85.0):
        for t_ref in (50.0, 100.0, 150.0):
            cond = launch.Conditions(t_ref=t_ref, oil_temp_C=temp)
            launches.append((launch.simulate(p, "launch", cond), launch.simulate(p, "pi", cond)))
    ver = verify.run(samples, seed, workers, "launch", progress=progress)
    base = verify.run(baseline_samples, seed, workers, "pi", progress=progress)
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
        "Requirements (spec section 7), on the axle torque `T_r` in the slip phase: steady-state error "
        f"<= {metrics.REQ_ESS_PCT:g} %, 95 % response time < {metrics.REQ_T95_S:g} s, and a response that stays nearly the "
        "same when the system changes (here: t95 within "
        f"{metrics.ROBUST_DT95:g} s of the nominal launch's, overshoot at most {metrics.ROBUST_OVERSHOOT:g} points above it). "
        "Metric definitions: `wetclutch.metrics`.",
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
              "See `wetclutch.control`: fill and hold at the kiss point while waiting, feedforward through the "
              "inverse static map scheduled on oil temperature, an online friction factor, PI on pressure, "
              "integral on torque, anti-windup, lock-up at synchronisation.", ""]
    return "\n".join(lines)
