"""Publishing to and downloading from the Hub with the real huggingface_hub and datasets clients, against a fake
Hub on 127.0.0.1: create, upload, re-upload, download, retried 429/503, a failed commit, a clear 401."""

import logging
import os
import shutil
import socket
import subprocess
import sys
import types

import datasets
import huggingface_hub
import pyarrow.parquet as pq
import pytest
from lerobot.datasets import LeRobotDataset

from lerobot_contrast import publish
from lerobot_contrast.record import hub as hub_module
from lerobot_contrast.record.hub import HubAuthError, HubError, download_run, publish_run, resolve_run, run_files
from lerobot_contrast.record.run_lock import RunLock, RunLockedError

REPO = "tester/lt-contrast"
# huggingface_hub passes raw bytes as `data=`, which httpx deprecates; not ours to fix.
pytestmark = pytest.mark.filterwarnings("ignore:Use 'content=<...>' to upload raw bytes:DeprecationWarning")


@pytest.fixture(scope="module")
def run(recorded_run, tmp_path_factory):
    """The recorded run with a report beside it, as the report command leaves it."""
    run_dir = tmp_path_factory.mktemp("published") / "run"
    shutil.copytree(recorded_run, run_dir)
    (run_dir / "report").mkdir()
    (run_dir / "report" / "report.md").write_text(
        "# Report\n\n| perturbation | success [95% CI] |\n![sens](sensitivity.png)\n"
    )
    (run_dir / "report" / "sensitivity.png").write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(range(256)))
    (run_dir / "report" / "cost.png").write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(200))
    (run_dir / "rerun" / "episode_000099.rrd.partial").write_bytes(b"half written")
    return run_dir


def test_publish_creates_a_dataset_repo_holding_the_whole_run(hub, run):
    url = publish_run(run, REPO, endpoint=hub.endpoint)
    repo = hub.repo(REPO)
    sha, files = repo.head
    assert url.endswith(f"/datasets/{REPO}/commit/{sha}") and len(repo.commits) == 2  # .gitattributes, then ours
    expected = set(run_files(run)) | {"README.md", ".gitattributes"}
    assert set(files) == expected
    assert {"results.parquet", "summary.json", "config.json", "journal.jsonl", "report/cost.png"} <= expected
    assert any(p.startswith("rerun/episode_") for p in expected) and "rerun/episode_000099.rrd.partial" not in expected
    assert "dataset/meta/info.json" in expected and not any(p.startswith("dataset/images/") for p in expected)
    assert all(files[p].content == (run / p).read_bytes() for p in run_files(run))
    assert files["rerun/episode_000000.rrd"].lfs and files["results.parquet"].lfs


def test_the_card_describes_the_run_and_configures_the_viewer(hub, run):
    publish_run(run, REPO, endpoint=hub.endpoint)
    card = hub.repo(REPO).head[1]["README.md"].content.decode()
    header, body = card.split("---\n")[1], card.split("---\n", 2)[2]
    assert "config_name: results" in header and "path: results.parquet" in header and "- LeRobot" in header
    assert "config_name: frames" in header and "dataset/data/*/*.parquet" in header
    assert "[Anwar, Gupta and Thomason, CoRL 2024](https://arxiv.org/abs/2406.13636)" in body
    assert "| policy | `oracle` |" in body and "strategy: `contrast`" in body
    assert "ΔLB1 (ΔLB): swap the source" in body
    assert "### Report" in body and "![sens](report/sensitivity.png)" in body and "![cost](report/cost.png)" in body
    assert f'load_dataset("{REPO}", "results", split="train")' in body
    assert "python -m lerobot_contrast.review" in body and f"{hub.endpoint}/datasets/{REPO}/resolve/main/rerun/" in body


def test_publishing_again_is_idempotent_and_drops_files_the_run_no_longer_has(hub, run, tmp_path):
    publish_run(run, REPO, endpoint=hub.endpoint)
    publish_run(run, REPO, endpoint=hub.endpoint)
    assert len(hub.repo(REPO).commits) == 2  # nothing changed, so no second commit
    smaller = tmp_path / "run"
    shutil.copytree(run, smaller)
    shutil.rmtree(smaller / "report")
    publish_run(smaller, REPO, endpoint=hub.endpoint)
    files = hub.repo(REPO).head[1]
    assert len(hub.repo(REPO).commits) == 3 and not any(p.startswith("report/") for p in files)
    assert "## Results" in files["README.md"].content.decode() and "| **all** |" in files["README.md"].content.decode()


