"""The HTML reports in a real browser: headless Chromium (the system's) driven by playwright.

Each product's ``.html`` is opened from disk with the network cut off; it must load
without console errors, render every bokeh plot it holds, show the pass/fail cells
that the product's own results call for, and show a verification sample's replay
command on hover. A screenshot of each page is saved (to ``$WETCLUTCH_SCREENSHOTS``
if set, else the test's temporary directory).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from playwright.sync_api import Page, sync_playwright

from inprocess import invoke
from wetclutch import params
from wetclutch.launch.metrics import REQUIREMENTS
from wetclutch.report import rig as rig_report
from wetclutch.rig import experiments as rig

CHROMIUM = "/usr/bin/chromium"


def _cli(*args: str) -> None:
    r = invoke(args)
    assert r.returncode == 0, r.stderr


@pytest.fixture(scope="module")
def reports(tmp_path_factory) -> dict[str, Path]:
    """Each product written by the command line on small inputs."""
    root = tmp_path_factory.mktemp("html")
    _cli("report", "--out", str(root / "main"), "--samples", "2", "--baseline-samples", "1", "--workers", "1", "--quiet")
    _cli("verify", "--out", str(root / "verify"), "--samples", "3", "--workers", "1", "--quiet")
    _cli("calibration-report", "--out", str(root / "calibration"))
    p = params.Params()
    for name, kw in {"step41": dict(experiment="step", level=1.5, oil_temp_C=41.0, seed=1),
                     "stair": dict(experiment="staircase", config="valve-only", input_mode="pwm", level=0.15,
                                   from_=0.0, seed=3)}.items():
        kw = dict(kw)
        rig_report.write(rig.run(kw.pop("experiment"), p, **kw), root / name)
    _cli("identify", str(root / "step41" / "measured.csv"), str(root / "stair" / "measured.csv"),
         "--out", str(root / "identify"))
    return {"main": root / "main" / "report.html", "verify": root / "verify" / "verify.html",
            "calibration": root / "calibration" / "report.html", "identify": root / "identify" / "report.html"}


@pytest.fixture(scope="module")
def browser():
    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM)
        yield b
        b.close()


def _open(browser, path: Path) -> tuple[Page, list[str], list[str]]:
    """The page loaded with every request but the file itself refused; (page, console errors, refused URLs)."""
    ctx = browser.new_context(viewport={"width": 1100, "height": 900}, offline=True)
    page = ctx.new_page()
    errors: list[str] = []
    refused: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))

    def route(r):
        if r.request.url == path.as_uri() or r.request.url.startswith("data:"):
            r.continue_()
        else:
            refused.append(r.request.url)
            r.abort()

    page.route("**/*", route)
    page.goto(path.as_uri())
    page.wait_for_function("() => window.Bokeh !== undefined && Bokeh.documents.length > 0", timeout=60_000)
    page.wait_for_function("""() => Object.values(Bokeh.index).every(v => v.has_finished())""", timeout=60_000)
    return page, errors, refused


_PLOTS = """() => {
  const models = [...Bokeh.documents[0]._all_models.values()].filter(m => m.type === 'Figure');
  const views = [];
  const walk = v => { if (v.model.type === 'Figure') views.push(v); for (const c of v.child_views ?? []) walk(c); };
  Object.values(Bokeh.index).forEach(walk);
  const drawn = views.filter(v => v.has_finished() && v.canvas_view.bbox.width > 100 && v.canvas_view.bbox.height > 100
                                  && v.renderer_views.size > 0);
  return {figures: models.length, drawn: drawn.length};
}"""


def _screenshot(page: Page, name: str, tmp_path: Path) -> Path:
    folder = Path(os.environ.get("WETCLUTCH_SCREENSHOTS", tmp_path))
    folder.mkdir(parents=True, exist_ok=True)
    shot = folder / f"{name}.png"
    page.screenshot(path=str(shot), full_page=True)
    img = np.asarray(Image.open(shot).convert("L"))
    assert (img < 250).mean() > 0.02, "the screenshot is (nearly) blank"
    return shot


@pytest.mark.parametrize("product", ["main", "verify", "calibration", "identify"])
def test_report_renders_in_chromium(reports, browser, product, tmp_path):
    path = reports[product]
    assert path.stat().st_size < 5e6
    page, errors, refused = _open(browser, path)
    assert not errors, errors
    assert not refused, f"the page asked for other files or the network: {refused}"
    n = page.evaluate(_PLOTS)
    # every image of the markdown report became a plot or was inlined
    md = path.with_name("verify.md" if product == "verify" else "report.md").read_text()
    assert md.count("![") > 0
    assert page.locator("img:not([src^='data:'])").count() == 0
    assert page.locator("div.plot").count() + page.locator("img").count() >= md.count("![")
    assert n["figures"] >= page.locator("div.plot").count() and n["drawn"] == n["figures"], n
    _screenshot(page, product, tmp_path)
    page.context.close()


def _cells(page: Page) -> tuple[int, int]:
    return page.locator("td.pass").count(), page.locator("td.fail").count()


def test_pass_fail_cells_match_the_results(reports, browser):
    names = REQUIREMENTS
    # calibration: one cell a figure
    rep = json.loads(reports["calibration"].with_name("report.json").read_text())
    page, _, _ = _open(browser, reports["calibration"])
    assert _cells(page) == (rep["passed"], rep["total"] - rep["passed"])
    page.context.close()
    # verify: each worst launch, each requirement
    ver = json.loads(reports["verify"].with_name("verify.json").read_text())
    page, _, _ = _open(browser, reports["verify"])
    flags = [w["requirements"][k] for w in ver["worst"] for k in names]
    assert _cells(page) == (sum(flags), len(flags) - sum(flags))
    page.context.close()
    # main: each nominal launch of design and baseline, and the worst launches of both verifications
    summary = json.loads(reports["main"].with_name("summary.json").read_text())
    flags = [s[c]["requirements"][k] for s in summary["nominal"] for c in ("design", "baseline") for k in names]
    for f in ("verify_launch.json", "verify_baseline.json"):
        flags += [w["requirements"][k] for w in json.loads(reports["main"].with_name(f).read_text())["worst"] for k in names]
    page, _, _ = _open(browser, reports["main"])
    assert _cells(page) == (sum(flags), len(flags) - sum(flags))
    page.context.close()


def test_hovering_a_verification_sample_shows_its_replay_command(reports, browser):
    ver = json.loads(reports["verify"].with_name("verify.json").read_text())
    page, _, _ = _open(browser, reports["verify"])
    # where a launch is drawn in the first scatter, in page pixels
    xy = page.evaluate("""() => {
      const views = [];
      const walk = v => { if (v.model.type === 'Figure') views.push(v); for (const c of v.child_views ?? []) walk(c); };
      Object.values(Bokeh.index).forEach(walk);
      // the first scatter of the launches (its data source carries the replay commands)
      const v = views.find(v => [...v.renderer_views.values()].some(r => r.model.data_source?.data?.replay !== undefined));
      v.el.scrollIntoView({block: "center"});
      const rv = [...v.renderer_views.values()].find(r => r.model.data_source.data.replay !== undefined);
      const d = rv.model.data_source.data;
      const g = rv.model.glyph;
      // a launch with both coordinates finite
      const i = d.index.findIndex((_, k) => Number.isFinite(d[g.x.field][k]) && Number.isFinite(d[g.y.field][k]));
      const box = v.canvas_view.el.getBoundingClientRect();
      return [box.left + v.frame.x_scale.compute(d[g.x.field][i]), box.top + v.frame.y_scale.compute(d[g.y.field][i]),
              d.index[i]];
    }""")
    page.mouse.move(xy[0] - 30, xy[1] - 30)
    page.mouse.move(xy[0], xy[1])
    page.wait_for_timeout(300)
    tooltip = page.locator(".wc-tip")  # inside the tooltip's shadow root
    tooltip.first.wait_for(state="visible", timeout=5000)
    text = tooltip.first.inner_text()
    launch = next(r for r in ver["results"] if r["index"] == xy[2])
    assert launch["replay"] in text
    assert f"#{launch['index']}" in text and ver["ranges"][0]["name"] in text, text
    page.context.close()


def test_a_verification_page_carries_its_sequence_lockup_figures_and_sample_sets(tmp_path):
    # a verification of 3 launches per clutch run to lock-up, written from a hand-made result (no browser needed):
    # the page says how often each clutch was launched and the first launch's pass rate, tables the lock-up time
    # and slip energy, and its percentile tables and histograms keep the random clutches and the corners apart
    from test_report_text import verification

    from wetclutch.launch import design as designs
    from wetclutch.report import verify as verify_report

    res = verification(sequence=3, lockup=True)
    verify_report.write(res, tmp_path / "v", designs.cached(params.Params()))
    page = (tmp_path / "v" / "verify.html").read_text()
    assert "launched 3 times in a row" in page
    assert f"On the first launch, before any adaptation, {100 * res['pass_rate_first_launch']:.1f} %" in page
    assert "<td>lock-up time t_sync [s]</td>" in page and "<td>slip energy [J]</td>" in page
    assert "Metrics over the 20 random clutches" in page and "Metrics over the 4 corners" in page
    # the histograms' legends: both sets drawn
    assert '"label":{"type":"value","value":"random"}' in page.replace(" ", "")
    assert '"label":{"type":"value","value":"corners"}' in page.replace(" ", "")
