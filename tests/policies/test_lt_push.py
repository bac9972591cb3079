"""`convert --push_to_hub` uploads the converted folder with the real huggingface_hub client, here to a fake Hub on
127.0.0.1 that implements the endpoints a small upload uses (create repo, validate the card, preupload, commit)."""

from __future__ import annotations

import base64
import json
import os
import subprocess
import sys
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest


class FakeHub(BaseHTTPRequestHandler):
    files: dict[str, bytes] = {}
    requests: list[str] = []

    def log_message(self, *args) -> None:  # keep pytest output clean
        pass

    def _reply(self, payload: dict, status: int = 200) -> None:
        body = json.dumps(payload).encode()
        self.send_response(status)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def do_POST(self) -> None:
        body = self.rfile.read(int(self.headers.get("Content-Length", 0)))
        self.requests.append(self.path)
        if self.path == "/api/repos/create":
            name = json.loads(body)["name"]
            self._reply({"url": f"http://{self.headers['Host']}/user/{name}", "name": f"user/{name}"})
        elif self.path == "/api/validate-yaml":  # the client checks the model card's metadata
            self._reply({"errors": [], "warnings": []})
        elif "/preupload/" in self.path:
            files = json.loads(body)["files"]
            self._reply({"files": [{"path": f["path"], "uploadMode": "regular", "shouldIgnore": False} for f in files]})
        elif "/commit/" in self.path:
            for line in body.decode().splitlines():
                entry = json.loads(line)
                if entry["key"] == "file":
                    self.files[entry["value"]["path"]] = base64.b64decode(entry["value"]["content"])
            repo = self.path.split("/")[3:5]
            url = f"http://{self.headers['Host']}/{'/'.join(repo)}/commit/{'1' * 40}"
            self._reply({"commitUrl": url, "commitOid": "1" * 40})
        else:
            self._reply({"error": f"fake hub has no {self.path}"}, status=404)


@pytest.fixture
def fake_hub():
    server = ThreadingHTTPServer(("127.0.0.1", 0), FakeHub)
    FakeHub.files, FakeHub.requests = {}, []
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_address[1]}"
    server.shutdown()
    server.server_close()


def test_push_to_hub_uploads_every_converted_file(small_checkpoint, tmp_path, fake_hub):
    env = {**os.environ, "HF_ENDPOINT": fake_hub, "HF_TOKEN": "hf_fake", "HF_HUB_DISABLE_TELEMETRY": "1"}
    out_dir = tmp_path / "out"
    argv = [str(small_checkpoint), str(out_dir), "--push_to_hub", "user/language_table_bc"]
    cmd = [sys.executable, "-m", "lerobot_policy_language_table.convert", *argv]
    result = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert "pushed to" in result.stdout
    written = {p.name: p.read_bytes() for p in Path(out_dir).iterdir()}
    assert FakeHub.files == written
    assert FakeHub.requests[0] == "/api/repos/create"


def test_a_failed_push_keeps_the_conversion_and_says_so(small_checkpoint, tmp_path):
    # Nothing listens on port 9 of the loopback address: the upload fails at once.
    env = {**os.environ, "HF_ENDPOINT": "http://127.0.0.1:9", "HF_TOKEN": "hf_fake", "HF_HUB_DISABLE_TELEMETRY": "1"}
    cmd = [sys.executable, "-m", "lerobot_policy_language_table.convert", str(small_checkpoint), str(tmp_path / "out")]
    result = subprocess.run([*cmd, "--push_to_hub", "user/x"], env=env, capture_output=True, text=True, timeout=300)
    assert result.returncode == 2
    assert result.stderr.startswith("error: pushing to user/x failed") and result.stderr.count("\n") == 1
    assert (tmp_path / "out" / "model.safetensors").exists()
