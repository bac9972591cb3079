"""A fake Hugging Face Hub for tests, on 127.0.0.1 only, with repositories in memory.

It speaks the HTTP endpoints the real `huggingface_hub` and `datasets` clients use to create dataset repos,
commit regular and LFS files (Xet disabled), list trees and download files, and it can fail chosen requests
(429, 503, ...) and reject bad tokens with 401. The endpoints live in `fake_hub_routes`."""

from __future__ import annotations

import re
import threading
from http.server import ThreadingHTTPServer

from tests.fake_hub_routes import Handler, Repo


class FakeHub:
    """Start with `start()` (returns the endpoint URL); `fail(method, path_regex, status, times)` injects errors."""

    def __init__(self, token: str = "hf_fake_write_token_0123456789") -> None:
        self.token = token
        self.repos: dict[tuple[str, str], Repo] = {}
        self.lfs: dict[str, bytes] = {}
        self.requests: list[tuple[str, str, int]] = []
        self.faults: list[list] = []
        self.lock = threading.Lock()
        self._server: ThreadingHTTPServer | None = None

    def start(self) -> str:
        handler = type("BoundHandler", (Handler,), {"hub": self})
        self._server = ThreadingHTTPServer(("127.0.0.1", 0), handler)
        threading.Thread(target=self._server.serve_forever, daemon=True).start()
        return self.endpoint

    @property
    def endpoint(self) -> str:
        assert self._server is not None
        return f"http://127.0.0.1:{self._server.server_address[1]}"

    def stop(self) -> None:
        if self._server is not None:
            self._server.shutdown()
            self._server.server_close()

    def fail(self, method: str, path_regex: str, status: int, times: int = 1) -> None:
        self.faults.append([method, re.compile(path_regex), status, times])

    def repo(self, repo_id: str, repo_type: str = "dataset") -> Repo:
        return self.repos[(repo_type, repo_id)]
