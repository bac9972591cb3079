"""The page on 127.0.0.1: the static files, the runs' document (rebuilt when a run's files change) and each
episode's signals as scripts, the dataset's videos with byte ranges (a browser seeks with them), and the audit
page's labels (audit_post.py)."""

from __future__ import annotations

import contextlib
import errno
import json
import re
import shutil
from http import HTTPStatus
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from urllib.parse import unquote, urlsplit

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.view.audit_post import MAX_BODY, Refused, check_sender, take_label
from lerobot_contrast.view.payload import Pages
from lerobot_contrast.view.static_files import STATIC, script

HOST = "127.0.0.1"
EPISODE = re.compile(r"/data/episodes/(r\d+)/(\d+)\.js")
VIDEO = re.compile(r"/videos/(r\d+)/(.+\.mp4)")
RANGE = re.compile(r"bytes=(\d*)-(\d*)")
AUDIT = re.compile(r"/audit/(r\d+)")


class ViewServerError(UserError):
    pass


class Handler(SimpleHTTPRequestHandler):
    pages: Pages  # set on the class `serve` makes

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, directory=str(STATIC), **kwargs)

    def log_message(self, format: str, *args) -> None:  # a quiet server: the terminal shows the URL only
        return

    def end_headers(self) -> None:
        self.send_header("Cache-Control", "no-store")
        super().end_headers()

    def do_GET(self) -> None:
        path = unquote(urlsplit(self.path).path)
        if path == "/data/runs.js":
            return self._text(script("viewData", self.pages.current()), "text/javascript")
        if match := EPISODE.fullmatch(path):
            return self._episode(match.group(1), int(match.group(2)))
        if match := VIDEO.fullmatch(path):
            return self._video(match.group(1), match.group(2))
        if path.startswith(("/data/", "/videos/")):
            return self.send_error(HTTPStatus.NOT_FOUND)
        if path == "/" or path.startswith("/static/"):  # the package's static/ folder, served as the bundle lays it out
            self.path = "/index.html" if path == "/" else path.removeprefix("/static")
            return super().do_GET()
        return self.send_error(HTTPStatus.NOT_FOUND)

    def do_POST(self) -> None:
        match = AUDIT.fullmatch(unquote(urlsplit(self.path).path))
        if match is None:
            return self.send_error(HTTPStatus.NOT_FOUND)
        try:
            check_sender(self.headers, self.server.server_address[1])
            run_dir = self.pages.run_dir(match.group(1))
            if run_dir is None:
                raise Refused(HTTPStatus.NOT_FOUND, f"no run {match.group(1)} on this page")
            length = self.headers.get("Content-Length") or "0"
            if not (length.isdigit() and 0 < int(length) <= MAX_BODY):
                raise Refused(HTTPStatus.BAD_REQUEST, f"a label is one short JSON object (at most {MAX_BODY} bytes)")
            kept = take_label(run_dir, self.rfile.read(int(length)))
        except Refused as refused:
            return self._json({"error": str(refused)}, refused.status)
        except OSError as error:
            return self._json({"error": f"cannot keep the label ({error.strerror})"}, HTTPStatus.INTERNAL_SERVER_ERROR)
        return self._json({"kept": kept}, HTTPStatus.OK)

    def _json(self, data: dict, status: HTTPStatus) -> None:
        body = json.dumps(data).encode("utf-8")
        self.send_response(status)
        self.send_header("Content-Type", "application/json; charset=utf-8")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def _text(self, text: str, kind: str) -> None:
        body = text.encode("utf-8")
        self.send_response(HTTPStatus.OK)
        self.send_header("Content-Type", f"{kind}; charset=utf-8")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def _episode(self, run_id: str, index: int) -> None:
        dataset = self.pages.dataset(run_id)
        episode = None if dataset is None else dataset.episode(index)
        if episode is None:
            return self.send_error(HTTPStatus.NOT_FOUND)
        return self._text(script("viewEpisode", {"run": run_id, **episode}), "text/javascript")

    def _video(self, run_id: str, relative: str) -> None:
        dataset = self.pages.dataset(run_id)
        if dataset is None or ".." in Path(relative).parts:
            return self.send_error(HTTPStatus.NOT_FOUND)
        path = dataset.root / relative
        if not path.is_file():
            return self.send_error(HTTPStatus.NOT_FOUND)
        size = path.stat().st_size
        start, end = 0, size - 1
        match = RANGE.fullmatch(self.headers.get("Range", ""))
        if match and (match.group(1) or match.group(2)):
            if match.group(1):
                start, end = int(match.group(1)), int(match.group(2) or size - 1)
            else:  # the last N bytes
                start = max(size - int(match.group(2)), 0)
            end = min(end, size - 1)
            if start > end:
                self.send_response(HTTPStatus.REQUESTED_RANGE_NOT_SATISFIABLE)
                self.send_header("Content-Range", f"bytes */{size}")
                return self.end_headers()
            self.send_response(HTTPStatus.PARTIAL_CONTENT)
            self.send_header("Content-Range", f"bytes {start}-{end}/{size}")
        else:
            self.send_response(HTTPStatus.OK)
        self.send_header("Content-Type", "video/mp4")
        self.send_header("Accept-Ranges", "bytes")
        self.send_header("Content-Length", str(end - start + 1))
        self.end_headers()
        # The browser hangs up when it seeks elsewhere.
        with path.open("rb") as handle, contextlib.suppress(BrokenPipeError, ConnectionResetError):
            handle.seek(start)
            shutil.copyfileobj(_limited(handle, end - start + 1), self.wfile)


class _limited:
    """A file object that reads at most `left` bytes (a byte range)."""

    def __init__(self, handle, left: int) -> None:
        self.handle, self.left = handle, left

    def read(self, size: int = -1) -> bytes:
        size = self.left if size < 0 else min(size, self.left)
        data = self.handle.read(size)
        self.left -= len(data)
        return data


def serve(port: int, pages: Pages | None = None) -> ThreadingHTTPServer:
    """A server on 127.0.0.1:`port` (0: any free port), not yet serving, for `pages` (or those set later on its
    handler class); a port in use is one line."""
    handler = type("ViewHandler", (Handler,), {"pages": pages})
    try:
        server = ThreadingHTTPServer((HOST, port), handler)
    except OSError as error:
        if error.errno == errno.EADDRINUSE:
            raise ViewServerError(
                f"--port={port}: another program listens on {HOST}:{port}; pass another --port, or --port=0 for "
                "any free one"
            ) from None
        raise ViewServerError(f"--port={port}: cannot listen on {HOST}:{port} ({error.strerror})") from None
    server.daemon_threads = True
    return server


def url(server: ThreadingHTTPServer) -> str:
    return f"http://{HOST}:{server.server_address[1]}/"
