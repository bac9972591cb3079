"""The person's page (`--person.page=true`), served as the viewer's pages are (the standard library's HTTP server): a
page for a phone that shows what the console shows (each trial, what to move where, why a person is called, what was
said) and answers its prompts with buttons. It is a console channel (operators/channel.py's messages come in through
`send`) and a second source of the console's answers: an answer counts only for the prompt on screen and only while
the terminal has not answered it (whichever answers first wins; the other is told).

Who may use it: by default the server listens on 127.0.0.1 only and answers requests that name it as their Host (a
web page whose name is rebound to 127.0.0.1 does not). With `--person.lan=true` it listens on every interface, and a
request from another machine needs the session's token: the link printed with its QR code carries it once, and the
page keeps it in a cookie (HttpOnly, SameSite=Strict); without it, 401 and nothing changes. Every answer must be JSON
from the page's own origin (a form or a script on another site cannot send one). The page loads nothing from
elsewhere. The token is kept in the run directory (person_page.json), so a resumed run takes the same link."""

from __future__ import annotations

import collections
import errno
import hmac
import ipaddress
import json
import re
import secrets
import socket
import threading
import time
from collections.abc import Callable
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlsplit

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.operators.console import Answers

PAGE = Path(__file__).with_name("person_page.html")
TOKEN_FILE = "person_page.json"
COOKIE = "lerobot_contrast_token"
SAID_LINES = 8  # the console's last lines the page shows
MARKUP = re.compile(r"\[/?[a-z ]*\]")  # rich's markup in what the console says
MAX_BODY = 1024
CLOSE_WAIT_S = 3.0  # at the session's end, time for an open page (it asks every second) to see it ended


