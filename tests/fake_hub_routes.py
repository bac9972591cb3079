"""The fake Hub's HTTP side: repository state and one handler method per endpoint the clients call."""

from __future__ import annotations

import base64
import hashlib
import json
import re
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler
from typing import TYPE_CHECKING
from urllib.parse import parse_qs, unquote, urlsplit

if TYPE_CHECKING:
    from tests.fake_hub import FakeHub

TYPES = {"models": "model", "datasets": "dataset", "spaces": "space"}
LFS_THRESHOLD = 10 * 1024 * 1024
GITATTRIBUTES = b"*.parquet filter=lfs diff=lfs merge=lfs -text\n"


def git_sha1(data: bytes) -> str:
    return hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()


@dataclass
class File:
    content: bytes
    lfs: bool

    @property
    def oid(self) -> str:
        return hashlib.sha256(self.content).hexdigest() if self.lfs else git_sha1(self.content)


@dataclass
class Repo:
    repo_type: str
    repo_id: str
    private: bool
    commits: list[tuple[str, dict[str, File]]] = field(default_factory=list)

    @property
    def head(self) -> tuple[str, dict[str, File]]:
        return self.commits[-1]

    def files(self, revision: str) -> tuple[str, dict[str, File]] | None:
        if revision in ("main", "refs/heads/main"):
            return self.head
        return next(((sha, files) for sha, files in self.commits if sha == revision), None)

    def commit(self, files: dict[str, File], title: str) -> str:
        sha = hashlib.sha1(f"{self.repo_id}:{len(self.commits)}:{title}".encode()).hexdigest()
        self.commits.append((sha, files))
        return sha


