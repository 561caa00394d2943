"""The ``wetclutch`` command line.

Every bad input ends in one line on stderr, ``wetclutch: error: ...``, and exit
code 2; output directories are written whole or not at all.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import shlex
import signal
import sys
import threading
from collections.abc import Sequence
from pathlib import Path
from typing import NoReturn

from . import params as params_mod
from .errors import COMMAND_LINE, WetclutchError, one_line
from .output import check_out_dir, check_target
from .plant.scenarios import SCENARIOS, simulate
from .report.text import plural

EXIT_USAGE = 2
#: the exit code of a run stopped by a signal: 128 + the signal's number, as a shell reports it
EXIT_SIGNAL = 128
#: the most output samples of ``simulate``: --t-end / --dt-out
MAX_SAMPLES = 1_000_000


class _Parser(argparse.ArgumentParser):
    _relaxed: tuple[argparse.Action, ...] = ()

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, f"{self.prog}: error: {one_line(message)}\n")

    def parse_known_args(self, args=None, namespace=None):
        # an unknown option is named before a missing required one: argparse checks the required options first, and
        # `launch --bogus` would otherwise be told that --out is missing, not that --bogus is no option. A first pass
        # with the required options relaxed finds what no option takes
        relaxed = tuple(a for a in self._actions if a.required and a.option_strings)
        if relaxed:
            self._relaxed = relaxed
            try:
                with self._required(False):
                    _, extras = super().parse_known_args(None if args is None else list(args), argparse.Namespace())
            finally:
                self._relaxed = ()
            if any(x.startswith("-") for x in extras):
                self.error(f"unrecognized arguments: {' '.join(extras)}")
        return super().parse_known_args(args, namespace)

    def format_usage(self) -> str:
        # help asked for in the first pass shows the relaxed options as required, as they are
        with self._required(True):
            return super().format_usage()

    def format_help(self) -> str:
        with self._required(True):
            return super().format_help()

    @contextlib.contextmanager
    def _required(self, required: bool):
        """The relaxed options' ``required`` set to ``required`` while the block runs, then back to what it was."""
        before = [a.required for a in self._relaxed]
        for a in self._relaxed:
            a.required = required
        try:
            yield
        finally:
            for a, was in zip(self._relaxed, before, strict=True):
                a.required = was


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


def _lockup_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--through-lockup", action="store_true",
                   help="run every verified launch to lock-up, for lock-up times and slip energies (default: "
                        "only as far past the request as the requirements judge, with the same verdicts; faster)")


def _scheduler_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="run the launches on this dask.distributed scheduler, e.g. tcp://10.0.0.5:8786 "
                        "(default: $DASK_SCHEDULER_ADDRESS; neither: local processes)")


def _load_params(args: argparse.Namespace) -> params_mod.Params:
    overrides = dict(params_mod.parse_set(s) for s in args.sets)
    return params_mod.load(args.param_file, overrides)


def _check_times(args: argparse.Namespace) -> tuple[float, float]:
    """The run's end time and output interval (the scenario's defaults where not given); one line naming the option
    if either is out of range or not a number."""
    from .rig.experiments import MAX_T_END_S

    t_end = SCENARIOS[args.scenario].t_end if args.t_end is None else args.t_end
    if not 0.0 < t_end <= MAX_T_END_S:
        raise WetclutchError(f"--t-end must be in (0, {MAX_T_END_S:g}] s (got {t_end:g})")
    dt_out = 1e-3 if args.dt_out is None else args.dt_out
    shortest = t_end / MAX_SAMPLES
    if not shortest <= dt_out <= t_end:
        raise WetclutchError(f"--dt-out must be in [{shortest:g}, {t_end:g}] s for a run of {t_end:g} s, at most "
                             f"{MAX_SAMPLES} samples (got {dt_out:g})")
    return t_end, dt_out