class PersonPage:
    """The page's server and what it shows. `answers`: the console's, which the page's answers join where the prompt
    they answer is still open (Answers.offer: the terminal may have answered first); `run_dir`: where the token is
    kept once the run has one; `picture`: the calibrated camera's last overlay (its count, JPEG bytes), where there
    is one."""

    def __init__(
        self,
        port: int,
        lan: bool,
        answers: Answers,
        run_dir: Callable[[], Path | None],
        picture: Callable[[], tuple[int, bytes] | None] = lambda: None,
    ) -> None:
        self.answers, self.run_dir, self.lan, self.picture = answers, run_dir, lan, picture
        self.prompt_served = 0  # the console's answers handed out when the prompt on screen was shown
        self.token = _kept_token(run_dir()) or secrets.token_urlsafe(18)
        self._lock = threading.Lock()
        self.seq = 0  # changes with every prompt and event the console sends: what an answer names
        self.version = 0  # changes with anything shown, what the console said included
        self.started = secrets.token_hex(4)  # this server's: a resumed session's page starts its counts again
        self._served: int | None = None  # the version a page last fetched (None: no page has looked)
        self.state: dict[str, Any] = {"prompt": None, "trial": None, "running": False, "ended": None}
        self.said: collections.deque[str] = collections.deque(maxlen=SAID_LINES)
        self.answered = True  # the prompt on screen has had its answer (or there is none)
        handler = type("PersonHandler", (_Handler,), {"page": self})
        try:
            self.server = ThreadingHTTPServer(("0.0.0.0" if lan else "127.0.0.1", port), handler)
        except OSError as error:
            if error.errno == errno.EADDRINUSE:
                raise UserError(
                    f"--person.port={port}: another program listens there; pass another --person.port"
                ) from None
            raise UserError(f"--person.port={port}: cannot listen there ({error.strerror})") from None
        self.server.daemon_threads = True
        self.port = self.server.server_address[1]
        threading.Thread(target=self.server.serve_forever, daemon=True, name="person-page").start()

    def link(self, token: bool = True) -> str:
        """The page's address: on the LAN with its token (for the QR code; `token=False` for a message sent through
        somebody else's service, which a phone that scanned the code opens with its cookie), else this machine's."""
        if not self.lan:
            return f"http://127.0.0.1:{self.port}/"
        return f"http://{_lan_address()}:{self.port}/" + (f"?token={self.token}" if token else "")

    # --- a console channel ---
    def send(self, **message: Any) -> None:
        with self._lock:
            self.seq += 1
            self.version += 1
            if "prompt" in message:  # every prompt (an aborted trial's too) comes after the episode's keys
                self.state.update(prompt=message, running=False)
                self.answered, self.prompt_served = False, self.answers.served
            elif message.get("event") == "trial":
                self.state.update(trial=message, prompt=None, running=False)
                self.answered = True
                self._keep_token()
            elif message.get("event") == "running":
                self.state.update(prompt=None, running=True)
                self.answered = True
            elif message.get("event") == "ended":  # the episode's end, said before the arm looks and labels
                self.state["running"] = False
            elif message.get("event") == "session":
                self.state.update(prompt=None, running=False, ended=message["text"])
                self.answered = True

    def said_line(self, text: str) -> None:
        with self._lock:
            self.said.append(MARKUP.sub("", text).replace("\a", "").strip())
            self.version += 1

    def answered_elsewhere(self) -> None:
        """The terminal's answer was taken: the prompt on screen is no longer open."""
        with self._lock:
            self.answered = True
            self.seq += 1
            self.version += 1

    def close(self) -> None:
        """Stop serving, once an open page has seen the last state (the session's end), or after CLOSE_WAIT_S."""
        deadline = time.monotonic() + CLOSE_WAIT_S
        while self._served is not None and self._served < self.version and time.monotonic() < deadline:
            time.sleep(0.05)
        self.server.shutdown()
        self.server.server_close()

    # --- what the handler asks ---
    def snapshot(self) -> dict[str, Any]:
        with self._lock:
            self._served = self.version
            open_prompt = None if self.answered else self.state["prompt"]
            picture = self.picture()
            shown = f"{self.started}.{self.version}.{0 if picture is None else picture[0]}"
            return {"seq": self.seq, "version": shown, "picture": None if picture is None else picture[0],
                    "prompt": open_prompt, "trial": self.state["trial"], "running": self.state["running"],
                    "ended": self.state["ended"], "said": list(self.said)}  # fmt: skip

    def take(self, seq: int, line: str, key: bool) -> tuple[HTTPStatus, str]:
        """An answer from the page for the prompt it showed at `seq` (`key`: an in-trial key, taken while running)."""
        with self._lock:
            if key:
                if not self.state["running"]:
                    return HTTPStatus.CONFLICT, "no episode is running now"
            elif self.answered or self.state["prompt"] is None:
                return HTTPStatus.CONFLICT, "that was answered already (at the terminal, or on another page)"
            elif seq != self.seq:
                return HTTPStatus.CONFLICT, "the session has moved on since: look again"
            if not self.answers.offer(line, key, None if key else self.prompt_served):
                return HTTPStatus.CONFLICT, "the terminal answered first"
            if not key:
                self.answered = True
                self.seq += 1
                self.version += 1
            return HTTPStatus.OK, "taken"

    def allowed(self, client: str, host: str, cookie: str, query_token: str | None) -> bool:
        """Whether a request may see or change anything: this machine naming the page as its host, or the token."""
        local = {f"127.0.0.1:{self.port}", f"localhost:{self.port}"}
        if ipaddress.ip_address(client).is_loopback and host in local:
            return True
        return self.lan and self.token_matches(query_token or _cookie_token(cookie))

    def token_matches(self, given: str | None) -> bool:
        return given is not None and hmac.compare_digest(given.encode("utf-8", "replace"), self.token.encode())

    def _keep_token(self) -> None:
        run_dir = self.run_dir()
        if run_dir is None or not Path(run_dir).is_dir() or (Path(run_dir) / TOKEN_FILE).is_file():
            return
        path = Path(run_dir) / TOKEN_FILE
        path.touch(mode=0o600)
        path.write_text(json.dumps({"token": self.token}) + "\n", encoding="utf-8")


