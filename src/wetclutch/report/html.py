"""Self-contained HTML reports: the markdown report's text and tables with interactive plots in place of its PNGs.

Each product's HTML file is its markdown report rendered to HTML (so the two never
disagree), in which every image that has an interactive counterpart is replaced by a
bokeh plot (zoom, pan, hover) and every other image is inlined. Scripts and styles are
inlined too (bokeh's ``INLINE`` resources), so one file opens offline and can be sent
on its own. Cells that read ``pass`` or ``FAIL`` carry the classes ``pass`` and
``fail`` (coloured).

The plot builders (:func:`launch_plot`, :func:`verify_plots`, ...) return bokeh
layouts; :func:`page` puts text and plots together and :func:`write` writes a page.
"""

from __future__ import annotations

import base64
import re
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import jinja2
import markdown
import numpy as np
import pandas as pd
from bokeh.embed import file_html
from bokeh.layouts import column, gridplot
from bokeh.models import ColumnDataSource, HoverTool, Range1d, Span
from bokeh.models.layouts import LayoutDOM
from bokeh.palettes import Category10_10
from bokeh.plotting import figure
from bokeh.resources import INLINE

from ..ident.estimate import BAR
from ..launch import metrics

#: width of the plots, px
WIDTH = 900
PALETTE = Category10_10

_STYLE = """
body { font-family: system-ui, sans-serif; max-width: 1000px; margin: 1em auto; padding: 0 1em; color: #222;
       height: auto; display: block; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.9em; display: block; max-width: 100%; overflow-x: auto; }
th, td { border: 1px solid #ccc; padding: 2px 7px; text-align: right; }
th { background: #f0f0f0; }
th:first-child, td:first-child { text-align: left; }
td.pass { background: #d9f2d9; color: #135e13; }
td.fail { background: #f9d6d6; color: #8b0000; font-weight: bold; }
code { font-size: 0.85em; background: #f4f4f4; padding: 0 2px; word-break: break-all; }
.plot { margin: 0.8em 0 1.4em 0; }
img { max-width: 100%; }
"""