def _cmd_simulate(args: argparse.Namespace) -> None:
    from .report import scenario

    t_end, dt_out = _check_times(args)
    p = _load_params(args)
    opts = {} if args.dt_out is None else {"dt_out": dt_out}
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

    if not args.file.strip():
        raise WetclutchError("F.toml must not be empty")
    p = _load_params(args)
    target = Path(args.file)
    parent = target.parent if str(target.parent) else Path(".")
    if not parent.is_dir():
        raise WetclutchError(f"cannot write '{target}': directory '{parent}' does not exist")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", dir=parent)
    except OSError as err:
        raise WetclutchError(f"cannot write '{target}': {err.strerror or err}") from None
    try:
        with os.fdopen(fd, "w") as f:
            f.write(params_mod.to_toml(p))
        os.replace(tmp, target)
    except OSError as err:
        os.unlink(tmp)
        raise WetclutchError(f"cannot write '{target}': {err.strerror or err}") from None
    except BaseException:
        os.unlink(tmp)
        raise
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
    if args.config == "clutch" and not float(res.truth["T_c"].abs().max()) > 0.0:
        # identification finds no torque onset, slip phase or ring-out in such a run, and says only "no suitable runs"
        print(f"warning: the clutch plates never touched (clutch pressure at most "
              f"{float(res.truth['p_clutch'].max()) / 1e5:.2f} bar): this run shows no torque; a higher --level "
              "presses the plates", file=sys.stderr)


def _cmd_calibration(args: argparse.Namespace) -> None:
    from .report import calibration as calibration_report
    from .rig import calibration

    figs = calibration.run(_load_params(args))
    calibration_report.write(figs, args.out)
    for f in figs:
        print(f"{'pass' if f.passed else 'FAIL'}  {f.name}")
    print(f"{sum(f.passed for f in figs)} of {len(figs)} figures within tolerance -> {args.out}/report.md")


def _out_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", required=True, metavar="DIR", help="output directory (replaced as a whole)")


def _controller_args(p: argparse.ArgumentParser,
                     what: str = "controller kind: the design (launch, default) or the fair baseline") -> None:
    p.add_argument("--controller", choices=("launch", "baseline"),
                   help=f"{what}; designed on the plant unless --controller-file is given")
    p.add_argument("--controller-file", metavar="C.toml",
                   help="a controller file from 'wetclutch design' (designed on any plant)")


def _plant(args: argparse.Namespace) -> tuple[params_mod.Params, dict[str, str]]:
    """The plant of the command line and how each of its parameters was obtained."""
    from .launch.design import plant_origin

    overrides = dict(params_mod.parse_set(s) for s in args.sets)
    return params_mod.load(args.param_file, overrides), plant_origin(args.param_file, overrides)


def _design(args: argparse.Namespace, plant: params_mod.Params, origin: dict[str, str], kind: str | None = None):
    """The controller to run: the file's, or ``kind`` (default ``--controller``) designed on ``plant``."""
    from .launch import design, settings

    if getattr(args, "controller_file", None) and kind is None:
        return settings.load(args.controller_file, args.controller)
    return design.design(plant, kind or args.controller or "launch", origin)


def _replay_args(args: argparse.Namespace, controller_file: str) -> str:
    """Options that make ``wetclutch launch`` replay a sample: the plant's file and changes (the ranges' own
    ``--set`` options follow them and win), and the controller file written beside the results (the design, not
    one made anew on the sample's plant)."""
    out = f" --param-file {shlex.quote(str(args.param_file))}" if args.param_file else ""
    out += "".join(f" --set {shlex.quote(s)}" for s in args.sets)
    return out + f" --controller-file {shlex.quote(str(Path(args.out) / controller_file))}"


def _cmd_design(args: argparse.Namespace) -> None:
    from .report import design as design_report

    plant, origin = _plant(args)
    kinds = [args.controller] if args.controller else ["launch", "baseline"]
    designs = [_design(args, plant, origin, k) for k in kinds]
    design_report.write(designs, args.out)
    names = ["controller.toml"] + [f"{d.kind}.toml" for d in designs[1:]]
    print(f"design: {', '.join(d.kind for d in designs)} for the plant (kiss point "
          f"{designs[0].settings['p_kiss'] / 1e5:.3f} bar) -> {args.out}/{', '.join(names)}, design.md")


