"""Screenshots of the run viewer for the docs (docs/figures/viewer_*.png): the overview, a perturbation's flipped
pairs and a pair opened mid-play, of a run with a dataset (the default run with --record_dataset=true), in Debian's
headless Chromium (chromium, chromium-driver).

    .venv/bin/python scripts/figures/figure_viewer.py RUN_DIR [OUT_DIR]
"""

from __future__ import annotations

import shutil
import sys
import threading
import time
from pathlib import Path

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By
from selenium.webdriver.support import expected_conditions
from selenium.webdriver.support.ui import WebDriverWait

from lerobot_contrast.view.payload import Pages
from lerobot_contrast.view.server import serve, url


def browser() -> webdriver.Chrome:
    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium")
    for flag in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--window-size=1400,1000",
                 "--autoplay-policy=no-user-gesture-required", "--hide-scrollbars"):  # fmt: skip
        options.add_argument(flag)
    return webdriver.Chrome(options=options, service=Service(shutil.which("chromedriver")))


def wait_for(driver, css: str):
    located = expected_conditions.presence_of_element_located((By.CSS_SELECTOR, css))
    return WebDriverWait(driver, 60).until(located)


def main() -> None:
    run_dir, out = Path(sys.argv[1]), Path(sys.argv[2] if len(sys.argv) > 2 else "docs/figures")
    server = serve(0, Pages([str(run_dir)]))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    driver = browser()
    try:
        driver.get(url(server))
        wait_for(driver, "#overview section[data-title] tbody tr")
        time.sleep(1)
        driver.save_screenshot(str(out / "viewer_overview.png"))
        # The perturbation with the most flips, flips only.
        name = driver.execute_script(
            """const run = view.doc.runs[0], counts = {};
               for (const p of run.pairs) if (p.flip) { const t = view.byIndex[run.id][p.perturbed];
                 counts[t.perturbation] = (counts[t.perturbation] || 0) + 1; }
               return Object.entries(counts).sort((a, b) => b[1] - a[1])[0][0];"""
        )
        driver.get(url(server) + f"#/p/r0/{name}")
        wait_for(driver, 'input[data-filter="flips only"]').click()
        wait_for(driver, "#pairs tr.pair")
        time.sleep(1)
        driver.save_screenshot(str(out / "viewer_pairs.png"))
        driver.find_element(By.CSS_SELECTOR, "#pairs tr.pair").click()
        wait_for(driver, "#pair video")
        wait_for(driver, "#play").click()
        time.sleep(2.5)
        wait_for(driver, "#play").click()  # pause mid-episode, both videos at the same time
        time.sleep(0.5)
        driver.execute_script("window.scrollTo(0, 60)")
        driver.save_screenshot(str(out / "viewer_pair.png"))
    finally:
        driver.quit()
        server.shutdown()
    print(f"wrote {out}/viewer_overview.png, viewer_pairs.png, viewer_pair.png")


if __name__ == "__main__":
    main()