_PLAIN = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{{ title | e }}</title>
{% block postamble %}{% endblock %}</head>
<body>{% block contents %}{% endblock %}</body></html>"""

_TEMPLATE = """{% extends base %}
{% block postamble %}<style>{{ style }}</style>{% endblock %}
{% block contents %}{{ body }}{% endblock %}"""


def page(title: str, text_md: str, plots: Mapping[str, LayoutDOM], folder: Path | None = None) -> str:
    """One HTML document: ``text_md`` rendered, each image ``![..](NAME)`` replaced by ``plots[NAME]``.

    Parameters
    ----------
    title
        The document's title.
    text_md
        The report in markdown (tables included).
    plots
        Interactive plots by the file name of the image they replace.
    folder
        Where images without an interactive counterpart are read from (they are inlined);
        without it such images are left out.

    Returns
    -------
    str
        The HTML document, with bokeh's scripts inlined.
    """
    # "- #3: ..." would be read as a heading inside a list item
    text_md = re.sub(r"^(\s*[-*] )#", r"\1\\#", text_md, flags=re.M)
    # an image on a line of its own becomes a paragraph of its own (to be replaced whole)
    text_md = re.sub(r"^(!\[[^\]]*\]\([^)]+\))\s*$", r"\n\1\n", text_md, flags=re.M)
    body = markdown.markdown(text_md, extensions=["tables"], output_format="html")
    body = re.sub(r"<td>(<strong>)?pass(</strong>)?</td>", r'<td class="pass">\1pass\2</td>', body)
    body = re.sub(r"<td>(<strong>)?FAIL(</strong>)?</td>", r'<td class="fail">\1FAIL\2</td>', body)
    roots: list[LayoutDOM] = []
    parts: list[str] = []
    pos = 0
    for m in re.finditer(r'<p><img alt="([^"]*)" src="([^"]+)"\s*/?></p>', body):
        parts.append(body[pos:m.start()])
        pos = m.end()
        name = m.group(2)
        if name in plots:
            parts.append(f'<div class="plot">{{{{ embed(docs[0].roots[{len(roots)}]) }}}}</div>')
            roots.append(plots[name])
        elif folder is not None and (folder / name).is_file():
            data = base64.b64encode((folder / name).read_bytes()).decode("ascii")
            parts.append(f'<p><img alt="{m.group(1)}" src="data:image/png;base64,{data}"></p>')
    parts.append(body[pos:])
    # the report's text is data, not template: keep jinja away from it, then let only the embeds through
    text = "".join(p.replace("{{", "&#123;&#123;") if "embed(docs" not in p else p for p in parts)
    template = jinja2.Environment().from_string(_TEMPLATE.replace("{{ body }}", text))
    if not roots:  # nothing interactive: a plain page
        return template.render(base=jinja2.Template(_PLAIN), style=_STYLE, title=title)
    return file_html(roots, INLINE, title, template=template, template_variables={"style": _STYLE})


def write(path: Path, title: str, text_md: str, plots: Mapping[str, LayoutDOM]) -> None:
    """Write :func:`page` to ``path`` (inside an output directory being written atomically)."""
    path.write_text(page(title, text_md, plots, path.parent), encoding="utf-8")


def _fig(title: str, y_label: str, x_label: str = "time [s]", height: int = 230, **kw: Any) -> figure:
    f = figure(title=title, width=WIDTH, height=height, x_axis_label=x_label, y_axis_label=y_label,
               tools="pan,xwheel_zoom,box_zoom,reset,save", active_scroll="xwheel_zoom", output_backend="canvas", **kw)
    f.title.text_font_size = "11pt"
    return f


def _f32(v: Any) -> np.ndarray:
    return np.asarray(v, dtype=np.float32)


def launch_plot(runs: Sequence[tuple[str, pd.DataFrame]], truth: pd.DataFrame | None = None) -> LayoutDOM:
    """Axle torque, clutch pressure, valve input and speeds of one or more launches on linked time axes.

    Parameters
    ----------
    runs
        ``(label, signals)`` of each launch (the signals of :class:`wetclutch.launch.LaunchResult`);
        the first one's request and speeds are drawn too.
    truth
        The first launch's true signals (its true axle torque is drawn).
    """
    label0, s0 = runs[0]
    torque = _fig("Axle torque T_r [N m]", "N m")
    pres = _fig("Clutch pressure [bar]", "bar", x_range=torque.x_range)
    volt = _fig("Valve input u [V]", "V", x_range=torque.x_range)
    speed = _fig("Speeds [rad/s]", "rad/s", x_range=torque.x_range)
    for k, (label, s) in enumerate(runs):
        # one source a launch: its time column is stored once for all its lines
        cols = ["time", "T_r", "u"] + (["t_ref", "omega_p", "omega_1", "omega_s"] if k == 0 else [])
        src = ColumnDataSource({**{c: _f32(s[c]) for c in cols}, "p_bar": _f32(s["p_clutch"] * 1e-5)})
        c = PALETTE[k % len(PALETTE)]
        if k == 0:
            torque.line("time", "t_ref", source=src, color="black", line_dash="dashed", legend_label="request t_ref")
            for j, name in enumerate(("omega_p", "omega_1", "omega_s")):
                speed.line("time", name, source=src, color=PALETTE[(j + 2) % len(PALETTE)], legend_label=f"{name}, {label}")
        torque.line("time", "T_r", source=src, color=c, legend_label=f"T_r measured, {label}")
        pres.line("time", "p_bar", source=src, color=c, legend_label=label)
        volt.line("time", "u", source=src, color=c, legend_label=label)
    if truth is not None:
        torque.line(_f32(truth["time"]), _f32(truth["T_r"]), color=PALETTE[8], legend_label=f"T_r true, {label0}")
    figs = [torque, pres, volt, speed]
    for f in figs:
        f.legend.click_policy = "hide"
        f.legend.label_text_font_size = "8pt"
        f.add_tools(HoverTool(tooltips=[("t", "$x{0.000} s"), ("value", "$y{0.000}")], mode="mouse"))
    return column(figs)


#: a verification's metrics as the verification report lists them: (key, label, requirement limit or None)
MetricSpecs = Sequence[tuple[str, str, "float | None"]]


def _column(name: str) -> str:
    return name.replace(".", "_")


def verify_source(result: Mapping[str, Any], specs: MetricSpecs) -> ColumnDataSource:
    """One row per launch of a verification run: its sampled values, metrics, pass/fail and replay command."""
    rows = result["results"]
    data: dict[str, list[Any]] = {"index": [r["index"] for r in rows], "corner": [r["corner"] for r in rows],
                                  "result": ["pass" if r["all_pass"] else "FAIL" for r in rows],
                                  "replay": [r["replay"] for r in rows],
                                  "failed": [", ".join(k for k, ok in r["requirements"].items() if not ok) or "none"
                                             for r in rows],
                                  "color": ["#2ca02c" if r["all_pass"] else "#d62728" for r in rows]}
    for rg in result["ranges"]:
        data[_column(rg["name"])] = [r["values"].get(rg["name"], np.nan) for r in rows]
    for key, _, _ in specs:
        data[key] = [np.nan if r["metrics"].get(key) is None else r["metrics"][key] for r in rows]
    return ColumnDataSource(data)


def _range_label(rg: Mapping[str, Any]) -> str:
    how = {"rel": " (x plant)", "offset": " (+ plant)"}.get(rg["how"], "")
    return f"{rg['name']}{how}" + (f" [{rg['unit']}]" if rg.get("unit") else "")


def verify_plots(result: Mapping[str, Any], specs: MetricSpecs) -> LayoutDOM:
    """Histograms of the metrics with the limits, and scatters of the metrics over the sampled ranges.

    Every launch is a point; hovering it shows its sampled values, figures and the
    command that replays it. The scatters share one data source, so a selection in one
    marks the same launches in the others.
    """
    src = verify_source(result, specs)
    ranges = list(result["ranges"])
    rows = ([("launch", "#@index (corner: @corner)"), ("result", "@result (fails: @failed)")]
            + [(_range_label(rg), f"@{{{_column(rg['name'])}}}{{0.0000}}") for rg in ranges]
            + [(label, f"@{{{key}}}{{0.000}}") for key, label, _ in specs])
    # an HTML tooltip: the replay command is long and must wrap
    tips = ('<div class="wc-tip" style="max-width: 430px; font-size: 11px;"><table>'
            + "".join(f"<tr><td>{k}</td><td>{v}</td></tr>" for k, v in rows)
            + '</table><div>replay:</div><code style="white-space: normal; word-break: break-all;">@replay</code></div>')
    figs = []
    corner = np.asarray(src.data["corner"], dtype=bool)
    for key, label, limit in specs:
        every = np.asarray(src.data[key], dtype=float)
        ok = np.isfinite(every)
        v = every[ok]
        f = figure(title=label, width=WIDTH // 2, height=220, x_axis_label=label, y_axis_label="cases",
                   tools="pan,wheel_zoom,box_zoom,reset,save")
        if v.size:
            # the random samples and the corners stacked on common bins: the pass rates are the random samples',
            # the corners a worst-case set beside them, and each is told apart by its colour
            edges = np.histogram_bin_edges(v, bins=min(40, max(5, v.size // 5)))
            bottom = np.zeros(edges.size - 1)
            for name, mask, colour in (("random", ~corner, PALETTE[0]), ("corners", corner, PALETTE[1])):
                counts, _ = np.histogram(every[ok & mask], bins=edges)
                if not counts.any():
                    continue
                h = ColumnDataSource({"top": bottom + counts, "bottom": bottom.copy(), "count": counts,
                                      "left": edges[:-1], "right": edges[1:]})
                r = f.quad(top="top", bottom="bottom", left="left", right="right", source=h, fill_alpha=0.7,
                           color=colour, legend_label=name)
                f.add_tools(HoverTool(renderers=[r], tooltips=[("range", "@left{0.0000} .. @right{0.0000}"),
                                                               (f"launches ({name})", "@count")]))
                bottom = bottom + counts
            f.legend.label_text_font_size = "8pt"
        if limit is not None:
            f.add_layout(Span(location=limit, dimension="height", line_color="#d62728", line_width=2))
            if v.size:  # keep the limit in view
                lo, hi = min(float(v.min()), limit), max(float(v.max()), limit)
                f.x_range = Range1d(lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo))
        figs.append(f)
    # each metric with a limit over the ranges that take part in the corners (the ones that matter most)
    xs = [rg for rg in ranges if rg.get("corner")] or ranges[:4]
    ys = [(key, label, limit) for key, label, limit in specs if limit is not None] or list(specs)
    for i, rg in enumerate(xs):
        key, label, limit = ys[i % len(ys)]
        f = figure(title=f"{label} over {rg['name']}", width=WIDTH // 2, height=260, x_axis_label=_range_label(rg),
                   y_axis_label=label, tools="pan,wheel_zoom,box_zoom,box_select,tap,reset,save")
        f.scatter(_column(rg["name"]), key, source=src, color="color", size=6, alpha=0.7)
        if limit is not None:
            f.add_layout(Span(location=limit, dimension="width", line_color="#d62728", line_width=1.5))
        f.add_tools(HoverTool(tooltips=tips))
        figs.append(f)
    return gridplot(figs, ncols=2)


def calibration_plots(figs: Sequence[Any], band: Callable[[Any, Any], tuple[Any, Any]]) -> LayoutDOM:
    """One panel per calibration figure: the study's value or curve, its tolerance band and the model.

    Parameters
    ----------
    figs
        :class:`wetclutch.rig.calibration.Figure` objects.
    band
        ``band(figure, published) -> (low, high)``: the tolerance band around the published value(s).
    """
    panels = []
    for f in figs:
        colour = "#2ca02c" if f.passed else "#d62728"
        c = f.curve
        p = figure(title=f.name, width=WIDTH // 2, height=260, tools="pan,wheel_zoom,box_zoom,reset,save")
        p.title.text_font_size = "8pt"
        if c and "published" in c:
            xkey = next(iter(c))
            x = np.asarray(c[xkey], dtype=float)
            lo, hi = band(f, c["published"])
            p.varea(x=x, y1=np.asarray(lo, dtype=float), y2=np.asarray(hi, dtype=float), color="#d9d9d9",
                    legend_label="tolerance")
            p.line(x, np.asarray(c["published"], dtype=float), color="black", line_dash="dashed", legend_label="study")
            for k, key in enumerate(("simulated", "up", "down")):
                if key in c:
                    col = colour if key == "simulated" else PALETTE[k]
                    lab = "model" if key == "simulated" else f"model {key}"
                    p.line(x, np.asarray(c[key], dtype=float), color=col, legend_label=lab)
                    p.scatter(x, np.asarray(c[key], dtype=float), color=col, size=4, legend_label=lab)
            p.xaxis.axis_label = xkey
            p.yaxis.axis_label = f"p [{f.unit}]"
            p.add_tools(HoverTool(tooltips=[(xkey, "$x{0.000}"), ("p", "$y{0.000}")]))
        else:
            value = float(f.published) if isinstance(f.published, (int, float)) else None
            if value is not None:
                lo, hi = band(f, value)
                p.quad(left=-1, right=1, bottom=float(lo), top=float(hi), color="#d9d9d9", legend_label="tolerance")
                p.line([-1, 1], [value, value], color="black", line_dash="dashed", legend_label="study")
            src = ColumnDataSource({"x": [0.0], "y": [float(f.simulated)], "study": [str(f.published)]})
            p.scatter("x", "y", source=src, size=10, color=colour, legend_label="model")
            p.add_tools(HoverTool(tooltips=[("model", "@y{0.0000}"), ("study", "@study")]))
            p.xaxis.visible = False
            p.yaxis.axis_label = f.unit
        p.legend.label_text_font_size = "7pt"
        p.legend.location = "top_left"
        panels.append(p)
    return gridplot(panels, ncols=2)


def xy_plot(title: str, x_label: str, y_label: str, lines: Sequence[tuple[str, Any, Any, str]],
            log: bool = False, height: int = 300) -> figure:
    """A plot of several series: ``(label, x, y, style)`` with style ``line``, ``dashed`` or ``points``."""
    kw = {"x_axis_type": "log", "y_axis_type": "log"} if log else {}
    f = figure(title=title, width=WIDTH, height=height, x_axis_label=x_label, y_axis_label=y_label,
               tools="pan,wheel_zoom,box_zoom,reset,save", **kw)
    for k, (label, x, y, style) in enumerate(lines):
        c = PALETTE[k % len(PALETTE)]
        if style == "points":
            f.scatter(_f32(x), _f32(y), size=3, alpha=0.5, color=c, legend_label=label)
        else:
            f.line(_f32(x), _f32(y), color=c, line_dash="dashed" if style == "dashed" else "solid", legend_label=label,
                   line_width=1.5)
    f.add_tools(HoverTool(tooltips=[(x_label, "$x{0.0000}"), (y_label, "$y{0.0000}")]))
    f.legend.click_policy = "hide"
    f.legend.label_text_font_size = "8pt"
    return f


# ---------------------------------------------------------------- the products' pages


def _launch_title(summary: Mapping[str, Any]) -> str:
    return f"{summary['oil_temp_C']:g} C, {summary['t_ref_Nm']:g} N m"


def write_main(path: Path, text_md: str, job: Any, specs: MetricSpecs) -> None:
    """The main job's page: its report, every nominal launch (design against baseline) and both verifications.

    ``job`` is a :class:`wetclutch.launch.campaign.MainJob`; its launches are pairs of
    :class:`~wetclutch.launch.LaunchResult` (design, baseline); ``specs``: the metrics shown, as the
    verification report lists them.
    """
    def plot(i: int) -> LayoutDOM:
        res, base = job.launches[i]
        return launch_plot([(res.controller, res.signals), (base.controller, base.signals)], res.truth)

    plots: dict[str, LayoutDOM] = {name: plot(int(name[7:-4]))
                                   for name in re.findall(r"!\[[^\]]*\]\((launch_\d+\.png)\)", text_md)}
    extra = ["", "## Every nominal launch", "", "Drag to pan, scroll to zoom the time axis (shared by the four "
             "plots of a launch); click a legend entry to hide its line.", ""]
    for i, (res, _) in enumerate(job.launches):
        plots[f"nominal_{i}.png"] = plot(i)
        extra += [f"### {_launch_title(res.summary)}", "", f"![launch {_launch_title(res.summary)}](nominal_{i}.png)", ""]
    for name in re.findall(r"!\[[^\]]*\]\((verify_\w+\.png)\)", text_md):
        plots[name] = verify_plots(job.verify_baseline if "baseline" in name else job.verify, specs)
    extra += ["## Worst launches of the verifications", "", worst_table(job.verify, specs),
              worst_table(job.verify_baseline, specs)]
    write(path, "wetclutch launch report", text_md + "\n".join(extra), plots)


def worst_table(result: Mapping[str, Any], specs: MetricSpecs) -> str:
    """Markdown: the worst launches of a verification, their values, each requirement's pass/fail, the replay command."""
    names = list(metrics.REQUIREMENTS)
    lines = [f"### Worst launches, {result['controller']}", "",
             "| launch | sampled values | " + " | ".join(label for _, label, _ in specs) + " | "
             + " | ".join(names) + " | replay |", "|---" * (3 + len(specs) + len(names)) + "|"]
    num = lambda v: "-" if v is None else f"{v:.4g}"  # noqa: E731
    for w in result["worst"]:
        vals = ", ".join(f"{k} {v:.4g}" for k, v in w["values"].items())
        lines.append(f"| #{w['index']} | {vals} | " + " | ".join(num(w["metrics"].get(k)) for k, _, _ in specs) + " | "
                     + " | ".join("pass" if w["requirements"].get(k) else "FAIL" for k in names)
                     + f" | `{w['replay']}` |")
    return "\n".join(lines) + "\n"


