"""A headless Chromium (Debian's chromium and chromium-driver) driven by Selenium, for the viewer's browser tests:
skipped where it is not installed, except in CI, where scripts/setup.sh --dev installs it and its absence fails."""

import os
import shutil
from contextlib import contextmanager

import pytest

CHROMIUM, DRIVER = shutil.which("chromium"), shutil.which("chromedriver")


@contextmanager
def chromium(phone: bool = False):
    """`phone`: a phone's screen (390x844 CSS pixels, touch), as the person's page is seen at the bench."""
    if not (CHROMIUM and DRIVER):
        if os.environ.get("CI"):
            pytest.fail("chromium and chromium-driver are missing in CI: scripts/setup.sh --dev installs them")
        pytest.skip("needs chromium and chromium-driver (apt-get install chromium chromium-driver)")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--window-size=1400,1000",
                 "--autoplay-policy=no-user-gesture-required", "--allow-file-access-from-files"):  # fmt: skip
        options.add_argument(flag)
    if phone:
        options.add_experimental_option(
            "mobileEmulation", {"deviceMetrics": {"width": 390, "height": 844, "pixelRatio": 3.0, "touch": True}}
        )
    driver = webdriver.Chrome(options=options, service=Service(DRIVER))
    try:
        yield driver
    finally:
        driver.quit()


def wait_for(driver, css: str, timeout: float = 30):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support import expected_conditions
    from selenium.webdriver.support.ui import WebDriverWait

    return WebDriverWait(driver, timeout).until(expected_conditions.presence_of_element_located((By.CSS_SELECTOR, css)))


def table_rows(driver, title: str) -> list[list[str]]:
    return driver.execute_script(
        """return [...document.querySelectorAll(`section[data-title^="${arguments[0]}"] tbody tr`)]
             .map((tr) => [...tr.children].map((td) => td.textContent))""",
        title,
    )


PLAYING = """
const done = arguments[arguments.length - 1];
document.getElementById("play").click();
setTimeout(() => done([...document.querySelectorAll("video")].map((v) => ({
  ready: v.readyState, error: v.error && v.error.code, time: v.currentTime,
  frames: v.getVideoPlaybackQuality().totalVideoFrames, paused: v.paused }))), 1500);
"""


def play_videos(driver) -> list[dict]:
    """Press play and say, 1.5 s later, what each video did."""
    wait_for(driver, "#play")
    driver.set_script_timeout(30)
    return driver.execute_async_script(PLAYING)