def _cmd_launch(args: argparse.Namespace) -> None:
    import numpy as np

    from .launch import loop as launch
    from .report import launch as launch_report

    if args.hold_time is not None and not args.post_sync_hold:
        raise WetclutchError("--hold-time needs --post-sync-hold (it limits that hold)")
    from .launch import adaptation

    if args.t_ref is not None and args.profile not in launch.PROFILES:
        raise WetclutchError(f"--t-ref: the profile '{args.profile}' gives the request itself; leave --t-ref out")
    launch.check_sequence(args.sequence)
    cond = launch.Conditions(t_ref=100.0 if args.t_ref is None else args.t_ref, profile=args.profile,
                             oil_temp_C=args.oil_temp, seed=args.seed, noise=not args.no_noise,
                             noise_scale=args.noise_scale, post_sync_hold=args.post_sync_hold,
                             **({} if args.hold_time is None else {"hold_time": args.hold_time})).checked()
    # the files read before the design, which may take minutes on a new plant: a bad one is refused at once
    launch.reference(cond, np.zeros(1))  # a CSV profile read and checked
    p, origin = _plant(args)
    d = _design(args, p, origin) if args.controller_file else None  # a file is read at once, a design takes long
    if args.adaptation and (d.kind if d is not None else args.controller or "launch") == "baseline":
        raise WetclutchError("--adaptation: the baseline controller has no adaptation")
    start = adaptation.check_plant(adaptation.load(args.adaptation), p, args.adaptation) if args.adaptation else None
    d = d if d is not None else _design(args, p, origin)
    runs = launch.sequence(p, d, cond, args.sequence, start)
    res = runs[-1]
    launch_report.write(res, args.out, p, runs)
    s = res.summary
    req = ", ".join(f"{k} {'pass' if v else 'FAIL'}" for k, v in s["requirements"].items())
    fmt = lambda v, f: "-" if v is None else format(v, f)  # noqa: E731
    print(f"launch ({d.kind} controller): ess {fmt(s['steady_state_error_pct'], '.2f')} %, "
          f"t95 {fmt(s['t95_s'], '.3f')} s "
          f"(settled {fmt(s['t95_settled_s'], '.3f')} s), overshoot {fmt(s['overshoot_pct'], '.1f')} %, "
          f"creep {fmt(s['creep_Nm'], '.1f')} N m, t_sync {fmt(s['t_sync_s'], '.2f')} s, "
          f"plate {s['T_plate_peak_C']:.1f} C; {req} -> {args.out}")
    if cond.post_sync_hold:
        print(f"post-sync hold: {s['hold_s']:.2f} s ({s['hold_end']}), axle torque within 10 % of the request for "
              f"{s['held_in_band_s']:.2f} s after lock-up, ratio {s['ratio_start']:.2f} -> {s['ratio_end']:.2f}")
    if s["T_plate_over_limit"]:
        print(f"warning: clutch plates reached {s['T_plate_peak_C']:.1f} C, above the limit "
              f"thermal.T_plate_limit_C = {s['T_plate_limit_C']:g} C", file=sys.stderr)


def _rates(res: dict) -> str:
    from .launch.metrics import REQUIREMENTS

    rate = res["pass_rate_per_requirement"]
    return ", ".join(f"{k} {100 * rate[k]:.1f} %" for k in REQUIREMENTS)


def _cmd_verify(args: argparse.Namespace) -> None:
    from .launch import loop as launch
    from .launch import ranges, verify
    from .report import verify as verify_report

    verify.check_options(args.samples, args.seed, args.workers)
    launch.check_sequence(args.sequence)
    p, origin = _plant(args)
    rs = ranges.load(args.ranges)
    ranges.fit(rs, p)  # a range that leaves the plant's physical range, refused before the design
    d = _design(args, p, origin)
    res = verify.run(d, p, args.samples, args.seed, args.workers, rs, progress=not args.quiet,
                     replay_args=_replay_args(args, "controller.toml"), sequence=args.sequence,
                     scheduler=args.scheduler, through_lockup=args.through_lockup)
    verify_report.write(res, args.out, d, p, args.param_file, args.sets)
    seq = (f"; after {args.sequence} launches of each clutch (first launch {100 * res['pass_rate_first_launch']:.1f} %,"
           f" {plural(res['slams'], 'slam')})" if args.sequence > 1 else "")
    reach = res["pass_rate_reachable"]
    reach = "" if math.isnan(reach) else f"; {100 * reach:.1f} % of those some controller can pass"
    print(f"verify {d.kind}: all requirements in {verify_report.headline(res, _rates(res))}{reach}{seq} -> {args.out}")


