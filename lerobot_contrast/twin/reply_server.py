"""A ZMQ REP socket on 127.0.0.1 answering one JSON object per request on a thread of its own: what the twin's
placement and clock sockets share. Every reply has "ok", and "error" with one line when "ok" is false."""

from __future__ import annotations

import json
import math
import threading
from abc import ABC, abstractmethod
from typing import Any

import zmq

from lerobot_contrast.contrast.errors import UserError

HOST = "127.0.0.1"
POLL_MS = 100  # how often the serving thread looks up to see whether it should stop


class RequestError(ValueError):
    """A request the twin cannot carry out; its message is the reply's one-line error."""


class ReplyServer(ABC):
    """Answers requests with `handle(request)` on `port`; `what` and `flag` name the socket in a bind error."""

    what, flag = "port", "--port"

    def __init__(self, port: int) -> None:
        self.port = port
        self.address = f"tcp://{HOST}:{port}"
        self._context = zmq.Context()
        self._socket = self._context.socket(zmq.REP)
        self._socket.setsockopt(zmq.LINGER, 0)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._closing = False  # set by a handler: the reply is the socket's last

    @abstractmethod
    def handle(self, request: dict[str, Any]) -> dict[str, Any]:
        """The reply's fields for one request (the placement's commands, the clock's); a RequestError refuses it."""

    def start(self) -> str:
        """Bind (a port in use is one line saying so) and serve on a daemon thread; returns the address."""
        try:
            self._socket.bind(self.address)
        except zmq.ZMQError as error:
            self._socket.close()
            self._context.term()
            raise UserError(
                f"{self.what} {self.port} on {HOST}: {error.strerror}; choose a free one with {self.flag}"
            ) from None
        self._thread = threading.Thread(target=self._serve, name=f"twin {self.what}", daemon=True)
        self._thread.start()
        return self.address

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None
        self._socket.close()
        self._context.term()

    def _serve(self) -> None:
        while not self._stop.is_set():
            if not self._socket.poll(POLL_MS):
                continue
            self._socket.send_string(json.dumps(self.answer(self._socket.recv())))
            if self._closing:  # after the reply: from now on the port answers nobody
                self._socket.close()
                return

    def answer(self, message: bytes) -> dict[str, Any]:
        """The reply to one request, as sent back."""
        try:
            request = json.loads(message)
            if not isinstance(request, dict):
                raise ValueError
        except ValueError:
            return error_reply('malformed request: send one JSON object, e.g. {"cmd": "scene"}')
        try:
            return {"ok": True, **self.handle(request)}
        except RequestError as error:
            return error_reply(str(error))
        except Exception as error:  # the socket must keep answering: a dead thread would leave the client waiting
            return error_reply(f"{request.get('cmd')} failed in the twin: {' '.join(str(error).split())[:200]}")


def number(request: dict[str, Any], key: str) -> float:
    """`request[key]` as a finite number, or a RequestError naming it."""
    value = request.get(key)
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise RequestError(f"{request.get('cmd')}: {key!r} must be a finite number, got {value!r}")
    return float(value)


def error_reply(message: str) -> dict[str, Any]:
    return {"ok": False, "error": message}
