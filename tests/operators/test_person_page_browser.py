"""The person's page on a phone's screen (headless Chromium): a session answered from it (ready, a label taken back
with undo and given again, a stop, and the resume, which the open page reconnects to by itself, to the session's
end); and the arm's call for a person, why and where each object goes, answered "fixed"."""

import io
import os
import socket
import subprocess
import sys
import threading
import time

import pytest
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import WebDriverWait

from lerobot_contrast.operators.console import Answers
from lerobot_contrast.operators.person_page import PersonPage
from tests.test_operator_console import CONSOLE, journal
from tests.view.browser import chromium

pytestmark = [pytest.mark.xdist_group("view"), pytest.mark.slow]


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def console_session(run, port: int, *flags: str) -> list[str]:
    return [sys.executable, "-m", "lerobot_contrast.eval", *CONSOLE, f"--output_dir={run}", "--rerun=false",
            "--person.page=true", f"--person.port={port}", *flags]  # fmt: skip


class Session:
    """The session, its terminal left unanswered (a pipe nobody writes to): every answer comes from the page. Its
    output is read as it comes (a full pipe would stall it)."""

    def __init__(self, command: list[str]) -> None:
        self.process = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                        stderr=subprocess.STDOUT, text=True)  # fmt: skip
        self.lines: list[str] = []
        self.reader = threading.Thread(target=lambda: self.lines.extend(iter(self.process.stdout.readline, "")))
        self.reader.start()
        deadline = time.monotonic() + 120
        while not any(line.startswith("the person's page:") for line in self.lines):
            assert time.monotonic() < deadline and self.process.poll() is None, "".join(self.lines)[-2000:]
            time.sleep(0.1)

    def end(self) -> tuple[int, str]:
        code = self.process.wait(timeout=120)
        self.reader.join(10)
        return code, "".join(self.lines)


def press(driver, prompt: str, answer: str, timeout: float = 120) -> None:
    """Wait for `prompt` on the page, then press its button for `answer`."""
    WebDriverWait(driver, timeout).until(
        lambda d: d.find_element(By.ID, "prompt").get_attribute("data-prompt") == prompt
    )
    driver.find_element(By.CSS_SELECTOR, f'#prompt button[data-answer="{answer}"]').click()


def test_a_session_answered_from_a_phone_with_an_undo_a_stop_and_the_resume(tmp_path):
    run, port = tmp_path / "run", free_port()
    session = Session(console_session(run, port))
    with chromium(phone=True) as driver:
        try:
            driver.get(f"http://127.0.0.1:{port}/")
            press(driver, "stage", "")
            assert driver.find_elements(By.CSS_SELECTOR, "#trial li[data-move]")  # what to move where
            press(driver, "label", "y")
            driver.find_element(By.ID, "undo").click()  # taken back within its 5 s
            assert "taken back" in driver.find_element(By.ID, "status").text
            press(driver, "label", "n")  # sent after 5 s
            press(driver, "stage", "q", timeout=30)  # the next trial: stop the session
            code, out = session.end()
            assert code == 0 and "stopped:" in out
            labelled = [r for r in journal(run) if r["status"] == "done"]
            assert len(labelled) == 1 and labelled[0]["success"] is False  # the label given again, not the undone one
            assert "the session stopped" in driver.find_element(By.ID, "ended").text  # seen before its server closed
            WebDriverWait(driver, 20).until(lambda d: "reconnecting" in d.find_element(By.ID, "status").text)
            session = Session(console_session(run, port, "--resume=true"))
            ended = lambda d: "the session ended" in d.find_element(By.ID, "ended").text  # noqa: E731
            for _ in range(5):  # each trial left: staged, then labelled a success
                WebDriverWait(driver, 120).until(lambda d: d.find_element(By.ID, "prompt").get_attribute("data-prompt")
                                                 in ("stage", "label") or ended(d))  # fmt: skip
                if ended(driver):
                    break
                prompt = driver.find_element(By.ID, "prompt").get_attribute("data-prompt")
                press(driver, prompt, "" if prompt == "stage" else "y")
                time.sleep(0.5 if prompt == "stage" else 6)  # a label is sent 5 s after its button
            WebDriverWait(driver, 60).until(ended)
            code, out = session.end()
            assert code == 0, out[-2000:]
        finally:
            session.process.kill()
    records = journal(run)
    assert all(r["status"] in ("done", "not_applicable") for r in records) and records[0]["success"] is False


def test_the_arms_call_for_a_person_shows_why_and_where_and_fixed_answers_it(tmp_path):
    read_end, _ = os.pipe()  # the terminal, unanswered
    answers = Answers(io.TextIOWrapper(io.FileIO(read_end), encoding="utf-8"))
    page = PersonPage(0, False, answers, lambda: tmp_path)
    answers.taken.append(page.answered_elsewhere)
    try:
        page.send(event="trial", trial=4, of=9, instruction="put the red cube next to the green cube", moves={})
        page.said_line("[bold]the arm could not stage it[/]: red_cube out of reach")
        page.send(
            prompt="call", trial=4, trouble="red_cube: out of reach", fix={"red_cube": [0.3, 0.05], "yellow_cube": None}
        )
        with chromium(phone=True) as driver:
            driver.get(f"http://127.0.0.1:{page.port}/")
            WebDriverWait(driver, 30).until(
                lambda d: d.find_element(By.ID, "prompt").get_attribute("data-prompt") == "call"
            )
            shown = driver.find_element(By.ID, "prompt").text
            assert "A person is needed: red_cube: out of reach" in shown
            assert "put red_cube at (0.300, 0.050) m" in shown and "put yellow_cube off the workspace" in shown
            assert "the arm could not stage it: red_cube out of reach" in driver.find_element(By.ID, "said").text
            driver.find_element(By.CSS_SELECTOR, '#prompt button[data-answer=""]').click()
            assert answers.next() == ""  # the arm's call answered: fixed
    finally:
        page.close()