def _cmd_report(args: argparse.Namespace) -> None:
    from .launch import campaign, ranges, settings, verify
    from .launch import loop as launch
    from .report import main as report
    from .report import verify as verify_report

    verify.check_options(args.samples, args.seed, args.workers)
    verify.check_options(args.baseline_samples, args.seed, args.workers, "--baseline-samples")
    launch.check_sequence(args.sequence)
    p, origin = _plant(args)
    rs = ranges.load(args.ranges)
    ranges.fit(rs, p)  # a range that leaves the plant's physical range, refused before the design
    d = settings.load(args.controller_file, "launch") if args.controller_file else _design(args, p, origin, "launch")
    b = (settings.load(args.baseline_file, "baseline") if args.baseline_file
         else _design(args, p, origin, "baseline"))
    job = campaign.main_job(p, d, b, rs, args.samples, args.baseline_samples, args.seed, args.workers,
                            progress=not args.quiet, replay_args=_replay_args(args, "controller.toml"),
                            baseline_replay_args=_replay_args(args, "baseline.toml"), scheduler=args.scheduler,
                            sequence=args.sequence, through_lockup=args.through_lockup)
    s = report.write(job, args.out, args.param_file, args.sets)
    same = s["same_samples"]
    launches = "one launch each" if args.sequence == 1 else f"{args.sequence} launches each, judged on the last"
    print(f"report: launch controller meets all requirements in {verify_report.headline(job.verify)} "
          f"({launches}); on the same {plural(same['samples'], 'clutch', 'clutches')}: design "
          f"{100 * same['design']:.1f} %, baseline {100 * same['baseline']:.1f} % -> {args.out}/report.md")


def _cmd_tune(args: argparse.Namespace) -> None:
    from rich.progress import Progress

    from .launch import loop as launch
    from .launch import ranges, tune, verify
    from .report import tune as tune_report

    verify.check_options(args.samples, args.seed, args.workers)
    if args.heldout_seed < 0:  # checked below as a seed, it would be named --seed
        raise WetclutchError(f"--heldout-seed must be >= 0 (got {args.heldout_seed})")
    verify.check_options(args.heldout_samples, args.heldout_seed, args.workers, "--heldout-samples")
    tune.check_options(args.samples, args.generations, args.popsize)
    launch.check_sequence(args.sequence)
    if args.heldout_seed in (args.seed, args.seed + 1):
        raise WetclutchError("--heldout-seed must differ from --seed and --seed + 1 (the held-out plants must be other "
                             "than the training and the validation plants)")
    if args.heldout_samples < 1:
        # the held-out verification has no corners: without samples it has no pass rate, found only after the search
        raise WetclutchError(f"--heldout-samples must be >= 1 (got {args.heldout_samples})")
    if args.state is not None:
        state = tune.check_state(args.state).resolve()
        out = Path(args.out).resolve()
        if state == out or out in state.parents:
            raise WetclutchError(f"--state '{args.state}' lies inside --out '{args.out}', which is replaced as a whole "
                                 "when the tuning ends: the state would go with it; keep it outside")
    p, origin = _plant(args)
    rs = ranges.load(args.ranges)
    ranges.fit(rs, p)  # a range that leaves the plant's physical range, refused before the design
    start = _design(args, p, origin)
    with Progress(disable=args.quiet) as bar:
        task = bar.add_task(f"tune {start.kind}", total=args.generations)
        res = tune.run(start, p, rs, args.samples, args.seed, args.generations, args.popsize, args.workers,
                       args.state, on_generation=lambda g, *_: bar.update(task, completed=g), sequence=args.sequence)

    def rate(design, n, seed):
        return verify.run(design, p, n, seed, args.workers, rs, corners=False, progress=False,
                          sequence=args.sequence)["pass_rate"]

    fin = res.finalists
    rates = {"training": {"start": fin["start"][1], "tuned": fin[res.chosen][1]},
             "held-out": {"start": rate(start, args.heldout_samples, args.heldout_seed),
                          "tuned": rate(res.design, args.heldout_samples, args.heldout_seed)}}
    meta = {"samples": args.samples, "seed": args.seed, "heldout_samples": args.heldout_samples,
            "heldout_seed": args.heldout_seed, "sequence": args.sequence, "generations": args.generations,
            "popsize": args.popsize}
    tune_report.write(res, rates, args.out, meta)
    print(f"tune {start.kind}: training {100 * rates['training']['start']:.1f} -> {100 * rates['training']['tuned']:.1f} %, "
          f"held-out {100 * rates['held-out']['start']:.1f} -> {100 * rates['held-out']['tuned']:.1f} % "
          f"-> {args.out}/controller.toml")


