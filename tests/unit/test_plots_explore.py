"""``fibersweep explore``: a self-contained page, checked in a real headless browser.

The page is written from a real refined sweep (tests/unit/_results_folder.py),
opened in Chromium (Debian's ``chromium`` and ``chromium-driver``, driven by
selenium) from a file URL, and must:

* load nothing over the network (the browser's resource timing lists nothing);
* draw the phase diagram (a screenshot holds the class colours);
* show a run's settings and outcome on hover;
* filter by a column (the run count follows);
* draw a run's trajectory on click (its traces, its id, and pixels of the
  pillar in the lower plot of a second screenshot).

Without a browser the test is skipped with the reason, except under CI
(``CI=true``), where .ci/run installs one and a missing browser is a failure.
"""

from __future__ import annotations

import io
import json
import os
import re
import shutil

import numpy as np
import pytest
from _results_folder import refined_folder
from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.plots.style import CLASS_STYLE


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    folder = refined_folder(tmp_path_factory.mktemp("sweep"))
    out = tmp_path_factory.mktemp("explore") / "explore.html"
    r = CliRunner().invoke(app, ["explore", str(folder), "-o", str(out)])
    assert r.exit_code == 0, r.output
    return out


def _data(html: str) -> dict:
    m = re.search(r'<script id="data" type="application/json">(.*?)</script>', html, re.S)
    return json.loads(m.group(1))


def test_page_is_self_contained_and_holds_every_run(page):

    html = page.read_text()
    # nothing fetched: no external script, style sheet, image or font
    assert not re.search(r"<(script|link|img)[^>]+(src|href)=", html)
    assert "@import" not in html
    data = _data(html)
    assert len(data["rows"]) >= 30 and "class" in data["columns"]
    ids = {r[data["columns"].index("id")] for r in data["rows"]}
    assert set(data["tracks"]) == ids  # every run of this sweep recorded its trajectory
    tr = next(iter(data["tracks"].values()))
    assert len(tr["x"]) == len(tr["t"]) <= 150


def _browser():
    """A headless Chromium driven by selenium, or the reason there is none."""
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.options import Options
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        return None, "selenium is not installed (pip install -e '.[test]')"
    binary = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver")
    if not binary or not driver:
        return None, "no chromium/chromedriver (apt-get install chromium chromium-driver)"
    opts = Options()
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
              "--window-size=1400,900"):  # fmt: skip
        opts.add_argument(a)
    opts.binary_location = binary
    return webdriver.Chrome(service=Service(driver), options=opts), ""


def _pixels(png: bytes, color: str) -> int:
    from PIL import Image

    rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=int)
    target = np.array([int(color[i : i + 2], 16) for i in (1, 3, 5)])
    return int((np.abs(rgb - target).sum(axis=-1) < 12).sum())


_POINT_JS = """
const gd = document.getElementById('phase'), want = arguments[0];
for (const tr of gd.calcdata) for (const p of tr) {
  if (tr[0].trace.customdata[p.i] !== want) continue;
  const xa = gd._fullLayout.xaxis, ya = gd._fullLayout.yaxis, box = gd.getBoundingClientRect();
  return [xa._offset + xa.c2p(p.x) - box.width / 2, ya._offset + ya.c2p(p.y) - box.height / 2];
}
return null;
"""


