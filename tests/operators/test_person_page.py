"""--person.page: the page answers the console's prompt on screen, unless the terminal answered first or the session
moved on; from another machine only with the session's token (kept in a cookie from the QR link); answers only as
JSON from the page's own origin; and a name rebound to 127.0.0.1 is not served."""

import http.client
import io
import json
import os
import time
import urllib.error
import urllib.request

import pytest

from lerobot_contrast.operators.console import Answers
from lerobot_contrast.operators.person_args import PersonArgs
from lerobot_contrast.operators.person_page import PersonPage, _lan_address
from lerobot_contrast.spine.build import person_channels


class Stream:
    """The terminal: lines a person types."""

    def __init__(self):
        self.read_end, self.write_end = os.pipe()

    def type(self, line: str) -> None:
        os.write(self.write_end, (line + "\n").encode())


@pytest.fixture
def bench(tmp_path):
    stream = Stream()
    answers = Answers(io.TextIOWrapper(io.FileIO(stream.read_end), encoding="utf-8"))
    page = PersonPage(0, True, answers, lambda: tmp_path)
    answers.taken.append(page.answered_elsewhere)
    yield page, answers, stream
    page.close()


def ask(url: str, body: dict | None = None, **headers) -> tuple[int, dict, dict]:
    data = None if body is None else json.dumps(body).encode()
    request = urllib.request.Request(url, data=data, headers=headers, method="GET" if body is None else "POST")
    opener = urllib.request.build_opener(NoRedirect)
    try:
        with opener.open(request, timeout=10) as answer:
            return answer.status, dict(answer.headers), json.loads(answer.read() or b"{}")
    except urllib.error.HTTPError as error:
        return error.code, dict(error.headers), json.loads(error.read() or b"{}")


def raw_post(port: int, path: str, **headers) -> int:
    """A POST with the headers as given (a Content-Length no client library would send); its status."""
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    try:
        connection.putrequest("POST", path)
        for name, value in headers.items():
            connection.putheader(name.replace("_", "-"), value)
        connection.endheaders()
        return connection.getresponse().status
    finally:
        connection.close()


class NoRedirect(urllib.request.HTTPRedirectHandler):
    def redirect_request(self, *args, **kwargs):
        return None


def stage_prompt(page: PersonPage) -> int:
    page.send(
        event="trial", trial=0, of=2, instruction="put the red cube in the left bin", moves={"red_cube": [0.3, 0.18]}
    )
    page.send(prompt="stage", trial=0, of=2, moves={"red_cube": [0.3, 0.18]})
    return page.seq


def test_another_machine_needs_the_token_and_keeps_it_in_a_cookie(bench):
    page, answers, _ = bench
    address = _lan_address()
    if address.startswith("127."):
        pytest.skip("this machine has no network interface besides loopback")
    base = f"http://{address}:{page.port}/"
    seq = stage_prompt(page)
    assert ask(base + "state")[0] == 401  # no token
    assert ask(base + "state", Cookie="lerobot_contrast_token=wrong")[0] == 401
    origin = {"Origin": base.rstrip("/"), "Content-Type": "application/json"}
    assert ask(base + "answer", {"seq": seq, "answer": ""}, **origin)[0] == 401  # nothing changed
    status, headers, _ = ask(base + f"?token={page.token}")
    assert status == 303 and headers["Location"] == "/"
    cookie = headers["Set-Cookie"].split(";")[0]
    assert "HttpOnly" in headers["Set-Cookie"] and "SameSite=Strict" in headers["Set-Cookie"]
    status, _, state = ask(base + "state", Cookie=cookie)
    assert (
        status == 200 and state["prompt"]["prompt"] == "stage" and state["trial"]["moves"] == {"red_cube": [0.3, 0.18]}
    )
    assert ask(base + "answer", {"seq": seq, "answer": ""}, Cookie=cookie, **origin)[0] == 200
    assert answers.next() == ""  # the console's stage prompt got "ready" from the page
    assert json.loads((page.run_dir() / "person_page.json").read_text())["token"] == page.token  # for a resume


def test_the_first_answer_counts_and_a_stale_or_foreign_one_is_refused(bench):
    page, answers, stream = bench
    local = f"http://127.0.0.1:{page.port}/"
    json_from_page = {"Origin": local.rstrip("/"), "Content-Type": "application/json"}
    seq = stage_prompt(page)
    assert ask(local + "answer", {"seq": seq, "answer": "q"}, Origin="http://evil.example",
               **{"Content-Type": "application/json"})[0] == 403  # fmt: skip
    assert ask(local + "answer", {"seq": seq, "answer": "q"}, Origin=local.rstrip("/"))[0] == 415  # a form's post
    assert ask(local + "answer", {"seq": seq - 1, "answer": "q"}, **json_from_page)[0] == 409  # an older prompt
    stream.type("")  # the terminal answers first
    assert answers.next() == ""
    status, _, said = ask(local + "answer", {"seq": seq, "answer": "q"}, **json_from_page)
    assert status == 409 and "answered already" in said["said"]
    page.send(prompt="label", trial=0, instruction="put the red cube in the left bin", subgoals=[])
    assert ask(local + "answer", {"seq": page.seq, "answer": "y"}, **json_from_page)[0] == 200
    assert answers.next() == "y"
    assert ask(local + "state", Host="attacker.example")[0] == 401  # a name rebound to 127.0.0.1, no token