def _kept_token(run_dir: Path | None) -> str | None:
    path = None if run_dir is None else Path(run_dir) / TOKEN_FILE
    try:
        return json.loads(path.read_text(encoding="utf-8"))["token"] if path is not None and path.is_file() else None
    except (OSError, json.JSONDecodeError, KeyError, TypeError):
        return None


def _cookie_token(cookie: str) -> str | None:
    for part in cookie.split(";"):
        name, _, value = part.strip().partition("=")
        if name == COOKIE:
            return value
    return None


def _lan_address() -> str:
    """This machine's address on its local network (the interface its default route leaves by)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(("10.255.255.255", 1))  # no packet is sent: this only picks the interface
            return probe.getsockname()[0]
        except OSError:
            return "127.0.0.1"


class _Handler(BaseHTTPRequestHandler):
    page: PersonPage

    def log_message(self, format: str, *args) -> None:
        return

    def _allowed(self) -> bool:
        query = parse_qs(urlsplit(self.path).query).get("token", [None])[0]
        if self.page.allowed(
            self.client_address[0], self.headers.get("Host", ""), self.headers.get("Cookie", ""), query
        ):
            return True
        self._reply(HTTPStatus.UNAUTHORIZED, {"error": "open the page with the link the terminal printed (its token)"})
        return False

    def do_GET(self) -> None:
        if not self._allowed():
            return
        path, query = urlsplit(self.path).path, parse_qs(urlsplit(self.path).query)
        if path == "/" and "token" in query:  # the QR link: keep the token in a cookie, and drop it from the address
            self.send_response(HTTPStatus.SEE_OTHER)
            if self.page.token_matches(query["token"][0]):  # the page's own token only: nothing of the query's
                self.send_header("Set-Cookie", f"{COOKIE}={self.page.token}; HttpOnly; SameSite=Strict; Path=/")
            self.send_header("Location", "/")
            self.send_header("Content-Length", "0")
            return self.end_headers()
        if path == "/":
            return self._send(HTTPStatus.OK, PAGE.read_bytes(), "text/html; charset=utf-8")
        if path == "/state":
            return self._reply(HTTPStatus.OK, self.page.snapshot())
        if path == "/picture.jpg" and (picture := self.page.picture()) is not None:
            return self._send(HTTPStatus.OK, picture[1], "image/jpeg")
        return self._reply(HTTPStatus.NOT_FOUND, {"error": "no such page"})

    def do_POST(self) -> None:
        if not self._allowed():
            return
        if urlsplit(self.path).path != "/answer":
            return self._reply(HTTPStatus.NOT_FOUND, {"error": "no such page"})
        host = self.headers.get("Host", "")
        if self.headers.get("Origin", "") != f"http://{host}":
            return self._reply(HTTPStatus.FORBIDDEN, {"error": "answers are taken from the page itself only"})
        if self.headers.get("Content-Type", "").split(";")[0].strip() != "application/json":
            return self._reply(HTTPStatus.UNSUPPORTED_MEDIA_TYPE, {"error": "send the answer as JSON"})
        try:
            length = int(self.headers.get("Content-Length") or 0)
            if not 0 < length <= MAX_BODY:
                raise ValueError
            said = json.loads(self.rfile.read(length))
            seq, line, key = said["seq"], said["answer"], bool(said.get("key", False))
            if not isinstance(seq, int) or not isinstance(line, str) or len(line) > 40:
                raise ValueError
        except (ValueError, KeyError, TypeError):
            return self._reply(HTTPStatus.BAD_REQUEST, {"error": 'give {"seq": N, "answer": "..."}'})
        status, why = self.page.take(seq, line, key)
        return self._reply(status, {"ok": status == HTTPStatus.OK, "said": why})

    def _reply(self, status: HTTPStatus, data: dict) -> None:
        self._send(status, json.dumps(data).encode("utf-8"), "application/json")

    def _send(self, status: HTTPStatus, body: bytes, kind: str) -> None:
        self.send_response(status)
        self.send_header("Content-Type", kind)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Frame-Options", "DENY")
        self.end_headers()
        self.wfile.write(body)