def test_rate_limits_and_unavailable_servers_are_retried(hub, run, caplog):
    hub.fail("POST", r"/api/repos/create$", 429)
    hub.fail("POST", r"/commit/main$", 503, times=2)
    with caplog.at_level(logging.WARNING, logger="lerobot_contrast.record.hub"):
        publish_run(run, REPO, endpoint=hub.endpoint, backoff_s=0.01)
    assert len(hub.repo(REPO).commits) == 2
    retries = [r.getMessage() for r in caplog.records if "retrying" in r.getMessage()]
    assert len(retries) == 3 and "429 to create the repo" in retries[0] and "503 to commit the run" in retries[1]
    statuses = [status for method, path, status in hub.requests if path.endswith("/commit/main")]
    assert statuses == [503, 503, 200]


def test_a_failed_upload_leaves_the_repo_untouched_and_can_be_retried(hub, run):
    hub.fail("POST", r"/commit/main$", 500)
    with pytest.raises(HubError, match="the Hub answered 500 to commit the run: injected 500"):
        publish_run(run, REPO, endpoint=hub.endpoint, backoff_s=0.01)
    assert set(hub.repo(REPO).head[1]) == {".gitattributes"}  # the LFS blobs went up, but no commit names them
    publish_run(run, REPO, endpoint=hub.endpoint)
    assert set(hub.repo(REPO).head[1]) == set(run_files(run)) | {"README.md", ".gitattributes"}


def test_a_rejected_token_gives_one_clear_line_and_never_shows_the_token(hub, run, caplog, capfd):
    bad = "hf_ThisIsNotAValidTokenAtAll123456"
    with caplog.at_level(logging.DEBUG), pytest.raises(HubAuthError) as raised:
        publish_run(run, REPO, endpoint=hub.endpoint, token=bad)
    message = str(raised.value)
    assert "refused the token (401 Unauthorized)" in message and "hf auth login" in message and "\n" not in message
    out, err = capfd.readouterr()
    assert bad not in message + out + err + caplog.text
    assert hub.repos == {}  # nothing was created


def test_the_cli_publishes_with_the_token_from_the_environment_and_reports_401_in_one_line(hub, run, tmp_path):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path), "HF_HUB_DISABLE_PROGRESS_BARS": "1"}
    command = [sys.executable, "-m", "lerobot_contrast.publish", str(run), f"--repo_id={REPO}", "--private"]
    ok = subprocess.run(command, env=env, capture_output=True, text=True, timeout=300)
    assert ok.returncode == 0, ok.stderr[-2000:]
    assert ok.stdout.startswith(f"published {run} to {REPO}: {hub.endpoint}/datasets/{REPO}/commit/")
    assert hub.repo(REPO).private
    env["HF_TOKEN"] = "hf_WrongTokenForThisTest0000000"
    denied = subprocess.run(command, env=env, capture_output=True, text=True, timeout=300)
    assert denied.returncode == 2 and denied.stderr.startswith("error: the Hub at") and denied.stderr.count("\n") == 1
    assert "hf_WrongToken" not in denied.stdout + denied.stderr


def test_bad_input_is_refused_before_any_request(hub, run, tmp_path, capsys):
    with pytest.raises(HubError, match="--repo_id must look like USER/NAME"):
        publish_run(run, "no-namespace", endpoint=hub.endpoint)
    with pytest.raises(HubError, match="no config.json, results.parquet, summary.json; pass a run directory"):
        publish_run(tmp_path, REPO, endpoint=hub.endpoint)
    assert publish.main([str(run)]) == 2
    assert "--repo_id is required" in capsys.readouterr().err
    assert hub.requests == []


def test_a_run_another_process_is_writing_is_not_published(hub, run):
    lock = RunLock.acquire(run, "an evaluation")
    try:
        with pytest.raises(RunLockedError, match=rf"is in use by process {os.getpid()} \(an evaluation, since "):
            publish_run(run, REPO + "-locked", endpoint=hub.endpoint)
    finally:
        lock.release()
    assert ("dataset", REPO + "-locked") not in hub.repos


def test_download_fetches_the_results_or_the_whole_run(hub, run, tmp_path):
    publish_run(run, REPO, endpoint=hub.endpoint)
    light = download_run(REPO, tmp_path / "light", endpoint=hub.endpoint)
    assert sorted(p.name for p in light.iterdir() if not p.name.startswith(".")) == [
        "README.md", "config.json", "journal.jsonl", "report", "results.parquet", "summary.json"
    ]  # fmt: skip
    assert pq.read_table(light / "results.parquet").num_rows == pq.read_table(run / "results.parquet").num_rows
    full = download_run(REPO, tmp_path / "full", endpoint=hub.endpoint, episodes=True)
    assert (full / "rerun" / "episode_000000.rrd").read_bytes() == (run / "rerun" / "episode_000000.rrd").read_bytes()
    dataset = LeRobotDataset("local/published", root=full / "dataset")
    assert dataset.num_episodes == LeRobotDataset("local/run", root=run / "dataset").num_episodes
    cached = resolve_run(f"hub:{REPO}", endpoint=hub.endpoint)
    assert (cached / "summary.json").read_bytes() == (run / "summary.json").read_bytes()
    with pytest.raises(HubError, match="no such dataset repo"):
        download_run("tester/missing", tmp_path / "missing", endpoint=hub.endpoint)


