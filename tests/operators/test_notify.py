"""--person.notify=URL: a local HTTP server receives a message for every label a session asks for and one when it
ends or stops, as plain text or as Slack's {"text": ...}; a service that fails is said once and the session goes on."""

import io
import json
import sys
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import httpx
import pytest

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.eval import main
from lerobot_contrast.operators.notify import Notifier
from tests.test_operator_console import CONSOLE, journal


@pytest.fixture
def inbox():
    """A local service that keeps each POST's content type and body."""
    received: list[tuple[str, bytes]] = []

    class Keep(BaseHTTPRequestHandler):
        def do_POST(self):
            received.append((self.headers["Content-Type"], self.rfile.read(int(self.headers["Content-Length"]))))
            self.send_response(200)
            self.send_header("Content-Length", "0")
            self.end_headers()

        def log_message(self, *args):
            return

    server = ThreadingHTTPServer(("127.0.0.1", 0), Keep)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    yield f"http://127.0.0.1:{server.server_address[1]}/notify", received
    server.shutdown()
    server.server_close()


def session(monkeypatch, run, answers, *flags) -> int:
    monkeypatch.setattr(sys, "stdin", io.StringIO("".join(a + "\n" for a in answers)))
    return main([*CONSOLE, f"--output_dir={run}", *flags])


def test_every_label_asked_and_the_sessions_end_reach_the_service_as_text(tmp_path, monkeypatch, inbox):
    url, received = inbox
    assert session(monkeypatch, tmp_path / "run", [""] * 6, f"--person.notify={url}") == 0
    texts = [body.decode() for kind, body in received]
    assert all(kind == "text/plain" for kind, _ in received)
    done = [r for r in journal(tmp_path / "run") if r["status"] == "done"]
    asked = [t for t in texts if t.startswith("lerobot-contrast: a label is asked for trial")]
    assert len(asked) == len(done) >= 1
    assert texts[-1].startswith(f"lerobot-contrast: the session ended: {len(journal(tmp_path / 'run'))} trials in")


def test_a_stop_reaches_the_service_as_slack_json_with_how_to_go_on(tmp_path, monkeypatch, inbox):
    url, received = inbox
    flags = (f"--person.notify={url}", "--person.notify_format=json")
    assert session(monkeypatch, tmp_path / "run", ["", "q"], *flags) == 0  # staged, then stop at the label
    last = json.loads(received[-1][1])
    assert received[-1][0] == "application/json" and set(last) == {"text"}
    assert last["text"].startswith("lerobot-contrast: the session stopped") and "--resume=true" in last["text"]


def test_a_session_that_fails_tells_the_service_how_to_go_on(tmp_path, monkeypatch, inbox):
    from lerobot_contrast.spine import evaluation

    def full(*args, **kwargs):
        raise UserError("no space left on the disk")

    url, received = inbox
    monkeypatch.setattr(evaluation, "run", full)
    assert session(monkeypatch, tmp_path / "run", [], f"--person.notify={url}") == 2  # said as one line, as before
    last = received[-1][1].decode()
    assert last.startswith("lerobot-contrast: the session stopped (no space left on the disk); continue with")
    assert "--resume=true" in last


def test_a_service_that_fails_is_said_once_and_the_session_goes_on(tmp_path, monkeypatch, capsys):
    closed = "http://127.0.0.1:9/notify"  # the discard port: nothing listens
    assert session(monkeypatch, tmp_path / "run", [""] * 6, f"--person.notify={closed}") == 0
    out = capsys.readouterr().out
    assert out.count("a notification to http://127.0.0.1:9/notify failed") == 1
    assert all(r["status"] in ("done", "not_applicable") for r in journal(tmp_path / "run"))


@pytest.mark.parametrize(("url", "form", "said"), [
    ("ntfy.sh/topic", "text", "--person.notify=ntfy.sh/topic: give an http:// or https:// URL"),
    ("http://127.0.0.1/x", "xml", "--person.notify_format: unknown 'xml'; choose from: text, json"),
    ("http://host:abc/", "text", "--person.notify=http://host:abc/: not a URL (Invalid port: 'abc')"),
])  # fmt: skip
def test_a_bad_url_or_format_is_one_line(url, form, said):
    with pytest.raises(UserError, match=said.replace("(", r"\(").replace(")", r"\)")):
        Notifier(url, form, print)


def test_an_interleaved_session_says_it_ended_too(tmp_path, monkeypatch, inbox):
    from tests.test_ab import TWO_ORACLES

    url, received = inbox
    monkeypatch.setattr(sys, "stdin", io.StringIO("\n" * 8))  # per policy and trial: staged, then the scene's label
    flags = ["--n_instances=1", "--seed=5", "--perturbations=SB1", "--max_episode_steps=40", "--operator=console"]
    assert (
        main([*flags, f"--policies={TWO_ORACLES}", f"--output_dir={tmp_path / 'pair'}", f"--person.notify={url}"]) == 0
    )
    texts = [body.decode() for _, body in received]
    assert sum(t.startswith("lerobot-contrast: a label is asked") for t in texts) == 4  # 2 trials x 2 policies
    assert texts[-1].startswith("lerobot-contrast: the interleaved session ended: 4 trials of 2 policies in")


def test_whatever_a_service_raises_is_said_once_and_later_messages_still_go(monkeypatch):
    tried, said = [], []

    def post(client, url, **kwargs):
        tried.append(url)
        raise ValueError("a service that answers nonsense")

    monkeypatch.setattr(httpx.Client, "post", post)
    notifier = Notifier("http://127.0.0.1:9/notify", "text", said.append)
    for trial in range(3):
        notifier.send(prompt="label", trial=trial, instruction="put the red cube in the left bin")
    notifier.close()
    assert len(tried) == 3 and len(said) == 1 and "a service that answers nonsense" in said[0]
