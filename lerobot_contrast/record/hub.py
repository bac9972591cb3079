"""Publish a run directory to the Hugging Face Hub as a dataset repo, and download published runs (`hub:USER/NAME`).

A publication is one commit: a failed upload leaves the repo as it was, and publishing again converges to the
same files. Rate limits and unavailable servers are retried with backoff; the token never appears in messages."""

from __future__ import annotations

import logging
import os
import re
import time
from collections.abc import Callable, Mapping
from pathlib import Path

import httpx
from huggingface_hub import CommitOperationAdd, CommitOperationDelete, HfApi, snapshot_download
from huggingface_hub.errors import (
    HfHubHTTPError,
    LocalEntryNotFoundError,
    RepositoryNotFoundError,
    RevisionNotFoundError,
)

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.record.card import dataset_card
from lerobot_contrast.record.run_lock import RunLock
from lerobot_contrast.record.third_party import quiet_hub_client

HUB_PREFIX = "hub:"
REQUIRED = ("config.json", "results.parquet", "summary.json")
OPTIONAL = ("journal.jsonl", "plan.json")
# What `eval --plan` and `report` need: everything but the episodes.
RUN_PATTERNS = ["README.md", *REQUIRED, *OPTIONAL, "report/*"]
RETRY_STATUS = (429, 502, 503, 504)
MAX_WAIT_S = 60.0
# The first wait before retrying (it doubles per try); a setting for slow links, or tests that must not wait.
BACKOFF_ENV = "LEROBOT_CONTRAST_HUB_BACKOFF_S"
DEFAULT_BACKOFF_S = 1.0
REPO_ID = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*/[A-Za-z0-9][A-Za-z0-9._-]*")
TOKEN_LIKE = re.compile(r"hf_[A-Za-z0-9]{8,}")

logger = logging.getLogger(__name__)


class HubError(UserError):
    pass


class HubAuthError(HubError):
    pass


def parse_hub_spec(spec: str) -> tuple[str, str | None] | None:
    """`hub:USER/NAME[@REVISION]` -> (repo_id, revision); None for anything else (a local path)."""
    if not spec.startswith(HUB_PREFIX):
        return None
    repo_id, _, revision = spec.removeprefix(HUB_PREFIX).partition("@")
    return check_repo_id(repo_id), revision or None


def check_repo_id(repo_id: str) -> str:
    if not REPO_ID.fullmatch(repo_id):
        raise HubError(f"--repo_id must look like USER/NAME (letters, digits, '.', '_', '-'), got {repo_id!r}")
    return repo_id


def run_files(run_dir: Path) -> dict[str, Path]:
    """The files a publication holds, by their path in the repo (the run directory's own layout)."""
    missing = [name for name in REQUIRED if not (run_dir / name).is_file()]
    if missing:
        raise HubError(f"{run_dir}: no {', '.join(missing)}; pass a run directory written by lerobot_contrast.eval")
    files = {name: run_dir / name for name in (*REQUIRED, *OPTIONAL) if (run_dir / name).is_file()}
    for folder, pattern in (("report", "**/*"), ("rerun", "*"), ("dataset", "**/*")):
        for path in sorted((run_dir / folder).glob(pattern)):
            relative = path.relative_to(run_dir).as_posix()
            if path.is_file() and not _transient(relative):
                files[relative] = path
    return files


def _transient(relative: str) -> bool:
    """Files still being written, and LeRobot's image staging, which never belongs in a published dataset."""
    return relative.endswith((".partial", ".tmp")) or relative.startswith("dataset/images/")


def _scrub(text: str, token: str | None) -> str:
    if token:
        text = text.replace(token, "***")
    return TOKEN_LIKE.sub("hf_***", text)


def backoff_from_env() -> float:
    """The first retry wait: LEROBOT_CONTRAST_HUB_BACKOFF_S seconds when set, else 1 s."""
    value = os.environ.get(BACKOFF_ENV)
    if value is None:
        return DEFAULT_BACKOFF_S
    try:
        seconds = float(value)
    except ValueError:
        seconds = -1.0
    if not 0 <= seconds <= MAX_WAIT_S:
        raise HubError(f"{BACKOFF_ENV}={value!r}: give the first retry wait in seconds, from 0 to {MAX_WAIT_S:g}")
    return seconds


def _with_retries[T](
    call: Callable[[], T], what: str, api: HfApi, repo_id: str, attempts: int, backoff_s: float | None
) -> T:
    backoff_s = backoff_from_env() if backoff_s is None else backoff_s
    for attempt in range(1, attempts + 1):
        try:
            with quiet_hub_client():
                return call()
        except HfHubHTTPError as error:
            status = error.response.status_code if error.response is not None else None
            if status not in RETRY_STATUS or attempt == attempts:
                raise _translate(error, status, what, api, repo_id) from None
            wait = _retry_after(error.response) or backoff_s * 2 ** (attempt - 1)
            # The Hub answered and asked us to wait: say so, since the wait may be long.
            logger.warning(
                "the Hub answered %s to %s; retrying in %.1f s (%d/%d)", status, what, wait, attempt, attempts
            )
        except httpx.TransportError as error:
            if attempt == attempts:
                raise HubError(
                    f"cannot reach the Hub at {api.endpoint} ({type(error).__name__}, {attempts} tries) to {what}; "
                    "check the network connection (or HF_ENDPOINT) and try again"
                ) from None
            wait = backoff_s * 2 ** (attempt - 1)  # no answer at all: the one-line error says it, if it lasts
            logger.debug("no answer from the Hub to %s; retrying in %.1f s (%d/%d)", what, wait, attempt, attempts)
        time.sleep(min(wait, MAX_WAIT_S))
    raise AssertionError("unreachable")


