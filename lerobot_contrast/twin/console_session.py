"""Run `python -m lerobot_contrast.eval ... --operator=console` as a child and answer its console from its structured
channel (operators/channel.py), echoing what it prints; a person typing at this terminal takes over the answers."""

from __future__ import annotations

import os
import selectors
import stat
import subprocess
import sys
from collections.abc import Sequence
from typing import IO, Any, Protocol

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.operators import channel

TAKEN_OVER = "a person took over: what they type goes to the console, and the scripted person answers no more"


class Answerer(Protocol):
    said: list[str]

    def handle(self, message: dict) -> str | None: ...


class Lines:
    """Whole lines read from a file descriptor without blocking on partial ones."""

    def __init__(self, fd: int) -> None:
        self.fd, self.pending, self.closed = fd, b"", False

    def read(self) -> list[str]:
        chunk = os.read(self.fd, 65536)
        if not chunk:
            self.closed = True
            lines, self.pending = ([self.pending] if self.pending else []), b""
        else:
            *lines, self.pending = (self.pending + chunk).split(b"\n")
        return [line.decode("utf-8", "replace") for line in lines]


def person_present(stream: IO[str]) -> bool:
    """Whether a person may type on `stream`: a terminal or a pipe (not /dev/null, not a file of answers)."""
    try:
        mode = os.fstat(stream.fileno()).st_mode
    except (OSError, ValueError):
        return False
    return stream.isatty() or stat.S_ISFIFO(mode)


class Session:
    """One eval child answered by `answerer`; `errors`: the exceptions after which the session is stopped with
    "q" (the run stays resumable) and re-raised."""

    def __init__(self, eval_argv: Sequence[str], answerer: Answerer, errors: tuple[type[Exception], ...]) -> None:
        self.answerer, self.errors = answerer, (*errors, UserError)
        self.person = False
        read_end, self.write_end = os.pipe()
        self.channel = Lines(read_end)
        # Wide lines keep the console's tables on one line each; unbuffered output shows each prompt when printed.
        env = {**os.environ, "COLUMNS": "200", "PYTHONUNBUFFERED": "1"}
        # The console by default; with --operator=arm the arm stages and the console is what it calls a person with.
        chosen = [] if any(arg.startswith("--operator=") for arg in eval_argv) else ["--operator=console"]
        command = [sys.executable, "-m", "lerobot_contrast.eval", *eval_argv, *chosen,
                   f"--operator_channel=/dev/fd/{self.write_end}"]  # fmt: skip
        self.child = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                      env=env, pass_fds=(self.write_end,))  # fmt: skip
        os.close(self.write_end)  # the child holds it: its exit closes the channel
        self.output = Lines(self.child.stdout.fileno())

    def run(self) -> int:
        """Answer until the child exits; returns its exit code."""
        selector = selectors.DefaultSelector()
        selector.register(self.output.fd, selectors.EVENT_READ, self._echo)
        selector.register(self.channel.fd, selectors.EVENT_READ, self._answer)
        self.typing = Lines(sys.stdin.fileno()) if person_present(sys.stdin) else None
        if self.typing is not None:
            selector.register(sys.stdin.fileno(), selectors.EVENT_READ, self._forward)
        try:
            while not self.output.closed:
                ready = [key.data for key, _ in selector.select()]
                # The console prints each prompt before sending it: echo first, so the log reads in order.
                for handler in sorted(ready, key=lambda h: h != self._echo):
                    handler(selector)
        except self.errors:
            self._type("q")  # stop the session where it is: the run stays resumable
            self.child.stdin.close()
            self.child.wait()
            raise
        except KeyboardInterrupt:
            pass
        finally:
            selector.close()
            os.close(self.channel.fd)
        return self.child.wait()

    def _echo(self, selector: selectors.BaseSelector) -> None:
        for line in self.output.read():
            print(line, flush=True)
        if self.output.closed:
            selector.unregister(self.output.fd)

    def _answer(self, selector: selectors.BaseSelector) -> None:
        for line in self.channel.read():
            message = channel.parse(line)
            if message is None or self.person:
                continue
            typed = self.answerer.handle(message)
            self._report()
            if typed is not None:
                print(f"[operator] {typed or 'Enter'}", flush=True)
                self._type(typed)
        if self.channel.closed:
            selector.unregister(self.channel.fd)

    def _forward(self, selector: selectors.BaseSelector) -> None:
        lines = self.typing.read()
        if self.typing.closed:
            selector.unregister(self.typing.fd)
        if lines and not self.person:
            self.person = True
            print(f"[operator] {TAKEN_OVER}", flush=True)
        for line in lines:
            self._type(line)

    def _report(self) -> None:
        for said in self.answerer.said:
            print(f"[operator] {said}", flush=True)
        self.answerer.said.clear()

    def _type(self, line: str) -> None:
        try:
            self.child.stdin.write(f"{line}\n".encode())
            self.child.stdin.flush()
        except (BrokenPipeError, ValueError):  # the console already ended
            return


def run_answered(eval_argv: Sequence[str], answerer: Any, errors: tuple[type[Exception], ...] = ()) -> int:
    """Run the eval with its console answered by `answerer`; returns its exit code."""
    return Session(eval_argv, answerer, errors).run()