def _cmd_identify(args: argparse.Namespace) -> None:
    from rich.console import Console
    from rich.progress import Progress

    from .ident import identify
    from .ident.result import PARAMS_FROM, REPORTED
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
    # what the files gave: the static maps and every entry that a parameter comes from (the oil temperature, the
    # files' own, is no finding)
    found = ", ".join(k for k in dict.fromkeys((*REPORTED, *PARAMS_FROM.values())) if k in e and k != "oil_temp_C")
    print(f"identify: {plural(len(recs), 'file')}, {plural(len(res.onsets), 'onset')}, "
          f"{plural(len(res.steps), 'step model')}, {plural(len(res.responses), 'frequency response')}; "
          f"{found or 'nothing'} -> {args.out}")


def _cmd_export_fmu(args: argparse.Namespace) -> None:
    from .fmi import export

    if args.controller is None and args.controller_file is None:
        if args.dt is not None:
            raise WetclutchError("--dt is the sample time of a controller: give --controller or --controller-file")
        path = export.export_plant(_load_params(args), args.out, pwm=args.pwm)
        print(f"export-fmu: plant ({'PWM duty' if args.pwm else 'DC voltage'} input) -> {path}")
    else:
        if args.pwm:
            raise WetclutchError("--pwm is an input of the plant: leave out --controller and --controller-file")
        plant, origin = _plant(args)
        d = _design(args, plant, origin)
        dt = export.DEFAULT_DT_S if args.dt is None else args.dt
        path = export.export_controller(d, args.out, dt)
        print(f"export-fmu: {d.kind} controller, sampled every {dt * 1e3:g} ms -> {path}")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="wetclutch", description="Wet-clutch driveline model, virtual rig, identification, control.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    sim = sub.add_parser("simulate", help="run a scenario and write signals.csv, summary.json, signals.png")
    sim.add_argument("scenario", choices=list(SCENARIOS), help="scenario name")
    _param_args(sim)
    sim.add_argument("--t-end", type=float, metavar="S", help="end time, s (default: the scenario's)")
    sim.add_argument("--dt-out", type=float, metavar="S", help="output interval, s (default 0.001)")
    _out_arg(sim)
    sim.set_defaults(func=_cmd_simulate)

    from .rig.experiments import EXPERIMENTS

    rg = sub.add_parser("rig", help="run an experiment on the virtual test rig and write measurement files")
    rg.add_argument("experiment", choices=EXPERIMENTS)
    _out_arg(rg)
    rg.add_argument("--input-mode", choices=("dc", "pwm"), default="dc", help="DC voltage or PWM duty cycle input")
    rg.add_argument("--level", type=float, metavar="X", help="input level (V or duty; default 1 V / 0.2)")
    rg.add_argument("--from", dest="from_", type=float, metavar="X0", help="start level (default the lowest input)")
    rg.add_argument("--oil-temp", type=float, metavar="C", help="oil temperature, C (default rig.oil_temp_C)")
    rg.add_argument("--config", choices=("clutch", "valve-only"), default="clutch",
                    help="rig configuration: the valve driving the clutch and driveline, or the valve alone on the "
                         "test bench, flowing through a restriction (default clutch)")
    rg.add_argument("--rate", type=float, default=1000.0, metavar="HZ", help="sampling rate (default 1000)")
    rg.add_argument("--seed", type=int, default=0, metavar="N", help="noise seed")
    rg.add_argument("--no-noise", action="store_true", help="ideal sensors: no noise, filters or quantisation")
    rg.add_argument("--t-end", type=float, metavar="S", help="duration, s (default: the experiment's)")
    _param_args(rg)
    rg.set_defaults(func=_cmd_rig)

    cal = sub.add_parser("calibration-report", help="compare the default rig with the study's figures")
    _out_arg(cal)
    _param_args(cal)
    cal.set_defaults(func=_cmd_calibration)

    des = sub.add_parser("design", help="design the launch controller (and the fair baseline) for a plant: "
                                        "controller.toml, baseline.toml, design.md")
    _out_arg(des)
    des.add_argument("--controller", choices=("launch", "baseline"), help="design only this kind (default: both)")
    _param_args(des)
    des.set_defaults(func=_cmd_design)

    lau = sub.add_parser("launch", help="a controlled launch from standstill: signals.csv, summary.json, plot.png")
    _out_arg(lau)
    _controller_args(lau)
    lau.add_argument("--t-ref", type=float, metavar="NM",
                     help="requested axle torque T_r, N m (default 100; a CSV profile gives its own)")
    lau.add_argument("--profile", default="step", metavar="step|ramp|FILE",
                     help="request profile, or a CSV file with columns time (s since the request, made 1 s into the "
                          "run) and t_ref (N m)")
    lau.add_argument("--oil-temp", type=float, metavar="C", help="oil temperature, C (default rig.oil_temp_C)")
    lau.add_argument("--seed", type=int, default=0, metavar="N", help="sensor noise seed")
    lau.add_argument("--noise-scale", type=float, default=1.0, metavar="X", help="multiplier on the sensor noise")
    lau.add_argument("--no-noise", action="store_true", help="ideal sensors")
    lau.add_argument("--sequence", type=int, default=1, metavar="N",
                     help="launch the clutch N times, the controller's adaptation carried over (default 1)")
    lau.add_argument("--adaptation", metavar="A.toml", help="adaptation state to start from (written as "
                                                             "DIR/adaptation.toml after the launches)")
    lau.add_argument("--post-sync-hold", action="store_true",
                     help="after lock-up, move the CVT ratio (within driveline.ratio_min/_max/_rate) to hold the axle "
                          "torque at the request")
    lau.add_argument("--hold-time", type=float, metavar="S", help="time limit of the post-sync hold, s (default 3)")
    _param_args(lau)
    lau.set_defaults(func=_cmd_launch)

    ver = sub.add_parser("verify", help="Monte Carlo and corner-case verification of a launch controller")
    _out_arg(ver)
    ver.add_argument("--samples", type=int, default=1000, metavar="N", help="random samples (default 1000; plus corners)")
    ver.add_argument("--seed", type=int, default=0, metavar="S",
                     help="seed of the random samples and their noise (default 0)")
    ver.add_argument("--workers", type=int, metavar="W", help="processes (default: all cores)")
    _scheduler_arg(ver)
    ver.add_argument("--ranges", metavar="R.toml", help="what varies and how (default: the shipped ranges file)")
    ver.add_argument("--sequence", type=int, default=1, metavar="N",
                     help="launches per sample, the adaptation carried over; judged on the last (default 1)")
    _lockup_arg(ver)
    _controller_args(ver)
    _param_args(ver)
    ver.add_argument("--quiet", action="store_true", help="no progress bar")
    ver.set_defaults(func=_cmd_verify)

    rep = sub.add_parser("report", help="the main job: design and baseline for the plant, nominal launches, "
                                        "verification of both, report.md")
    _out_arg(rep)
    rep.add_argument("--samples", type=int, default=1000, metavar="N",
                     help="random samples verifying the launch controller (default 1000; plus corners)")
    rep.add_argument("--baseline-samples", type=int, default=200, metavar="N",
                     help="random samples verifying the baseline (default 200; plus corners)")
    rep.add_argument("--seed", type=int, default=0, metavar="S",
                     help="seed of the random samples and their noise (default 0)")
    rep.add_argument("--workers", type=int, metavar="W", help="processes (default: all cores)")
    _scheduler_arg(rep)
    rep.add_argument("--ranges", metavar="R.toml", help="what varies and how (default: the shipped ranges file)")
    rep.add_argument("--sequence", type=int, default=3, metavar="N",
                     help="launches per verified clutch, the adaptation carried over; judged on the last (default 3)")
    rep.add_argument("--controller-file", metavar="C.toml", help="the launch controller (default: designed on the plant)")
    rep.add_argument("--baseline-file", metavar="B.toml", help="the baseline (default: designed on the plant)")
    _lockup_arg(rep)
    _param_args(rep)
    rep.add_argument("--quiet", action="store_true", help="no progress bar")
    rep.set_defaults(func=_cmd_report)

    tun = sub.add_parser("tune", help="tune a controller's gains against the requirements (CMA-ES over training "
                                      "plants, verified on held-out ones): controller.toml, tune.md")
    _out_arg(tun)
    tun.add_argument("--samples", type=int, default=40, metavar="N", help="training plants (default 40)")
    tun.add_argument("--seed", type=int, default=0, metavar="S",
                     help="seed of the training plants (default 0; the validation plants take S + 1)")
    tun.add_argument("--heldout-samples", type=int, default=200, metavar="N", help="held-out plants (default 200)")
    tun.add_argument("--heldout-seed", type=int, default=1000, metavar="S",
                     help="seed of the held-out plants (default 1000)")
    tun.add_argument("--generations", type=int, default=8, metavar="G", help="CMA-ES generations (default 8)")
    tun.add_argument("--popsize", type=int, default=8, metavar="P", help="candidates per generation (default 8)")
    tun.add_argument("--sequence", type=int, default=3, metavar="N",
                     help="launches per plant, the adaptation carried over; judged on the last (default 3)")
    tun.add_argument("--state", metavar="FILE", help="save the search here after each generation; resume from it")
    tun.add_argument("--workers", type=int, metavar="W", help="processes (default: all cores)")
    tun.add_argument("--ranges", metavar="R.toml", help="what varies and how (default: the shipped ranges file)")
    _controller_args(tun)
    _param_args(tun)
    tun.add_argument("--quiet", action="store_true", help="no progress bar")
    tun.set_defaults(func=_cmd_tune)

    idf = sub.add_parser("identify", help="identify the clutch from measurement files; write identified.json, "
                                          "params.toml, report.md")
    idf.add_argument("files", nargs="+", metavar="FILE", help="measurement files (.csv, .mf4, .mat)")
    _out_arg(idf)
    idf.add_argument("--channels", metavar="MAP.toml", help="channel map: names and units of the files' channels")
    idf.add_argument("--mu-order", type=int, default=2, metavar="N", help="order of the mu(slip) polynomial (default 2)")
    _param_args(idf)  # the prior: piston area, efficiency, inertias ... and the base of params.toml
    idf.set_defaults(func=_cmd_identify)

    fmu = sub.add_parser("export-fmu", help="write an FMI 2.0 co-simulation FMU of the plant or of a launch controller")
    fmu.add_argument("--out", required=True, metavar="F.fmu", help="the FMU file to write")
    _controller_args(fmu, "export this controller kind instead of the plant (default: the plant)")
    fmu.add_argument("--pwm", action="store_true", help="plant: the valve input is a PWM duty cycle (default DC volts)")
    fmu.add_argument("--dt", type=float, metavar="S",
                     help="controller: sample time, s (default 0.001)")
    _param_args(fmu)
    fmu.set_defaults(func=_cmd_export_fmu)

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


