"""In a real browser (headless Chromium): the page of a small run shows report's numbers, opens a perturbation's
pairs from the table, a pair from the list, and plays both videos; the A/B view and the bundle opened from disk."""

import threading

import pytest
from selenium.webdriver.common.by import By

from lerobot_contrast.view.command import main
from lerobot_contrast.view.payload import Pages
from lerobot_contrast.view.server import serve, url
from tests.view.browser import chromium, play_videos, table_rows, wait_for
from tests.view.conftest import report_rows

pytestmark = [pytest.mark.xdist_group("view"), pytest.mark.slow]


@pytest.fixture
def page_of():
    servers = []

    def start(*runs) -> str:
        server = serve(0, Pages([str(r) for r in runs]))
        threading.Thread(target=server.serve_forever, daemon=True).start()
        servers.append(server)
        return url(server)

    yield start
    for server in servers:
        server.shutdown()
        server.server_close()


def check_numbers(driver, report_md):
    wait_for(driver, "#overview")
    shown = table_rows(driver, "SPL per perturbation")
    changes = dict(report_rows(report_md, "Sensitivity"))
    assert [row[:2] for row in shown] == report_rows(report_md, "SPL per perturbation")
    assert [row[2] for row in shown] == [changes.get(row[0], "-") for row in shown]
    assert table_rows(driver, "Summary") == report_rows(report_md, "Summary")


def check_pair_plays(driver):
    wait_for(driver, "#pair video")
    videos = play_videos(driver)
    assert len(videos) == 2
    for video in videos:
        assert video["error"] is None and video["ready"] >= 2 and video["frames"] > 0, videos
        assert video["time"] > 0.2 or video["paused"], videos  # an episode shorter than 1.5 s may have ended
    assert len(driver.find_elements(By.CSS_SELECTOR, "#pair .uplot")) >= 4  # state and action, both sides


def test_table_to_perturbation_to_pair_to_video(runs, page_of):
    with chromium() as driver:
        driver.get(page_of(runs["noisy"]))
        check_numbers(driver, runs["report"])
        flipped = driver.execute_script(
            "const run = view.doc.runs[0]; const p = run.pairs.find((p) => p.flip); "
            "return p && view.byIndex[run.id][p.perturbed].perturbation"
        )
        driver.find_element(
            By.CSS_SELECTOR, f'section[data-title^="SPL per perturbation"] tr[data-key="{flipped}"]'
        ).click()
        wait_for(driver, "#pairs tr.pair")
        everything = len(driver.find_elements(By.CSS_SELECTOR, "#pairs tr.pair"))
        driver.find_element(By.CSS_SELECTOR, 'input[data-filter="flips only"]').click()
        flips = driver.find_elements(By.CSS_SELECTOR, "#pairs tr.pair")
        assert 1 <= len(flips) <= everything
        assert all(row.find_elements(By.CSS_SELECTOR, ".flip") for row in flips)
        flips[0].click()
        check_pair_plays(driver)
        assert driver.find_elements(By.CSS_SELECTOR, "#pair .flip")


def test_two_policies_side_by_side_with_a_run_that_has_no_videos(runs, page_of):
    with chromium() as driver:
        driver.get(page_of(runs["noisy"], runs["oracle"]))
        wait_for(driver, "a.ab-link").click()
        wait_for(driver, "#ab-table td.cell").click()
        wait_for(driver, "#pair video")
        absent = driver.find_element(By.CSS_SELECTOR, "#pair .absent").text
        assert absent.startswith("Videos absent: this run recorded no dataset")


def test_an_ab_session_shows_the_sequential_verdict_and_plays_both_policies(runs, page_of):
    import json

    verdict = json.loads((runs["session"] / "summary.json").read_text())["stopping"]["pairs"][0]["verdict"]
    with chromium() as driver:
        driver.get(page_of(runs["session"]))
        wait_for(driver, "a.ab-link").click()
        assert wait_for(driver, "#ab .verdict").text == verdict
        wait_for(driver, "#ab-table td.cell").click()
        wait_for(driver, "#pair .column")
        assert len(driver.find_elements(By.CSS_SELECTOR, "#pair .column")) == 2


def test_the_bundle_opens_from_disk(runs, tmp_path):
    out = tmp_path / "site"
    assert main([str(runs["noisy"]), f"--bundle={out}"]) == 0
    with chromium() as driver:
        driver.get((out / "index.html").as_uri())
        check_numbers(driver, runs["report"])
        wait_for(driver, 'a[href$="/all"]').click()
        wait_for(driver, "#pairs tr.pair").click()
        check_pair_plays(driver)


def with_staging_check(run) -> tuple[int, int]:
    """`run` with the staging bench's measurement (as the runner journals it) on its first perturbed trial that moved
    an object; returns (original, perturbed) trial indexes."""
    import json

    journal = run / "journal.jsonl"
    lines = [json.loads(line) for line in journal.read_text().splitlines()]
    trial = next(t for t in lines if t["perturbation"] and t["instance"] and t["axis"] in ("S", "SB"))
    objects = trial["instance"]["scene"]["objects"]
    first, second = sorted(objects)[:2]
    trial["extra"]["staging"] = {
        "tolerance_m": 0.02, "planned_cost": trial["cost"], "moved_m": 0.05,
        "before": {name: [x + 0.05, y, yaw] for name, (x, y, yaw) in objects.items()},
        "placed": {first: objects[first][:2], second: [objects[second][0] + 0.051, objects[second][1]]},
        "off_m": {first: 0.0, second: 0.031}, "accepted_off": [second],
    }  # fmt: skip
    journal.write_text("".join(json.dumps(t) + "\n" for t in lines))
    original = next(t for t in lines if t["base_id"] == trial["base_id"] and t["perturbation"] is None)
    return original["index"], trial["index"]


def test_a_pair_shows_the_staging_check_where_the_run_measured_it(runs, copy_of, page_of):
    run = copy_of(runs["noisy"])
    original, perturbed = with_staging_check(run)
    with chromium() as driver:
        driver.get(page_of(run) + f"#/pair/r0/{original}/r0/{perturbed}")
        check = wait_for(driver, f'.column[data-trial="{perturbed}"] .staging svg')
        assert len(check.find_elements(By.CSS_SELECTOR, "rect")) == 2 and "3.1 cm off" in check.text
        assert not driver.find_elements(By.CSS_SELECTOR, f'.column[data-trial="{original}"] .staging')


def test_a_run_in_progress_refreshes_as_trials_come_in(in_progress, page_of):
    from selenium.webdriver.support.ui import WebDriverWait

    run, lines = in_progress
    journal = run / "journal.jsonl"
    with chromium() as driver:
        driver.get(page_of(run))
        wait_for(driver, "#overview")
        assert driver.find_element(By.ID, "live").is_displayed()
        before = table_rows(driver, "Summary")
        journal.write_text("".join(lines))
        WebDriverWait(driver, 20).until(
            lambda d: d.execute_script("return view.doc.runs[0].trials.length") == len(lines)
        )
        after = table_rows(driver, "Summary")
        assert after != before and int(after[0][2]) + int(after[0][3]) == len(lines)  # trials and n/a: every line
