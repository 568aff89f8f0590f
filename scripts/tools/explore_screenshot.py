"""Screenshot of an explorer page after a click on one run, for docs/figures/explore.png.

Opens the page in headless Chromium (selenium, Debian's chromium and
chromium-driver), clicks the first run of the class given, and saves the window.
    python3 scripts/tools/explore_screenshot.py results/quick/explore.html explore.png --cls \
        Pole-vaulting
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import WebDriverWait

POINT_JS = """
const gd = document.getElementById('phase'), want = arguments[0];
for (const tr of gd.calcdata) for (const p of tr) {
  if (tr[0].trace.name.split(' (')[0] !== want) continue;
  const xa = gd._fullLayout.xaxis, ya = gd._fullLayout.yaxis, box = gd.getBoundingClientRect();
  return [xa._offset + xa.c2p(p.x) - box.width / 2, ya._offset + ya.c2p(p.y) - box.height / 2];
}
return null;
"""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("page", type=Path)
    ap.add_argument("out", type=Path)
    ap.add_argument("--cls", default="Pole-vaulting", help="class of the run to click")
    args = ap.parse_args()
    binary, driver = shutil.which("chromium"), shutil.which("chromedriver")
    if not binary or not driver:
        print("needs chromium and chromedriver", file=sys.stderr)
        return 1
    opts = Options()
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1300,820"):
        opts.add_argument(a)
    opts.binary_location = binary
    d = webdriver.Chrome(service=Service(driver), options=opts)
    try:
        d.get(args.page.resolve().as_uri())
        WebDriverWait(d, 30).until(lambda d: "runs shown" in d.find_element(By.ID, "count").text)
        xy = d.execute_script(POINT_JS, args.cls)
        if xy is None:
            print(f"no run of class {args.cls}", file=sys.stderr)
            return 1
        phase = d.find_element(By.ID, "phase")
        ActionChains(d).move_to_element_with_offset(phase, int(xy[0]), int(xy[1])).click().perform()
        WebDriverWait(d, 30).until(
            lambda d: d.find_element(By.ID, "traj").get_attribute("data-run")
        )
        # move the pointer off the diagram, so its tooltip does not cover the picture
        ActionChains(d).move_to_element(d.find_element(By.ID, "count")).perform()
        d.save_screenshot(str(args.out))
    finally:
        d.quit()
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
