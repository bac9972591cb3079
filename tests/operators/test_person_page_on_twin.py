"""On the twin, the arm's session answered from the person's page on a phone's screen (headless Chromium): its call
for a person (a cube it cannot see, put back by hand while the page shows the camera's frame with the targets), the
labels it asks for (the audit's, one taken back with undo and given again), a stop, and the resume, which the open
page reconnects to by itself."""

import json
import urllib.request

import pytest
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import WebDriverWait

from lerobot_contrast.twin.launch import running_twin
from lerobot_contrast.twin.placement_client import PlacementClient
from lerobot_contrast.twin.table_calibration import calibrate_table
from tests.operators.test_arm_on_twin import eval_command
from tests.operators.test_person_page_browser import Session, free_port, press
from tests.test_operator_console import journal
from tests.twin.test_eval_on_twin import save_so101_act
from tests.view.browser import chromium

pytestmark = [pytest.mark.xdist_group("view"), pytest.mark.slow]

AUDIT_ALL = "--arm.audit=1"  # every trial drawn for the audit: a person labels each, live, beside the camera


def prompt_of(driver) -> str:
    return driver.find_element(By.ID, "prompt").get_attribute("data-prompt")


def test_the_arms_call_and_labels_answered_on_a_phone_with_an_undo_a_stop_and_the_resume(tmp_path):
    with running_twin("--task=so101_blocks", "--clock=sim") as twin:
        table = calibrate_table(twin, "so101_blocks", tmp_path / "table.calibration.json")
        placement = PlacementClient(twin.placement)
        placement.place("red_cube", 0.08, 0.22)  # beside the arm's base, off the workspace: not seen there
        policy, run, port = save_so101_act(tmp_path / "act"), tmp_path / "run", free_port()
        flags = ("--arm.measure_joints=false", AUDIT_ALL, "--person.page=true", f"--person.port={port}")
        session = Session(eval_command(twin, table, run, policy, *flags))
        with chromium(phone=True) as driver:
            try:
                driver.get(f"http://127.0.0.1:{port}/")
                WebDriverWait(driver, 300).until(lambda d: prompt_of(d) == "call")
                assert "A person is needed: red_cube: not seen" in driver.find_element(By.ID, "prompt").text
                state = json.loads(urllib.request.urlopen(f"http://127.0.0.1:{port}/state", timeout=10).read())
                assert state["picture"] is not None  # the camera's frame with where each object goes
                WebDriverWait(driver, 10).until(lambda d: d.execute_script(
                    "const p = document.getElementById('picture'); return !p.hidden && p.naturalWidth > 0"))  # fmt: skip
                placement.place("red_cube", *state["prompt"]["fix"]["red_cube"])  # the person's hands
                press(driver, "call", "")  # fixed
                press(driver, "label", "y", timeout=300)
                driver.find_element(By.ID, "undo").click()
                press(driver, "label", "n")  # sent 5 s later
                WebDriverWait(driver, 300).until(lambda d: prompt_of(d) in ("call", "label") and d.find_elements(
                    By.CSS_SELECTOR, '#prompt button[data-answer="q"]'))  # fmt: skip
                driver.find_element(By.CSS_SELECTOR, '#prompt button[data-answer="q"]').click()
                code, out = session.end()
                assert code == 0 and "stopped:" in out, out[-2000:]
                first = journal(run)[0]
                assert first["status"] == "done" and first["extra"]["audit"] is False  # the label given again
                assert first["extra"]["interventions"] >= 1  # the call, counted
                session = Session(eval_command(twin, table, run, policy, *flags, "--resume=true"))
                ended = lambda d: "the session ended" in d.find_element(By.ID, "ended").text  # noqa: E731
                while not ended(driver):
                    WebDriverWait(driver, 300).until(lambda d: prompt_of(d) in ("call", "label") or ended(d))
                    if prompt_of(driver) == "label":
                        press(driver, "label", "y")
                        WebDriverWait(driver, 30).until(lambda d: "sent" in d.find_element(By.ID, "status").text)
                    elif prompt_of(driver) == "call":
                        press(driver, "call", "")
                code, out = session.end()
                assert code == 0, out[-2000:]
            except Exception:
                print("".join(session.lines)[-4000:])  # the session's terminal, shown with the failure
                raise
            finally:
                session.process.kill()
    assert all(r["status"] in ("done", "not_applicable") for r in journal(run))
