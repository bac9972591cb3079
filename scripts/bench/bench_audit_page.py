"""The run viewer's audit page (--arm.audit_at=viewer) in Chromium, labelled by a scripted person who presses the key
the moment each episode's video ends: seconds per audited trial on the page (the episode's video, then the label kept
in audit.jsonl), split into the video and what the page adds after the key. A real person's seconds after the video
(goal: under 10 s) are their own: the page keeps them with each label, and `report` prints their median.

Runs made (in --work, reused when there): a contrast run of the scripted oracle (8 bases, --record_dataset=true); a
copy of it with its first --trials done trials marked drawn for the audit, as an arm session marks them.

Usage: .venv/bin/python scripts/bench/bench_audit_page.py [--work DIR] [--trials N]; the last line holds the figures
as name=value."""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import tempfile
import time
from pathlib import Path

from bench_view import browser, evaluate, start_viewer

RUN = ["--policy.type=oracle", "--n_instances=8", "--seed=3", "--rerun=false", "--record_dataset=true"]


def drawn_copy(run: Path, target: Path, trials: int) -> list[int]:
    """`run` copied to `target` with its first `trials` done trials marked drawn; returns their indexes."""
    shutil.rmtree(target, ignore_errors=True)
    shutil.copytree(run, target)
    journal = target / "journal.jsonl"
    lines = [json.loads(line) for line in journal.read_text().splitlines()]
    drawn = [line["index"] for line in lines if line["status"] == "done"][:trials]
    for line in lines:
        if line["index"] in drawn:
            line["extra"]["audit_drawn"] = True
    journal.write_text("".join(json.dumps(line) + "\n" for line in lines))
    return drawn


def label_all(address: str, run: Path, count: int) -> list[tuple[float, float]]:
    """Per trial: (seconds from the trial shown to its video's end, seconds from the key to the label kept)."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    from lerobot_contrast.record.audit_labels import read_labels

    driver = browser()
    timings = []
    try:
        driver.get(address + "#/audit/r0")
        wait = WebDriverWait(driver, 60)
        for k in range(count):
            heading = wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, "#audit h3[data-trial]"))[0]
            trial, shown = int(heading.get_attribute("data-trial")), time.perf_counter()
            wait.until(lambda d: "ended" in d.find_element(By.ID, "audit-status").text)
            ended = time.perf_counter()
            driver.find_element(By.TAG_NAME, "body").send_keys("s" if k % 2 == 0 else "f")
            wait.until(lambda d, t=trial: t in read_labels(run))
            timings.append((ended - shown, time.perf_counter() - ended))
            wait.until(lambda d, t=trial: not d.find_elements(By.CSS_SELECTOR, f'#audit h3[data-trial="{t}"]'))
    finally:
        driver.quit()
    return timings


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--work", type=Path, default=None, help="keep the runs here (default: a temporary folder)")
    parser.add_argument("--trials", type=int, default=8, help="trials to label")
    args = parser.parse_args()
    if args.trials < 1:
        parser.error("--trials must be at least 1")
    work = args.work or Path(tempfile.mkdtemp(prefix="bench_audit_page_"))
    run = evaluate(work / "run", RUN)
    audited = work / "audited"
    drawn = drawn_copy(run, audited, args.trials)
    process, address, _ = start_viewer(audited)
    try:
        timings = label_all(address, audited, len(drawn))
    finally:
        process.terminate()
        process.wait()
    for trial, (video, kept) in zip(drawn, timings, strict=True):
        print(f"trial {trial}: video {video:.2f} s, label kept {kept:.2f} s after the key")
    videos, kept = [t[0] for t in timings], [t[1] for t in timings]
    print(f"trials={len(timings)} page_s_per_trial={statistics.mean(v + k for v, k in timings):.2f} "
          f"video_s_per_trial={statistics.mean(videos):.2f} kept_after_key_s={statistics.mean(kept):.2f} "
          f"kept_after_key_max_s={max(kept):.2f}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