def test_a_page_answer_to_a_prompt_the_terminal_answered_is_refused_even_before_the_page_hears(tmp_path):
    """The terminal's line taken, the page not yet told (answers.taken runs after the line is handed out): the page's
    answer names the prompt it saw, and is refused rather than left to answer the next one."""
    stream = Stream()
    answers = Answers(io.TextIOWrapper(io.FileIO(stream.read_end), encoding="utf-8"))
    shown = answers.served  # the prompt on the page
    stream.type("y")
    assert answers.next() == "y"
    assert not answers.offer("n", served=shown)
    assert answers.offer("n", served=answers.served)  # the next prompt's answer
    assert answers.next() == "n"


def test_keys_reach_the_running_episode_only_while_it_runs(bench):
    page, answers, _ = bench
    local = f"http://127.0.0.1:{page.port}/"
    json_from_page = {"Origin": local.rstrip("/"), "Content-Type": "application/json"}
    stage_prompt(page)
    assert ask(local + "answer", {"seq": page.seq, "answer": "e", "key": True}, **json_from_page)[0] == 409
    page.send(event="running")
    assert ask(local + "answer", {"seq": page.seq, "answer": "e", "key": True}, **json_from_page)[0] == 200
    deadline = time.monotonic() + 5
    while (key := answers.take_key()) is None and time.monotonic() < deadline:
        time.sleep(0.01)
    assert key == "estop"


def test_the_links_token_never_writes_a_header_and_messages_carry_no_token(bench, tmp_path):
    page, _, _ = bench
    local = f"http://127.0.0.1:{page.port}/"
    status, headers, _ = ask(local + "?token=x%0d%0aX-Injected:%201%0d%0a%0d%0a%3Cscript%3E")  # a site's link
    assert status == 303 and "Set-Cookie" not in headers and "X-Injected" not in headers
    status, headers, _ = ask(local + f"?token={page.token}")
    assert status == 303 and headers["Set-Cookie"].startswith(f"lerobot_contrast_token={page.token};")
    assert not page.token_matches("\u00e9t\u00e9") and page.token_matches(page.token)  # any cookie, no traceback
    args = PersonArgs(page=True, port=0, lan=True, notify="http://127.0.0.1:9/notify")
    served, notifier = person_channels(args, Answers(io.StringIO("")), print, lambda: tmp_path, None)
    try:
        assert "token=" in served.link() and "token" not in notifier.link  # a message passes through others' hands
    finally:
        served.close()
        notifier.close()


def test_an_emergency_stop_goes_before_a_line_the_terminal_left_waiting(bench):
    page, answers, stream = bench
    local = f"http://127.0.0.1:{page.port}/"
    json_from_page = {"Origin": local.rstrip("/"), "Content-Type": "application/json"}
    page.send(event="running")
    stream.type("")  # a stray Enter at the terminal while the episode runs
    deadline = time.monotonic() + 5
    while not answers._lines and time.monotonic() < deadline:  # the terminal's line has reached the queue
        time.sleep(0.01)
    assert ask(local + "answer", {"seq": page.seq, "answer": "e", "key": True}, **json_from_page)[0] == 200
    assert answers.take_key() == "estop"
    assert answers.next() == ""  # the terminal's line, for the prompt after the trial


def test_an_aborted_trial_after_the_episode_is_answered_as_a_prompt(bench):
    page, answers, _ = bench
    local = f"http://127.0.0.1:{page.port}/"
    json_from_page = {"Origin": local.rstrip("/"), "Content-Type": "application/json"}
    page.send(event="running")
    page.send(prompt="aborted", trial=0, reason="the robot was stopped")
    state = page.snapshot()
    assert not state["running"] and state["prompt"]["prompt"] == "aborted"
    assert ask(local + "answer", {"seq": page.seq, "answer": "s", "key": True}, **json_from_page)[0] == 409
    assert ask(local + "answer", {"seq": page.seq, "answer": ""}, **json_from_page)[0] == 200
    assert answers.next() == ""
    page.send(event="running")
    page.send(event="ended", trial=0)  # the arm's episode ended: its keys are gone from the page
    assert not page.snapshot()["running"]


@pytest.mark.parametrize("length", ["abc", "-5", "99999"])
def test_a_body_of_a_bad_length_is_refused(bench, length):
    page, _, _ = bench
    origin = f"http://127.0.0.1:{page.port}"
    assert raw_post(page.port, "/answer", Origin=origin, Content_Type="application/json", Content_Length=length) == 400