def _retry_after(response: httpx.Response | None) -> float | None:
    value = None if response is None else response.headers.get("Retry-After")
    try:
        return None if value is None else float(value)
    except ValueError:
        return None


def _translate(error: HfHubHTTPError, status: int | None, what: str, api: HfApi, repo_id: str) -> HubError:
    if status == 401:
        return HubAuthError(
            f"the Hub at {api.endpoint} refused the token (401 Unauthorized) to {what}; "
            "log in with `hf auth login` or set HF_TOKEN to a token with write access"
        )
    if status == 403:
        return HubAuthError(f"the token may not write to {repo_id} (403 Forbidden); use a token with write access")
    if isinstance(error, RepositoryNotFoundError):
        return HubError(
            f"{repo_id}: no such dataset repo at {api.endpoint} (or it is private and the token cannot read it)"
        )
    if isinstance(error, RevisionNotFoundError):
        return HubError(f"{repo_id}: no such revision; check the part after '@'")
    server = (error.server_message or "").splitlines()[0] if error.server_message else ""
    return HubError(_scrub(f"the Hub answered {status} to {what}{': ' + server if server else ''}", api.token))


def publish_run(
    run_dir: Path | str,
    repo_id: str,
    *,
    private: bool = False,
    token: str | None = None,
    endpoint: str | None = None,
    commit_message: str | None = None,
    attempts: int = 5,
    backoff_s: float | None = None,
    extra_files: Mapping[str, Path] | None = None,
) -> str:
    """Upload `run_dir` as the dataset repo `repo_id` in one commit; returns the commit URL. Without `backoff_s`, the
    first retry waits LEROBOT_CONTRAST_HUB_BACKOFF_S seconds (default 1). `extra_files` adds files made for the
    publication (the viewer's bundle), by their path in the repo.

    Files in the repo that the run no longer has are deleted in the same commit, so publishing twice
    leaves the repo exactly as publishing once."""
    run_dir = Path(run_dir)
    check_repo_id(repo_id)
    run_files(run_dir)  # a folder that holds no run is refused before it is locked
    try:  # a run another process is still writing is not published half-way
        lock = RunLock.acquire(run_dir, f"publishing to {repo_id}")
    except OSError as error:
        raise HubError(f"{run_dir}: cannot lock the run to publish it ({error.strerror})") from None
    try:
        files = run_files(run_dir) | dict(extra_files or {})
        return _publish(run_dir, files, repo_id, private, token, endpoint, commit_message, attempts, backoff_s)
    finally:
        lock.release()


def _publish(
    run_dir: Path,
    files: dict[str, Path],
    repo_id: str,
    private: bool,
    token: str | None,
    endpoint: str | None,
    commit_message: str | None,
    attempts: int,
    backoff_s: float | None,
) -> str:
    api = HfApi(endpoint=endpoint, token=token)
    card = dataset_card(run_dir, repo_id, api.endpoint, any(p.startswith("dataset/data/") for p in files))

    def retry[R](call: Callable[[], R], what: str) -> R:
        return _with_retries(call, what, api, repo_id, attempts, backoff_s)

    retry(lambda: api.create_repo(repo_id, repo_type="dataset", private=private, exist_ok=True), "create the repo")
    remote = retry(lambda: api.list_repo_files(repo_id, repo_type="dataset"), "list the repo")
    stale = sorted(set(remote) - set(files) - {"README.md", ".gitattributes"})

    def operations() -> list:  # rebuilt per attempt: the client annotates operations while uploading
        adds = [CommitOperationAdd("README.md", card.encode("utf-8"))]
        adds += [CommitOperationAdd(name, path) for name, path in files.items()]
        return adds + [CommitOperationDelete(name) for name in stale]

    message = commit_message or f"Publish contrast-set evaluation {run_dir.resolve().name}"
    info = retry(
        lambda: api.create_commit(repo_id, operations(), commit_message=message, repo_type="dataset"), "commit the run"
    )
    return info.commit_url


def download_run(
    repo_id: str,
    local_dir: Path | str | None = None,
    *,
    revision: str | None = None,
    episodes: bool = False,
    token: str | None = None,
    endpoint: str | None = None,
    attempts: int = 5,
    backoff_s: float | None = None,
) -> Path:
    """Download a published run; returns its directory. Without `episodes` only the results, summary, config,
    journal, plan and report come (what `report` and `eval --plan` read), not the Rerun files or the dataset."""
    check_repo_id(repo_id)
    api = HfApi(endpoint=endpoint, token=token)
    try:
        path = _with_retries(
            lambda: snapshot_download(
                repo_id,
                repo_type="dataset",
                revision=revision,
                local_dir=local_dir,
                allow_patterns=None if episodes else RUN_PATTERNS,
                token=token,
                endpoint=endpoint,
            ),
            "download the run",
            api,
            repo_id,
            attempts,
            backoff_s,
        )
    except LocalEntryNotFoundError:  # the client's word for "offline, and not in the cache either"
        raise HubError(
            f"hub:{repo_id}: cannot reach the Hub at {api.endpoint} and the local Hub cache holds no copy; "
            "check the network connection (or HF_ENDPOINT) and try again"
        ) from None
    run_dir = Path(path)
    if not all((run_dir / name).is_file() for name in ("config.json", "results.parquet")):
        raise HubError(f"hub:{repo_id} holds no lerobot-contrast run (no config.json and results.parquet)")
    return run_dir


def resolve_run(spec: str | Path, **download: object) -> Path:
    """A run directory from a local path or `hub:USER/NAME[@REVISION]` (downloaded into the Hub cache)."""
    parsed = parse_hub_spec(str(spec))
    if parsed is None:
        return Path(spec)
    repo_id, revision = parsed
    return download_run(repo_id, revision=revision, **download)  # type: ignore[arg-type]