def test_the_results_table_loads_with_datasets_from_the_hub(hub, run, tmp_path):
    publish_run(run, REPO, endpoint=hub.endpoint)
    results = datasets.load_dataset(REPO, "results", split="train", cache_dir=str(tmp_path / "cache"))
    local = pq.read_table(run / "results.parquet")
    assert results.num_rows == local.num_rows and results["instance_id"] == local.column("instance_id").to_pylist()
    frames = datasets.load_dataset(REPO, "frames", split="train", cache_dir=str(tmp_path / "cache"))
    assert "eval.instance_id" in frames.column_names and frames.num_rows == len(
        LeRobotDataset("x", root=run / "dataset")
    )


def test_huggingface_hub_is_the_pinned_major_version():
    assert huggingface_hub.__version__.split(".")[0] == "1"


def unreachable_hub_env(tmp_path) -> dict[str, str]:
    """The environment of a command whose Hub is a port on 127.0.0.1 that nothing listens on."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    return {
        **os.environ,
        "PYTHONPATH": os.pathsep.join(sys.path),
        "HF_ENDPOINT": f"http://127.0.0.1:{port}",
        "HF_HOME": str(tmp_path / "hf_home"),
        "HF_TOKEN": "hf_DummyTokenForThisTest00000000",
    }


# Runs eval's main with huggingface_hub's waits between its own retries recorded instead of slept (test-side only: the
# client's backoff has no setting); the retries are written to a file, one wait a line, as the process exits.
NO_CLIENT_WAITS = """
import atexit, sys, types
from pathlib import Path
import huggingface_hub.utils._http as client_http
from lerobot_contrast.eval import main

waits = []
client_http.time = types.SimpleNamespace(sleep=waits.append)
atexit.register(lambda: Path(sys.argv[1]).write_text("".join(f"{wait}\\n" for wait in waits)))
sys.exit(main(sys.argv[2:]))
"""


def test_an_unreachable_hub_is_our_one_line_without_the_clients_warnings_or_retries(run, tmp_path):
    env = {**unreachable_hub_env(tmp_path), "LEROBOT_CONTRAST_HUB_BACKOFF_S": "0.01"}  # our retries, without the wait
    publishing = [sys.executable, "-m", "lerobot_contrast.publish", str(run), "--repo_id=someone/nothing"]
    waits = tmp_path / "client_waits"
    loading = [sys.executable, "-c", NO_CLIENT_WAITS, str(waits), "--policy.path=someone/nothing", "--n_instances=1"]
    loading.append(f"--output_dir={tmp_path / 'never'}")
    for command, said in (
        (publishing, "error: cannot reach the Hub at "),
        (loading, "error: --policy.path: cannot load a LeRobot policy config from 'someone/nothing' "),
    ):
        result = subprocess.run(command, env=env, capture_output=True, text=True, timeout=300)
        assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr[-3000:]
        assert result.stderr.startswith(said), result.stderr
        if command is publishing:  # every try was made before giving up
            assert "(ConnectError, 5 tries) to create the repo" in result.stderr
    assert len(waits.read_text().splitlines()) >= 5  # the client retried too, and none of its lines reached the user
    assert not (tmp_path / "never").exists()


@pytest.mark.parametrize("value", ["soon", "-1", "61"])
def test_a_bad_backoff_setting_is_one_line_naming_it(monkeypatch, tmp_path, value):
    monkeypatch.setenv("LEROBOT_CONTRAST_HUB_BACKOFF_S", value)
    with pytest.raises(HubError, match=rf"^LEROBOT_CONTRAST_HUB_BACKOFF_S='{value}': give the first retry wait in "):
        download_run("someone/nothing", tmp_path / "never", endpoint="http://127.0.0.1:9")


def test_the_backoff_setting_sets_the_waits_between_retries(hub, run, monkeypatch):
    waits = []
    monkeypatch.setattr(hub_module, "time", types.SimpleNamespace(sleep=waits.append))
    monkeypatch.setenv("LEROBOT_CONTRAST_HUB_BACKOFF_S", "0.25")
    hub.fail("POST", r"/commit/main$", 503, times=2)
    publish_run(run, REPO, endpoint=hub.endpoint)
    assert waits == [0.25, 0.5] and len(hub.repo(REPO).commits) == 2
    monkeypatch.delenv("LEROBOT_CONTRAST_HUB_BACKOFF_S")
    hub.fail("POST", r"/commit/main$", 503)
    publish_run(run, REPO + "-again", endpoint=hub.endpoint)
    assert waits[2:] == [1.0]  # unset: the first wait is a second