class Handler(BaseHTTPRequestHandler):
    hub: FakeHub
    protocol_version = "HTTP/1.1"

    def log_message(self, *args) -> None:  # keep pytest output clean
        pass

    def do_GET(self) -> None:
        self._dispatch("GET")

    def do_HEAD(self) -> None:
        self._dispatch("HEAD")

    def do_POST(self) -> None:
        self._dispatch("POST")

    def do_PUT(self) -> None:
        self._dispatch("PUT")

    def do_DELETE(self) -> None:
        self._dispatch("DELETE")

    # -- plumbing ---------------------------------------------------------------------------------------------

    def _body(self) -> bytes:
        length = int(self.headers.get("Content-Length") or 0)
        return self.rfile.read(length) if length else b""

    def _send(self, status: int, body: bytes = b"", headers: dict[str, str] | None = None, ctype="application/json"):
        self.send_response(status)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        for key, value in (headers or {}).items():
            self.send_header(key, value)
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)
        self.hub.requests.append((self.command, self.path, status))

    def _json(self, status: int, data, headers: dict[str, str] | None = None) -> None:
        self._send(status, json.dumps(data).encode(), headers)

    def _error(self, status: int, message: str, code: str | None = None) -> None:
        self._json(status, {"error": message}, {"X-Error-Code": code} if code else None)

    def _auth(self) -> str:
        header = self.headers.get("Authorization")
        if header is None:
            return "none"
        return "ok" if header == f"Bearer {self.hub.token}" else "bad"

    def _dispatch(self, method: str) -> None:
        path = urlsplit(self.path).path
        body = self._body() if method in ("POST", "PUT") else b""
        with self.hub.lock:
            for fault in self.hub.faults:
                if fault[3] > 0 and fault[0] == method and fault[1].search(path):
                    fault[3] -= 1
                    return self._error(fault[2], f"injected {fault[2]}")
        auth = self._auth()
        if auth == "bad" or (auth == "none" and method in ("POST", "PUT", "DELETE") and "/lfs-" not in path):
            return self._error(401, "Invalid credentials in Authorization header")
        for verb, pattern, handler in ROUTES:
            match = re.fullmatch(pattern, path) if verb == method or (verb, method) == ("GET", "HEAD") else None
            if match:
                with self.hub.lock:
                    return handler(self, {k: unquote(v) for k, v in match.groupdict().items() if v}, body)
        self._error(404, f"no route for {method} {path}")

    def _repo(self, params: dict, revision: str | None = None):
        repo = self.hub.repos.get((TYPES.get(params.get("type", "models"), "model"), params["repo"]))
        if repo is None or (repo.private and self._auth() != "ok"):
            self._error(404, "Repository not found", "RepoNotFound")
            return None
        if revision is None:
            return repo
        state = repo.files(revision)
        if state is None:
            self._error(404, f"Invalid rev id: {revision}", "RevisionNotFound")
            return None
        return repo, state

    # -- routes -----------------------------------------------------------------------------------------------

    def create_repo(self, params: dict, body: bytes) -> None:
        data = json.loads(body)
        repo_id = f"{data.get('organization') or 'tester'}/{data['name']}"
        key = (data.get("type") or "model", repo_id)
        url = f"{self.hub.endpoint}/{'' if key[0] == 'model' else key[0] + 's/'}{repo_id}"
        if key in self.hub.repos:
            return self._json(409, {"error": "You already created this repo", "url": url})
        private = bool(data.get("private")) or data.get("visibility") == "private"
        repo = Repo(key[0], repo_id, private)
        repo.commit({".gitattributes": File(GITATTRIBUTES, False)}, "initial commit")
        self.hub.repos[key] = repo
        self._json(200, {"url": url, "name": repo_id})

    def whoami(self, params: dict, body: bytes) -> None:
        if self._auth() != "ok":
            return self._error(401, "Invalid credentials in Authorization header")
        self._json(200, {"type": "user", "name": "tester", "orgs": [], "auth": {"type": "access_token"}})

    def validate_yaml(self, params: dict, body: bytes) -> None:
        self._json(200, {"errors": [], "warnings": []})

    def repo_info(self, params: dict, body: bytes) -> None:
        found = self._repo(params, params.get("rev", "main"))
        if found:
            repo, (sha, files) = found
            self._json(
                200,
                {
                    "_id": sha[:24],
                    "id": repo.repo_id,
                    "author": repo.repo_id.split("/")[0],
                    "sha": sha,
                    "private": repo.private,
                    "gated": False,
                    "disabled": False,
                    "lastModified": "2026-01-01T00:00:00.000Z",
                    "createdAt": "2026-01-01T00:00:00.000Z",
                    "tags": [],
                    "downloads": 0,
                    "likes": 0,
                    "siblings": [{"rfilename": p} for p in sorted(files)],
                },
            )

    def refs(self, params: dict, body: bytes) -> None:
        repo = self._repo(params)
        if repo:
            branch = {"name": "main", "ref": "refs/heads/main", "targetCommit": repo.head[0]}
            self._json(200, {"branches": [branch], "tags": [], "converts": []})

    def preupload(self, params: dict, body: bytes) -> None:
        found = self._repo(params, params["rev"])
        if found:
            _, (_, files) = found
            out = []
            for item in json.loads(body)["files"]:
                binary = b"\0" in base64.b64decode(item["sample"]) or item["size"] > LFS_THRESHOLD
                existing = files.get(item["path"])
                entry = {"path": item["path"], "uploadMode": "lfs" if binary else "regular", "shouldIgnore": False}
                if existing is not None:
                    entry["oid"] = existing.oid
                out.append(entry)
            self._json(200, {"files": out})

    def lfs_batch(self, params: dict, body: bytes) -> None:
        if self._repo(params) is None:
            return
        objects = []
        for obj in json.loads(body)["objects"]:
            entry = {"oid": obj["oid"], "size": obj["size"], "authenticated": True}
            if obj["oid"] not in self.hub.lfs:
                base = self.hub.endpoint
                entry["actions"] = {
                    "upload": {"href": f"{base}/lfs-upload/{obj['oid']}"},
                    "verify": {"href": f"{base}/lfs-verify/{obj['oid']}"},
                }
            objects.append(entry)
        self._send(
            200, json.dumps({"transfer": "basic", "objects": objects}).encode(), ctype="application/vnd.git-lfs+json"
        )

    def lfs_upload(self, params: dict, body: bytes) -> None:
        if hashlib.sha256(body).hexdigest() != params["oid"]:
            return self._error(400, "sha256 mismatch")
        self.hub.lfs[params["oid"]] = body
        self._send(200)

    def lfs_verify(self, params: dict, body: bytes) -> None:
        self._json(200 if params["oid"] in self.hub.lfs else 404, {})

    def commit(self, params: dict, body: bytes) -> None:
        found = self._repo(params, params["rev"])
        if not found:
            return
        repo, (head, files) = found
        files, title = dict(files), ""
        for line in body.decode().splitlines():
            item = json.loads(line)
            key, value = item["key"], item["value"]
            if key == "header":
                title = value["summary"]
                if value.get("parentCommit") not in (None, head):
                    return self._error(412, "parent commit is not the head")
            elif key == "file":
                files[value["path"]] = File(base64.b64decode(value["content"]), False)
            elif key == "lfsFile":
                if value["oid"] not in self.hub.lfs:
                    return self._error(400, f"LFS object {value['oid']} was never uploaded")
                files[value["path"]] = File(self.hub.lfs[value["oid"]], True)
            elif key == "deletedFile":
                files.pop(value["path"], None)
            elif key == "deletedFolder":
                files = {p: f for p, f in files.items() if not p.startswith(value["path"].rstrip("/") + "/")}
        sha = repo.commit(files, title)
        self._json(
            200, {"commitOid": sha, "commitUrl": f"{self.hub.endpoint}/{params['type']}/{repo.repo_id}/commit/{sha}"}
        )

    def _entries(self, files: dict[str, File], prefix: str, recursive: bool) -> list[dict]:
        entries, dirs = [], set()
        for path, file in sorted(files.items()):
            if prefix and not path.startswith(prefix + "/"):
                continue
            rest = path[len(prefix) + 1 :] if prefix else path
            parts = rest.split("/")
            for depth in range(1, len(parts)):
                if recursive or depth == 1:
                    dirs.add("/".join(([prefix] if prefix else []) + parts[:depth]))
            if recursive or len(parts) == 1:
                entries.append(_file_entry(path, file))
        entries += [{"type": "directory", "oid": git_sha1(d.encode()), "size": 0, "path": d} for d in sorted(dirs)]
        return entries

    def tree(self, params: dict, body: bytes) -> None:
        found = self._repo(params, params["rev"])
        if found:
            _, (_, files) = found
            prefix = params.get("path", "").strip("/")
            recursive = parse_qs(urlsplit(self.path).query).get("recursive", ["false"])[0] == "true"
            if prefix and not any(p.startswith(prefix + "/") for p in files):
                return self._error(404, f"{prefix} does not exist", "EntryNotFound")
            self._json(200, self._entries(files, prefix, recursive))

    def paths_info(self, params: dict, body: bytes) -> None:
        found = self._repo(params, params["rev"])
        if found:
            _, (_, files) = found
            if self.headers.get("Content-Type", "").startswith("application/json"):
                paths = json.loads(body)["paths"]
            else:
                paths = parse_qs(body.decode()).get("paths", [])
            out = []
            for path in paths:
                if path in files:
                    out.append(_file_entry(path, files[path]))
                elif any(p.startswith(path.rstrip("/") + "/") for p in files):
                    out.append({"type": "directory", "oid": git_sha1(path.encode()), "size": 0, "path": path})
            self._json(200, out)

    def resolve(self, params: dict, body: bytes) -> None:
        found = self._repo(params, params["rev"])
        if not found:
            return
        _, (sha, files) = found
        file = files.get(params["path"])
        if file is None:
            return self._error(404, f"{params['path']} does not exist", "EntryNotFound")
        data, status = file.content, 200
        headers = {"X-Repo-Commit": sha, "ETag": f'"{file.oid}"', "Accept-Ranges": "bytes"}
        ranged = re.fullmatch(r"bytes=(\d+)-(\d*)", self.headers.get("Range", ""))
        if ranged:
            start = int(ranged.group(1))
            end = int(ranged.group(2)) if ranged.group(2) else len(data) - 1
            headers["Content-Range"] = f"bytes {start}-{min(end, len(data) - 1)}/{len(data)}"
            data, status = data[start : end + 1], 206
        self._send(status, data, headers, ctype="application/octet-stream")


