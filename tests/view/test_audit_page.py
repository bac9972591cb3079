"""The run viewer's audit page (--arm.audit_at=viewer): in headless Chromium a person labels each trial the audit
drew from the keyboard after its episode plays, while the session still appends to its journal, and the labels land
in audit.jsonl with nothing of the journal lost; the server takes labels from its own page only; and a trial
journalled with the camera's label before a kill keeps it, its audit label coming later, as the report counts it."""

import json
import threading
import time
import urllib.error
import urllib.request

import pytest
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import WebDriverWait

from lerobot_contrast.record.audit_labels import AUDIT_FILE, append_label, read_labels
from lerobot_contrast.record.journal import read_journal
from tests.operators.test_person_page import raw_post
from tests.view.browser import chromium, wait_for
from tests.view.test_browser import page_of  # noqa: F401  (the fixture)

pytestmark = [pytest.mark.xdist_group("view"), pytest.mark.slow]


def draw(journal, indices) -> list[dict]:
    """The journal's lines with the trials `indices` marked drawn for the audit, as an arm session marks them."""
    lines = [json.loads(line) for line in journal.read_text().splitlines()]
    for line in lines:
        if line["index"] in indices:
            line["extra"]["audit_drawn"] = True
    return lines


def write(journal, lines) -> None:
    journal.write_text("".join(json.dumps(line) + "\n" for line in lines))


def post(address: str, body: dict, **headers) -> tuple[int, dict]:
    request = urllib.request.Request(address + "audit/r0", data=json.dumps(body).encode(), method="POST",
                                     headers={"Content-Type": "application/json", **headers})  # fmt: skip
    try:
        with urllib.request.urlopen(request, timeout=10) as answer:
            return answer.status, json.loads(answer.read())
    except urllib.error.HTTPError as error:
        return error.code, json.loads(error.read())


def test_a_person_labels_the_drawn_trials_from_the_keyboard_while_the_session_appends(runs, copy_of, page_of):  # noqa: F811
    run = copy_of(runs["noisy"])
    journal = run / "journal.jsonl"
    summary = json.loads((run / "summary.json").read_text())
    (run / "summary.json").write_text(json.dumps({**summary, "complete": False}))  # a session still running
    done = [line["index"] for line in map(json.loads, journal.read_text().splitlines()) if line["status"] == "done"]
    drawn = done[:2]
    lines = draw(journal, drawn)
    cut = 1 + max(k for k, line in enumerate(lines) if line["index"] in drawn)
    write(journal, lines[:cut])  # journalled so far: the drawn trials and those before them
    rest = lines[cut:]
    address = page_of(run)

    def session():  # the evaluation going on: one journal line every 0.2 s
        for line in rest:
            with journal.open("a") as handle:
                handle.write(json.dumps(line) + "\n")
            time.sleep(0.2)

    with chromium() as driver:
        driver.get(address + "#/audit/r0")
        appending = threading.Thread(target=session)
        appending.start()
        listed = [
            int(li.get_attribute("data-trial"))
            for li in wait_for(driver, "#audit-todo").find_elements(By.TAG_NAME, "li")
        ]
        assert listed == drawn  # what is still to label
        for key in ("s", "f"):
            heading = wait_for(driver, "#audit h3[data-trial]")
            trial = int(heading.get_attribute("data-trial"))
            WebDriverWait(driver, 30).until(lambda d: "ended" in d.find_element(By.ID, "audit-status").text)
            driver.find_element(By.TAG_NAME, "body").send_keys(key)
            WebDriverWait(driver, 20).until(lambda d, t=trial: t in read_labels(run))
        wait_for(driver, "#audit-done")
        appending.join()
    labels = read_labels(run)
    assert [labels[t]["success"] for t in drawn] == [True, False]
    assert all(0 <= labels[t]["seconds"] < 10 for t in drawn)  # from the video's end to the key
    assert len(read_journal(journal)) == len(lines)  # every line the session appended, whole


def test_only_the_viewers_own_page_may_label_and_only_a_drawn_done_trial(runs, copy_of, page_of):  # noqa: F811
    run = copy_of(runs["noisy"])
    journal = run / "journal.jsonl"
    records = [json.loads(line) for line in journal.read_text().splitlines()]
    drawn = next(r["index"] for r in records if r["status"] == "done")
    other = next(r["index"] for r in records if r["index"] != drawn and r["status"] == "done")
    write(journal, draw(journal, [drawn]))
    address = page_of(run)
    port = address.rstrip("/").rsplit(":", 1)[1]
    own = {"Origin": f"http://127.0.0.1:{port}"}
    label = {"trial": drawn, "success": True, "seconds": 2.5}
    assert post(address, label)[0] == 403  # no Origin: not a page of this viewer's
    assert post(address, label, Origin="http://example.org")[0] == 403  # another site's page
    assert post(address, label, Host="attacker.example:80", **own)[0] == 403  # a name rebound to 127.0.0.1
    assert post(address, {"trial": "one"}, **own)[0] == 400
    assert post(address, {**label, "trial": other}, **own) == (409, {"error": f"trial {other} was not drawn for the "
                                                                            "audit; label only those it drew"})  # fmt: skip
    assert post(address, {**label, "trial": 999}, **own)[0] == 404
    assert not (run / AUDIT_FILE).exists()  # nothing written by any of them
    assert post(address, label, **own)[0] == 200
    assert read_labels(run)[drawn]["success"] is True and read_labels(run)[drawn]["seconds"] == 2.5
    for length in ("abc", "-5"):
        assert raw_post(int(port), "/audit/r0", Content_Type="application/json", Content_Length=length, **own) == 400
    journal.write_text(journal.read_text() + json.dumps({**records[0], "index": 999}) + "\n")  # not the next trial
    status, said = post(address, label, **own)
    assert status == 409 and said["error"].startswith("the run's journal cannot be read")


def test_a_label_cut_short_by_a_kill_is_skipped_and_a_later_one_counts(tmp_path):
    append_label(tmp_path, 3, True, 4.0)
    append_label(tmp_path, 5, False, None)
    with (tmp_path / AUDIT_FILE).open("a") as handle:
        handle.write('{"trial": 6, "succ')  # the viewer killed mid-write
    append_label(tmp_path, 3, False, 1.0)  # the person changed their mind
    labels = read_labels(tmp_path)
    assert {t: label["success"] for t, label in labels.items()} == {3: False, 5: False}