def write_verify(path: Path, text_md: str, result: Mapping[str, Any], specs: MetricSpecs) -> None:
    """A verification's page: its report with the interactive histograms and scatters, and its worst launches.

    ``specs``: the metrics shown, as the verification report lists them.
    """
    write(path, f"wetclutch verify {result['controller']}", text_md + "\n" + worst_table(result, specs),
          {"histograms.png": verify_plots(result, specs)})


def write_calibration(path: Path, text_md: str, figs: Sequence[Any],
                      band: Callable[[Any, Any], tuple[Any, Any]]) -> None:
    """The calibration's page (``figs``: :class:`wetclutch.rig.calibration.Figure`; ``band``: see
    :func:`calibration_plots`)."""
    write(path, "wetclutch calibration", text_md, {"figures.png": calibration_plots(figs, band)})


def _every(n: int, most: int = 3000) -> slice:
    """A stride that keeps at most about ``most`` of ``n`` points (the file stays small)."""
    return slice(None, None, max(1, n // most))


def identify_plots(result: Any) -> dict[str, LayoutDOM]:
    """Interactive plots of an identification (``result``: :class:`wetclutch.ident.result.Identification`).

    Friction against slip, the step models, the frequency responses, the static curves and
    the validation on held-out files, by the PNG of the markdown report they replace.
    """
    bar = BAR
    e = result.estimates
    plots: dict[str, LayoutDOM] = {}
    if result.slips and "mu_slip_poly" in e:
        coef = np.array(e["mu_slip_poly"].value)
        lines = []
        for s in result.slips:
            k = _every(s.slip.size)
            lines.append((f"{s.rec.path.parent.name}/{s.rec.path.name}", s.slip[k], s.mu[k], "points"))
        w = np.linspace(0.0, max(float(s.slip.max()) for s in result.slips), 200)
        lines.append(("identified", w, np.polyval(coef, w), "line"))
        prior = result.prior.friction
        lines.append(("prior", w, np.polyval(prior.mu_slip_poly, w) * prior.mu_scale, "dashed"))
        plots["friction.png"] = xy_plot("friction coefficient versus slip", "slip [rad/s]", "mu [m]", lines)
    if result.steps:
        lines = []
        for m in result.steps:
            t, y, fit = m.fit
            k = _every(t.size)
            if m.order == 1:
                lines.append((f"{m.rec.path.parent.name} measured", t[k] - m.t0, y[k] / bar, "points"))
            lines.append((f"{m.rec.path.parent.name} order {m.order}", t[k] - m.t0, fit[k] / bar,
                          "line" if m.order == 1 else "dashed"))
        plots["steps.png"] = xy_plot("pressure step models", "time after the command change [s]", "p [bar]", lines)
    if result.responses:
        mag, phase = [], []
        for r in result.responses:
            model = r.model_response(r.freq)
            name = r.rec.path.parent.name
            mag += [(f"{name} measured", r.freq, np.abs(r.H) / bar, "points"),
                    (f"{name} model", r.freq, np.abs(model) / bar, "line")]
            phase += [(f"{name} measured", r.freq, np.degrees(np.unwrap(np.angle(r.H))), "points"),
                      (f"{name} model", r.freq, np.degrees(np.unwrap(np.angle(model))), "line")]
        fm = xy_plot("frequency response, command to pressure", "frequency [Hz]", "|p/u| [bar/unit]", mag, log=True)
        fp = xy_plot("phase", "frequency [Hz]", "phase [deg]", phase)
        fp.x_range = fm.x_range
        plots["bode.png"] = column(fm, fp)
    if result.plateaus:
        lines = []
        for g in sorted({(q.rec.config, q.rec.input_mode) for q in result.plateaus}):
            for direction in ("up", "down", "first"):
                sel = [q for q in result.plateaus if (q.rec.config, q.rec.input_mode) == g and q.direction == direction]
                if sel:
                    lines.append((f"{g[0]} {g[1]} {direction}", [q.u for q in sel], [q.p / bar for q in sel], "points"))
        for key, est in e.items():
            if key.startswith(("valve_gain_poly", "clutch_gain_poly")):
                u = np.array([pt[0] for pt in est.extra["points"]])
                uu = np.linspace(u.min(), u.max(), 50)
                lines.append((f"{key} fit", uu, np.polyval(est.value, uu), "line"))
        plots["static.png"] = xy_plot("static pressure versus command", "command (V or duty)", "static p [bar]", lines)
    if result.validation:
        torque, pressure = [], []
        for v in result.validation:
            tr, name = v["trace"], f"{Path(v['file']).parent.name}"
            if v["signal"] == "T_r":
                order = np.argsort(tr["slip"])
                k = _every(order.size)
                torque += [(f"{name} measured", tr["slip"][order][k], tr["measured"][order][k], "points"),
                           (f"{name} predicted", tr["slip"][order][k], tr["predicted"][order][k], "line")]
            elif v["signal"] == "p_clutch":
                k = _every(len(tr["time"]))
                pressure += [(f"{name} measured", tr["time"][k], tr["measured"][k] / bar, "line"),
                             (f"{name} predicted", tr["time"][k], tr["predicted"][k] / bar, "dashed")]
        figs = []
        if torque:
            figs.append(xy_plot("held-out torque", "slip [rad/s]", "T_r [N m]", torque))
        if pressure:
            figs.append(xy_plot("held-out pressure", "time [s]", "p [bar]", pressure))
        if figs:
            plots["validation.png"] = column(figs)
    return plots


def write_identify(path: Path, text_md: str, result: Any) -> None:
    """An identification's page: its report with interactive plots (the others inlined as images)."""
    write(path, "wetclutch identification", text_md, identify_plots(result))