#: options whose files a command reads (identify's recordings are its positional ``files``); ``--adaptation`` is not
#: among them: a launch's state carried over in place (``--adaptation DIR/adaptation.toml --out DIR``) is rewritten
_INPUTS = ("param_file", "controller_file", "baseline_file", "ranges", "profile", "channels", "files")


def _check_inputs_outside(args: argparse.Namespace) -> None:
    """Refuse (one line naming the option) an input file inside ``--out``: the output replaces that directory as a
    whole, so the input would be deleted with it (``identify runs/*/measured.mf4 --out runs`` the recordings,
    ``design --param-file ident/params.toml --out ident`` the identification)."""
    out = Path(args.out).resolve()
    for name in _INPUTS:
        value = getattr(args, name, None)
        for f in (value if isinstance(value, list) else [value]):
            if not f or (name == "profile" and f in ("step", "ramp")):
                continue
            path = Path(f).resolve()
            if path == out or out in path.parents:
                option = "FILE" if name == "files" else "--" + name.replace("_", "-")
                raise WetclutchError(f"{option} '{f}' lies inside --out '{args.out}', which the output replaces as a "
                                     "whole: it would be deleted; write the output elsewhere")


class Interrupted(KeyboardInterrupt):
    """A termination signal (SIGTERM, SIGHUP) taken as an interrupt, so that what is half done is cleaned up."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


def _on_signal(signum: int, frame: object) -> None:
    if os.getpid() != _MAIN_PID[0]:
        # a worker process forked from this one: it ends as the signal's default would, silently (its parent cleans up)
        signal.signal(signum, signal.SIG_DFL)
        os.kill(os.getpid(), signum)
        return
    # the workers, signalled with this process's group, die meanwhile; a process pool's thread may then trip over
    # futures the interrupt has just cancelled (CPython's InvalidStateError): noise, not news
    threading.excepthook = _quiet_pool_thread
    raise Interrupted(signum)


def _quiet_pool_thread(args: threading.ExceptHookArgs) -> None:
    from concurrent.futures import InvalidStateError
    from concurrent.futures.process import BrokenProcessPool

    if not issubclass(args.exc_type, (InvalidStateError, BrokenProcessPool)):
        threading.__excepthook__(args)


#: the process whose interrupts clean up and end the command (the workers it forks inherit the handlers)
_MAIN_PID = [0]
#: the threads' exception hook before the command (put back after it)
_HOOK: list = [threading.excepthook]


def _catch_signals() -> dict[int, object]:
    """Take SIGTERM and SIGHUP as interrupts in this process (the handlers they had, to be put back)."""
    _MAIN_PID[0] = os.getpid()
    _HOOK[0] = threading.excepthook
    before = {}
    for name in ("SIGTERM", "SIGHUP"):
        sig = getattr(signal, name, None)
        if sig is None:
            continue
        try:
            before[sig] = signal.signal(sig, _on_signal)
        except (ValueError, OSError):  # not the main thread: the default stays
            pass
    return before


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    before = _catch_signals()
    # the errors of the calls below name the command line's options (--t-ref), not the Python arguments (t_ref)
    token = COMMAND_LINE.set(True)
    try:
        if getattr(args, "out", None) is not None:
            # before any work: an output that cannot replace its target is refused at once (export-fmu's --out is a
            # file, checked by the export)
            if args.command == "export-fmu":
                check_target(args.out)
            else:
                check_out_dir(args.out)
                _check_inputs_outside(args)
        args.func(args)
    except WetclutchError as err:
        print(f"wetclutch: error: {err}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt as err:
        # Ctrl-C or a termination signal: what was half written is gone (outputs are written whole or not at all)
        signum = err.signum if isinstance(err, Interrupted) else signal.SIGINT
        out = getattr(args, "out", None)
        print(one_line(f"wetclutch: interrupted ({signal.Signals(signum).name})"
                       + (f"; '{out}' not written" if out is not None else "")
                       + (f"; --state '{args.state}' holds the search up to its last finished generation, if any"
                          if getattr(args, "state", None) else "")), file=sys.stderr)
        return EXIT_SIGNAL + int(signum)
    finally:
        for sig, handler in before.items():
            signal.signal(sig, handler)
        threading.excepthook = _HOOK[0]
        COMMAND_LINE.reset(token)
    return 0

