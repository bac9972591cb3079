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


def test_the_bundle_opens_from_disk(runs, tmp_path):
    out = tmp_path / "site"
    assert main([str(runs["noisy"]), f"--bundle={out}"]) == 0
    with chromium() as driver:
        driver.get((out / "index.html").as_uri())
        check_numbers(driver, runs["report"])
        wait_for(driver, 'a[href$="/all"]').click()
        wait_for(driver, "#pairs tr.pair").click()
        check_pair_plays(driver)
