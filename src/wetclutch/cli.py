"""The ``wetclutch`` command line.

Every bad input ends in one line on stderr, ``wetclutch: error: ...``, and exit
code 2; output directories are written whole or not at all.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import NoReturn

from . import params as params_mod
from .errors import WetclutchError
from .plant.scenarios import SCENARIOS, simulate

EXIT_USAGE = 2


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message}\n")


def _param_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--param-file", metavar="F.toml", help="TOML parameter file (any subset of the parameters)")
    p.add_argument(
        "--set",
        dest="sets",
        action="append",
        default=[],
        metavar="PATH=VALUE",
        help="override one parameter, e.g. driveline.ratio=0.6 (repeatable; VALUE is a TOML literal)",
    )


def _load_params(args: argparse.Namespace) -> params_mod.Params:
    overrides = dict(params_mod.parse_set(s) for s in args.sets)
    return params_mod.load(args.param_file, overrides)


def _cmd_simulate(args: argparse.Namespace) -> None:
    from .report import scenario

    p = _load_params(args)
    if args.t_end is not None and not args.t_end > 0:
        raise WetclutchError(f"--t-end must be > 0 (got {args.t_end})")
    opts = {} if args.dt_out is None else {"dt_out": args.dt_out}
    res = simulate(args.scenario, p, args.t_end, **opts)
    scenario.write(res, args.out)
    s = res.summary
    line = f"{res.scenario}: {len(res.signals)} samples -> {args.out}"
    if s.get("t_sync") is not None:
        line += f"; t_sync = {s['t_sync']:.4f} s, T_r_peak = {s['T_r_peak']:.2f} N m, E_clutch = {s['E_clutch']:.1f} J"
    print(line)


def _cmd_params_show(args: argparse.Namespace) -> None:
    from rich.console import Console
    from rich.table import Table

    p = _load_params(args)
    table = Table("parameter", "value", "unit", "description", title="wetclutch parameters")
    for path, value, unit, desc in params_mod.describe(p):
        table.add_row(path, f"{value:g}" if isinstance(value, float) else str(value), unit, desc)
    Console(width=max(100, Console().width)).print(table)


def _cmd_params_export(args: argparse.Namespace) -> None:
    import os
    import tempfile
    from pathlib import Path

    p = _load_params(args)
    target = Path(args.file)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", dir=target.parent if str(target.parent) else ".")
    try:
        with os.fdopen(fd, "w") as f:
            f.write(params_mod.to_toml(p))
        os.replace(tmp, target)
    except OSError as err:
        os.unlink(tmp)
        raise WetclutchError(f"cannot write '{target}': {err.strerror}") from None
    print(f"wrote {target}")


def _cmd_rig(args: argparse.Namespace) -> None:
    from .report import rig as rig_report
    from .rig import experiments as rig

    p = _load_params(args)
    res = rig.run(
        args.experiment, p, input_mode=args.input_mode, level=args.level, from_=args.from_, oil_temp_C=args.oil_temp,
        config=args.config, rate_hz=args.rate, seed=args.seed, noise=not args.no_noise, t_end=args.t_end,
    )
    rig_report.write(res, args.out)
    m = res.measured
    extra = f"; t_sync = {res.meta['t_sync']:.3f} s" if res.meta["t_sync"] is not None else ""
    print(f"rig {args.experiment}: {len(m)} samples at {args.rate:g} Hz, {m.time.iloc[-1]:.2f} s -> {args.out}{extra}")


def _cmd_calibration(args: argparse.Namespace) -> None:
    from .report import calibration as calibration_report
    from .rig import calibration

    figs = calibration.run(_load_params(args))
    calibration_report.write(figs, args.out)
    for f in figs:
        print(f"{'pass' if f.passed else 'FAIL'}  {f.name}")
    print(f"{sum(f.passed for f in figs)} of {len(figs)} figures within tolerance -> {args.out}/report.md")


def _cmd_launch(args: argparse.Namespace) -> None:
    from .launch import loop as launch
    from .report import launch as launch_report

    p = _load_params(args)
    cond = launch.Conditions(t_ref=args.t_ref, profile=args.profile, oil_temp_C=args.oil_temp, seed=args.seed,
                             noise=not args.no_noise, noise_scale=args.noise_scale)
    res = launch.simulate(p, args.controller, cond)
    launch_report.write(res, args.out, p)
    s = res.summary
    req = ", ".join(f"{k} {'pass' if v else 'FAIL'}" for k, v in s["requirements"].items())
    fmt = lambda v, f: "-" if v is None else format(v, f)  # noqa: E731
    print(f"launch {args.controller}: ess {fmt(s['steady_state_error_pct'], '.2f')} %, t95 {fmt(s['t95_s'], '.3f')} s, "
          f"overshoot {fmt(s['overshoot_pct'], '.1f')} %, t_sync {fmt(s['t_sync_s'], '.2f')} s, "
          f"plate {s['T_plate_peak_C']:.1f} C; {req} -> {args.out}")
    if s["T_plate_over_limit"]:
        print(f"warning: clutch plates reached {s['T_plate_peak_C']:.1f} C, above the limit "
              f"thermal.T_plate_limit_C = {s['T_plate_limit_C']:g} C", file=sys.stderr)


def _cmd_verify(args: argparse.Namespace) -> None:
    from .launch import verify
    from .report import verify as verify_report

    res = verify.run(args.samples, args.seed, args.workers, args.controller, progress=not args.quiet)
    verify_report.write(res, args.out)
    rate = res["pass_rate_per_requirement"]
    print(f"verify {args.controller}: {res['cases']} launches, all three requirements in {100 * res['pass_rate']:.1f} % "
          f"(ess {100 * rate['steady_state_error']:.1f} %, t95 {100 * rate['response_time']:.1f} %, "
          f"robust {100 * rate['robustness']:.1f} %) -> {args.out}")


def _cmd_report(args: argparse.Namespace) -> None:
    from .launch import campaign
    from .report import main as report

    job = campaign.main_job(args.samples, args.baseline_samples, args.seed, args.workers, progress=not args.quiet)
    s = report.write(job, args.out)
    print(f"report: launch controller meets all requirements in {100 * s['verify']['pass_rate']:.1f} % of "
          f"{s['verify']['cases']} launches, PI baseline in {100 * s['verify_baseline']['pass_rate']:.1f} % "
          f"-> {args.out}/report.md")


def _cmd_identify(args: argparse.Namespace) -> None:
    from rich.console import Console
    from rich.progress import Progress

    from .ident import identify
    from .ident import recordings as channels
    from .report import identify as identify_report

    prior = _load_params(args)
    cmap = channels.read_channel_map(args.channels)
    with Progress(console=Console(stderr=True), transient=True, disable=not sys.stderr.isatty()) as bar:
        task = bar.add_task("reading", total=2 * len(args.files))
        recs = []
        for f in args.files:
            bar.update(task, description=f"reading {f}")
            recs.append(channels.load(f, cmap))
            bar.advance(task)
        res = identify(recs, prior, args.mu_order,
                                progress=lambda name: bar.update(task, advance=1, description=f"identifying {name}"))
        bar.update(task, description=f"writing {args.out}")
        identify_report.write(res, args.out)
    e = res.estimates
    found = ", ".join(k for k in ("mu_slip_poly", "contact_pressure_Pa", "valve_gain", "clutch_gain_poly_bar_per_V",
                                  "resonance_Hz") if k in e)
    print(f"identify: {len(recs)} files, {len(res.onsets)} onsets, {len(res.steps)} step models, "
          f"{len(res.responses)} frequency responses; {found or 'nothing'} -> {args.out}")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="wetclutch", description="Wet-clutch driveline model, virtual rig, identification, control.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    sim = sub.add_parser("simulate", help="run a scenario and write signals.csv, summary.json, signals.png")
    sim.add_argument("scenario", choices=list(SCENARIOS), help="scenario name")
    _param_args(sim)
    sim.add_argument("--t-end", type=float, metavar="S", help="end time, s (default: the scenario's)")
    sim.add_argument("--dt-out", type=float, metavar="S", help="output interval, s (default 0.001)")
    sim.add_argument("--out", required=True, metavar="DIR", help="output directory (replaced as a whole)")
    sim.set_defaults(func=_cmd_simulate)

    from .rig.experiments import EXPERIMENTS

    rg = sub.add_parser("rig", help="run an experiment on the virtual test rig and write measurement files")
    rg.add_argument("experiment", choices=EXPERIMENTS)
    rg.add_argument("--out", required=True, metavar="DIR")
    rg.add_argument("--input-mode", choices=("dc", "pwm"), default="dc", help="DC voltage or PWM duty cycle input")
    rg.add_argument("--level", type=float, metavar="X", help="input level (V or duty; default 1 V / 0.2)")
    rg.add_argument("--from", dest="from_", type=float, metavar="X0", help="start level (default the lowest input)")
    rg.add_argument("--oil-temp", type=float, metavar="C", help="oil temperature, C (default rig.oil_temp_C)")
    rg.add_argument("--config", choices=("clutch", "valve-only"), default="clutch")
    rg.add_argument("--rate", type=float, default=1000.0, metavar="HZ", help="sampling rate (default 1000)")
    rg.add_argument("--seed", type=int, default=0, metavar="N", help="noise seed")
    rg.add_argument("--no-noise", action="store_true", help="ideal sensors: no noise, filters or quantisation")
    rg.add_argument("--t-end", type=float, metavar="S", help="duration, s (default: the experiment's)")
    _param_args(rg)
    rg.set_defaults(func=_cmd_rig)

    cal = sub.add_parser("calibration-report", help="compare the default rig with the study's figures")
    cal.add_argument("--out", required=True, metavar="DIR")
    _param_args(cal)
    cal.set_defaults(func=_cmd_calibration)

    lau = sub.add_parser("launch", help="a controlled launch from standstill: signals.csv, summary.json, plot.png")
    lau.add_argument("--out", required=True, metavar="DIR")
    lau.add_argument("--controller", choices=("launch", "pi"), default="launch", help="design (launch) or PI baseline")
    lau.add_argument("--t-ref", type=float, default=100.0, metavar="NM", help="requested axle torque T_r, N m (default 100)")
    lau.add_argument("--profile", default="step", metavar="step|ramp|FILE", help="request profile or CSV (time, t_ref)")
    lau.add_argument("--oil-temp", type=float, metavar="C", help="oil temperature, C (default rig.oil_temp_C)")
    lau.add_argument("--seed", type=int, default=0, metavar="N", help="sensor noise seed")
    lau.add_argument("--noise-scale", type=float, default=1.0, metavar="X", help="multiplier on the sensor noise")
    lau.add_argument("--no-noise", action="store_true", help="ideal sensors")
    _param_args(lau)
    lau.set_defaults(func=_cmd_launch)

    ver = sub.add_parser("verify", help="Monte Carlo and corner-case verification of a launch controller")
    ver.add_argument("--out", required=True, metavar="DIR")
    ver.add_argument("--samples", type=int, default=1000, metavar="N", help="random samples (default 1000; plus 16 corners)")
    ver.add_argument("--seed", type=int, default=0, metavar="S")
    ver.add_argument("--workers", type=int, metavar="W", help="processes (default: all cores)")
    ver.add_argument("--controller", choices=("launch", "pi"), default="launch")
    ver.add_argument("--quiet", action="store_true", help="no progress bar")
    ver.set_defaults(func=_cmd_verify)

    rep = sub.add_parser("report", help="the main job: nominal launches, verification of design and baseline, report.md")
    rep.add_argument("--out", required=True, metavar="DIR")
    rep.add_argument("--samples", type=int, default=1000, metavar="N")
    rep.add_argument("--baseline-samples", type=int, default=200, metavar="N")
    rep.add_argument("--seed", type=int, default=0, metavar="S")
    rep.add_argument("--workers", type=int, metavar="W")
    rep.add_argument("--quiet", action="store_true")
    rep.set_defaults(func=_cmd_report)

    idf = sub.add_parser("identify", help="identify the clutch from measurement files; write identified.json, "
                                          "params.toml, report.md")
    idf.add_argument("files", nargs="+", metavar="FILE", help="measurement files (.csv, .mf4, .mat)")
    idf.add_argument("--out", required=True, metavar="DIR", help="output directory (replaced as a whole)")
    idf.add_argument("--channels", metavar="MAP.toml", help="channel map: names and units of the files' channels")
    idf.add_argument("--mu-order", type=int, default=2, metavar="N", help="order of the mu(slip) polynomial (default 2)")
    _param_args(idf)  # the prior: piston area, efficiency, inertias ... and the base of params.toml
    idf.set_defaults(func=_cmd_identify)

    par = sub.add_parser("params", help="show or export the parameter record")
    psub = par.add_subparsers(dest="params_command", required=True, parser_class=_Parser)
    show = psub.add_parser("show", help="print every parameter with its unit and description")
    _param_args(show)
    show.set_defaults(func=_cmd_params_show)
    exp = psub.add_parser("export", help="write a complete TOML parameter file")
    exp.add_argument("file", metavar="F.toml")
    _param_args(exp)
    exp.set_defaults(func=_cmd_params_export)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        args.func(args)
    except WetclutchError as err:
        print(f"wetclutch: error: {err}", file=sys.stderr)
        return EXIT_USAGE
    return 0


if __name__ == "__main__":
    sys.exit(main())
