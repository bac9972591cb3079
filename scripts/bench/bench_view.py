"""The run viewer's figures: seconds until a 2,000-trial run's page is ready and open in Chromium (goal: opens in at
most 2 s), and the size of the default run's bundle (`view --bundle`) with its videos.

Runs made (in --work, reused when there): a contrast run of the scripted oracle over 286 bases (2,002 trials, no
recordings), and the default evaluation (`python -m lerobot_contrast.eval`: the learned default policy, 50 bases)
with --record_dataset=true, so its bundle holds every episode's video. The browser is Debian's chromium through
chromium-driver (scripts/setup.sh --dev installs them).

Usage: .venv/bin/python scripts/bench/bench_view.py [--work DIR] [--repeats N]; the last line holds the figures as
name=value."""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BIG = ["--policy.type=oracle", "--n_instances=286", "--rerun=false"]
DEFAULT = ["--record_dataset=true", "--rerun=false"]


def evaluate(output_dir: Path, flags: list[str]) -> Path:
    if (output_dir / "summary.json").is_file():
        return output_dir
    shutil.rmtree(output_dir, ignore_errors=True)
    command = [sys.executable, "-m", "lerobot_contrast.eval", *flags, f"--output_dir={output_dir}"]
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, timeout=3600)
    return output_dir


def start_viewer(run_dir: Path) -> tuple[subprocess.Popen, str, float]:
    """The viewer on a free port; the seconds from starting the command to the page being served."""
    start = time.perf_counter()
    command = [sys.executable, "-m", "lerobot_contrast.view", str(run_dir), "--port=0"]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    line = process.stdout.readline()
    if not line.startswith("viewing"):
        raise SystemExit(f"the viewer did not start: {line}{process.stderr.read()}")
    return process, line.split(" at ")[1].split()[0], time.perf_counter() - start


def browser():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    chromium, driver = shutil.which("chromium"), shutil.which("chromedriver")
    if not (chromium and driver):
        raise SystemExit("needs chromium and chromium-driver: apt-get install chromium chromium-driver")
    options = webdriver.ChromeOptions()
    options.binary_location = chromium
    for flag in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--window-size=1400,1000"):
        options.add_argument(flag)
    return webdriver.Chrome(options=options, service=Service(driver))


def seconds_to(driver, action, css: str) -> float:
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support import expected_conditions
    from selenium.webdriver.support.ui import WebDriverWait

    start = time.perf_counter()
    action()
    WebDriverWait(driver, 60, poll_frequency=0.01).until(
        expected_conditions.presence_of_element_located((By.CSS_SELECTOR, css))
    )
    return time.perf_counter() - start


def open_figures(run_dir: Path, repeats: int) -> dict[str, float]:
    """Seconds to serve, then (median of `repeats` fresh loads) to open the overview, and the list of all pairs."""
    process, url, ready = start_viewer(run_dir)
    driver = browser()
    try:
        opened, pairs = [], []
        for _ in range(repeats):
            driver.get("about:blank")
            opened.append(seconds_to(driver, lambda: driver.get(url), "section[data-title] tbody tr"))
            pairs.append(seconds_to(driver, lambda: driver.get(url + "#/p/r0/all"), "#pairs tr.pair"))
        trials = driver.execute_script("return view.doc.runs[0].trials.length")
    finally:
        driver.quit()
        process.terminate()
        process.wait(timeout=30)
    return {
        "trials": trials,
        "ready_s": ready,
        "open_s": statistics.median(opened),
        "pairs_s": statistics.median(pairs),
    }


def bundle_figures(run_dir: Path, out: Path) -> dict[str, float]:
    shutil.rmtree(out, ignore_errors=True)
    start = time.perf_counter()
    command = [sys.executable, "-m", "lerobot_contrast.view", str(run_dir), f"--bundle={out}"]
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, timeout=3600)
    seconds = time.perf_counter() - start
    files = [p for p in out.rglob("*") if p.is_file()]
    size = lambda paths: sum(p.stat().st_size for p in paths) / 1e6  # noqa: E731
    return {
        "bundle_s": seconds,
        "bundle_mb": size(files),
        "bundle_files": len(files),
        "videos_mb": size(p for p in files if p.suffix == ".mp4"),
        "episodes_mb": size((out / "data" / "episodes").rglob("*.js")),
        "runs_js_mb": size([out / "data" / "runs.js"]),
        "episodes": len(list((out / "data" / "episodes").rglob("*.js"))),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--work", type=Path, default=None, help="where the runs are made (default: a temporary folder)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    work = args.work or Path(tempfile.mkdtemp(prefix="bench_view_"))
    work.mkdir(parents=True, exist_ok=True)
    load = os.getloadavg()[0]
    big = evaluate(work / "oracle_2000", BIG)
    default = evaluate(work / "default", DEFAULT)
    opened = open_figures(big, args.repeats)
    bundled = bundle_figures(default, work / "default_bundle")
    figures = {
        "trials": opened["trials"],
        "ready_2000_s": f"{opened['ready_s']:.2f}",
        "open_2000_s": f"{opened['open_s']:.2f}",
        "pairs_2000_s": f"{opened['pairs_s']:.2f}",
        "default_bundle_mb": f"{bundled['bundle_mb']:.2f}",
        "default_bundle_files": bundled["bundle_files"],
        "default_videos_mb": f"{bundled['videos_mb']:.2f}",
        "default_episode_data_mb": f"{bundled['episodes_mb']:.2f}",
        "default_runs_js_mb": f"{bundled['runs_js_mb']:.2f}",
        "default_episodes": bundled["episodes"],
        "default_bundle_s": f"{bundled['bundle_s']:.1f}",
        "load_avg": f"{load:.1f}",
    }
    print(" ".join(f"{name}={value}" for name, value in figures.items()))


if __name__ == "__main__":
    main()