def _file_entry(path: str, file: File) -> dict:
    entry = {"type": "file", "oid": git_sha1(file.content), "size": len(file.content), "path": path}
    if file.lfs:
        entry["lfs"] = {"oid": file.oid, "size": len(file.content), "pointerSize": 134}
    return entry


_REPO = r"(?P<repo>[^/]+/[^/]+)"
_API = rf"/api/(?P<type>models|datasets|spaces)/{_REPO}"
_GIT = rf"/(?:(?P<type>datasets|spaces)/)?{_REPO}"
ROUTES = [
    ("POST", r"/api/repos/create", Handler.create_repo),
    ("GET", r"/api/whoami-v2", Handler.whoami),
    ("POST", r"/api/validate-yaml", Handler.validate_yaml),
    ("GET", rf"{_API}(?:/revision/(?P<rev>[^/]+))?", Handler.repo_info),
    ("GET", rf"{_API}/refs", Handler.refs),
    ("POST", rf"{_API}/preupload/(?P<rev>[^/]+)", Handler.preupload),
    ("POST", rf"{_API}/commit/(?P<rev>[^/]+)", Handler.commit),
    ("GET", rf"{_API}/tree/(?P<rev>[^/]+)(?:/(?P<path>.*))?", Handler.tree),
    ("POST", rf"{_API}/paths-info/(?P<rev>[^/]+)", Handler.paths_info),
    ("POST", rf"{_GIT}\.git/info/lfs/objects/batch", Handler.lfs_batch),
    ("PUT", r"/lfs-upload/(?P<oid>[0-9a-f]{64})", Handler.lfs_upload),
    ("POST", r"/lfs-verify/(?P<oid>[0-9a-f]{64})", Handler.lfs_verify),
    ("GET", rf"{_GIT}/resolve/(?P<rev>[^/]+)/(?P<path>.+)", Handler.resolve),
]
