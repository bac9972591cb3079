"""A person can take over from the twin's scripted person at any prompt: what they type goes to the console, and
the scripted person answers no more."""

import io
import json
import os
import selectors
from types import SimpleNamespace

from lerobot_contrast.twin.console_session import TAKEN_OVER, Lines, Session


class Scripted:
    def __init__(self):
        self.said, self.seen = [], []

    def handle(self, message):
        self.seen.append(message)
        return ""


def session() -> tuple[Session, Scripted, int, int]:
    scripted = Scripted()
    channel_read, channel_write = os.pipe()
    typing_read, typing_write = os.pipe()
    s = Session.__new__(Session)  # the eval child's ends, without an eval child
    s.answerer, s.person, s.errors = scripted, False, ()
    s.channel, s.typing = Lines(channel_read), Lines(typing_read)
    s.child = SimpleNamespace(stdin=io.BytesIO())
    s.child.stdin.flush = lambda: None
    return s, scripted, channel_write, typing_write


def prompt(fd: int, **message) -> None:
    os.write(fd, (json.dumps({"version": 1, **message}) + "\n").encode())


def test_the_scripted_person_answers_until_a_person_types(capsys):
    s, scripted, channel, typing = session()
    selector = selectors.DefaultSelector()
    prompt(channel, prompt="check", off={}, tolerance=0.02)
    s._answer(selector)
    assert s.child.stdin.getvalue() == b"\n" and len(scripted.seen) == 1
    os.write(typing, b"q\n")  # a person at the terminal
    s._forward(selector)
    assert s.person and s.child.stdin.getvalue() == b"\nq\n"
    prompt(channel, prompt="label", trial=0, instruction="x", subgoals=[])
    s._answer(selector)
    assert len(scripted.seen) == 1 and s.child.stdin.getvalue() == b"\nq\n"  # the script stays silent
    assert TAKEN_OVER in capsys.readouterr().out