def test_explorer_in_a_headless_browser(page, tmp_path):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    driver, why = _browser()
    if driver is None:
        if os.environ.get("CI") == "true":
            pytest.fail(f"CI must test the explorer in a browser: {why}")
        pytest.skip(why)
    try:
        driver.get(page.as_uri())
        wait = WebDriverWait(driver, 30)
        wait.until(lambda d: "runs shown" in d.find_element(By.ID, "count").text)
        assert driver.execute_script("return performance.getEntriesByType('resource').length") == 0
        data = _data(page.read_text())
        n = len(data["rows"])
        assert driver.find_element(By.ID, "count").text == f"{n} of {n} runs shown"
        shot = driver.get_screenshot_as_png()
        (tmp_path / "explore.png").write_bytes(shot)
        for cls in ("Below", "Above"):
            assert _pixels(shot, CLASS_STYLE[cls]["color"]) > 200, cls

        # hover: the run's row in a tooltip
        cols = data["columns"]
        k = next(i for i, r in enumerate(data["rows"]) if r[cols.index("class")] == "Trapping")
        rid = data["rows"][k][cols.index("id")]
        phase = driver.find_element(By.ID, "phase")
        dx, dy = driver.execute_script(_POINT_JS, k)
        ActionChains(driver).move_to_element_with_offset(phase, int(dx), int(dy)).perform()
        wait.until(lambda d: "class: Trapping" in d.find_element(By.ID, "phase").text)
        assert f"id: {rid}" in phase.text and "theta0:" in phase.text and "delta:" in phase.text

        # click: the run's trajectory and its row
        ActionChains(driver).move_to_element_with_offset(phase, int(dx), int(dy)).click().perform()
        wait.until(lambda d: d.find_element(By.ID, "traj").get_attribute("data-run") == rid)
        n_traces = driver.execute_script(
            "return document.getElementById('traj').data.map(t => (t.x || []).length)"
        )
        assert len(n_traces) >= 3 and n_traces[1] == len(data["tracks"][rid]["x"])
        assert rid in driver.find_element(By.ID, "details").text
        shot = driver.get_screenshot_as_png()
        (tmp_path / "explore-click.png").write_bytes(shot)
        traj = driver.find_element(By.ID, "traj").rect
        from PIL import Image

        lower = Image.open(io.BytesIO(shot)).crop(
            (
                int(traj["x"]),
                int(traj["y"]),
                int(traj["x"] + traj["width"]),
                int(traj["y"] + traj["height"]),
            )  # fmt: skip
        )
        buf = io.BytesIO()
        lower.save(buf, format="PNG")
        assert _pixels(buf.getvalue(), "#dddddd") > 500  # the pillar, filled
        assert _pixels(buf.getvalue(), CLASS_STYLE["Trapping"]["color"]) > 50  # its path

        # filter: untick a class, the count follows
        n_above = sum(r[cols.index("class")] == "Above" for r in data["rows"])
        box = driver.find_element(
            By.CSS_SELECTOR, "div.filter[data-col='class'] input[value='Above']"
        )
        box.click()
        want = f"{n - n_above} of {n} runs shown"
        wait.until(lambda d: d.find_element(By.ID, "count").text == want)
        lo = driver.find_element(By.CSS_SELECTOR, "div.filter[data-col='y0'] input.lo")
        lo.send_keys("0.5")
        wait.until(lambda d: d.find_element(By.ID, "count").text != want)
    finally:
        driver.quit()


def test_page_data_survives_awkward_values():
    import pandas as pd

    from fibersweep.plots.explore import explorer_html
    from fibersweep.units import Geometry

    runs = pd.DataFrame({"id": ["a"], "theta0": [0.0], "y0": [0.3], "length": [1.0],
                         "class": [None], "status": ["failed"], "reason": ["</script><b>x"],
                         "delta": [float("nan")], "settings": ["s"]})  # fmt: skip
    html = explorer_html(runs, pd.DataFrame(columns=["id", "sample"]), {"s": Geometry()})
    assert html.count("</script>") == html.count("<script")  # the reason cannot close a script
    data = _data(html)
    row = dict(zip(data["columns"], data["rows"][0], strict=True))
    assert row["delta"] is None and row["class"] is None and row["reason"] == "</script><b>x"
    assert data["tracks"] == {} and len(data["outlines"]["s"]) == 3  # the triangle


def test_a_flexible_fiber_is_drawn_through_its_beads_or_not_at_all():
    """Never a head-to-tail chord for a bead-spring run: its beads, or a note saying how."""
    import pandas as pd

    from fibersweep.plots.explore import explorer_data
    from fibersweep.units import Geometry

    geo = Geometry()
    xb, yb = geo.base_center
    n, m = 6, 12
    t = np.linspace(0.0, 1.0, m)
    xs = xb - 60.0 + 10.0 * np.arange(m)
    s = np.linspace(-10, 10, n)
    beads = [np.column_stack([x + s, yb + 50 + 0.1 * s**2]).ravel().tolist() for x in xs]
    samples = pd.DataFrame({"id": "r", "sample": np.arange(m), "t": t, "x": xs, "y": yb + 55.0,
                            "head_x": xs + 10, "head_y": yb + 60.0, "tail_x": xs - 10,
                            "tail_y": yb + 60.0, "beads": beads})  # fmt: skip
    runs = pd.DataFrame({"id": ["r"], "theta0": [0.0], "y0": [0.5], "length": [1.0],
                         "class": ["Above"], "status": ["ok"], "settings": ["s"],
                         "model": ["bead-spring-ros2"], "n_beads": [n]})  # fmt: skip
    tr = explorer_data(runs, samples, {"s": geo})["tracks"]["r"]
    assert tr["fibers"] and all(len(xs_) == n for xs_, _ in tr["fibers"])
    bare = explorer_data(runs, samples.drop(columns="beads"), {"s": geo})["tracks"]["r"]
    assert bare["fibers"] is None and "all_beads" in bare["note"]
    rigid = runs.assign(model="rigid")
    chords = explorer_data(rigid, samples.drop(columns="beads"), {"s": geo})["tracks"]["r"]
    assert all(len(xs_) == 2 for xs_, _ in chords["fibers"])
