"""A design written out: ``controller.toml`` (loadable by ``launch``, ``verify``, ``report``) and ``design.md``."""

from __future__ import annotations

from pathlib import Path

from ..launch.design import SETTINGS, Design
from ..launch.settings import to_toml
from ..output import atomic_dir


def design_md(d: Design, file: str = "controller.toml") -> str:
    """Markdown: what each setting is, its value and where it came from.

    Parameters
    ----------
    d
        The design.
    file
        The file it is written to, which the tables' line names (the baseline beside a launch controller goes to
        ``baseline.toml``).

    Returns
    -------
    str
        The section, headed by the controller's kind.
    """
    lines = [f"# Controller design: {d.kind}", "",
             "Every setting of the controller, its value (SI) and where it came from: the plant's parameters "
             "(and whether those were identified, given in the parameter file, set on the command line or left at "
             "the defaults), a tuning rule, or the controller's defaults.", "",
             "| setting | value | unit | what it is | source |", "|---|---|---|---|---|"]
    for name, spec in SETTINGS[d.kind].items():
        lines.append(f"| {name} | {d.settings[name]:.6g} | {spec.unit} | {spec.description} | {d.sources.get(name, '')} |")
    lines += ["", f"Tables (in `{file}`):", "",
              f"- feedforward map `input_V`: {d.temps_C.size} oil temperatures ({d.temps_C[0]:g}..{d.temps_C[-1]:g} C) x "
              f"{d.pressures_Pa.size} pressures ({d.pressures_Pa[0] / 1e5:g}..{d.pressures_Pa[-1] / 1e5:g} bar); "
              f"source: {d.sources.get('input_V', '')}"]
    if d.kind == "baseline":
        lines.append("- fill pulse `fill_s`: " + ", ".join(f"{t:g} C: {s * 1e3:.0f} ms" for t, s in zip(d.temps_C, d.fill_s))
                     + f"; source: {d.sources.get('fill_s', '')}")
    return "\n".join(lines) + "\n"


def write(designs: list[Design], out: str | Path) -> None:
    """``controller.toml`` (the first design) and, for further designs, ``<kind>.toml``; ``design.md``; atomically."""
    with atomic_dir(out) as d:
        for i, des in enumerate(designs):
            (d / ("controller.toml" if i == 0 else f"{des.kind}.toml")).write_text(to_toml(des))
        names = ["controller.toml" if i == 0 else f"{des.kind}.toml" for i, des in enumerate(designs)]
        (d / "design.md").write_text("\n".join(design_md(des, name) for des, name in zip(designs, names)))
