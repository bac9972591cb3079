"""The command: one line for bad input, the server (page, data, episode scripts, video byte ranges, a run in
progress refreshed), the static bundle, and the bundle `publish` adds to the Hub dataset."""

import json
import socket
import subprocess
import sys
import threading
import urllib.request

import pytest

from lerobot_contrast import publish
from lerobot_contrast.view.command import main
from lerobot_contrast.view.payload import Pages
from lerobot_contrast.view.server import serve, url

pytestmark = pytest.mark.xdist_group("view")
VIEW = [sys.executable, "-m", "lerobot_contrast.view"]


def one_line_error(args, match):
    done = subprocess.run([*VIEW, *args], capture_output=True, text=True, timeout=300)
    assert done.returncode == 2 and done.stderr.startswith("error: ") and done.stderr.count("\n") == 1, done.stderr
    assert match in done.stderr
    return done


def test_a_folder_that_is_not_a_run_is_one_line(tmp_path):
    one_line_error([str(tmp_path)], "not a run directory (no config.json)")
    one_line_error([str(tmp_path / "missing")], "no such run directory")


def test_a_port_in_use_is_one_line(runs):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        one_line_error([str(runs["noisy"]), f"--port={port}"], f"another program listens on 127.0.0.1:{port}")


def test_a_bundle_is_never_written_over_other_files(runs, tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("mine")
    assert main([str(runs["noisy"]), f"--bundle={tmp_path}"]) == 2
    assert "holds other files" in capsys.readouterr().err and (tmp_path / "notes.txt").read_text() == "mine"


@pytest.fixture
def served(runs):
    server = serve(0, Pages([str(runs["noisy"])]))
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield url(server)
    server.shutdown()
    server.server_close()


def get(address, headers=None):
    with urllib.request.urlopen(urllib.request.Request(address, headers=headers or {}), timeout=30) as answer:
        return answer.status, dict(answer.headers), answer.read()


def document(text: bytes, callback: str) -> dict:
    body = text.decode()
    assert body.startswith(callback + "(") and body.endswith(");\n")
    return json.loads(body[len(callback) + 1 : -3])


def test_the_server_gives_the_page_its_data_and_the_videos_by_byte_range(served, runs):
    status, _, page = get(served)
    assert status == 200 and b"data/runs.js" in page
    assert get(served + "static/uPlot.iife.min.js")[0] == 200
    doc = document(get(served + "data/runs.js")[2], "viewData")
    trial = next(t for t in doc["runs"][0]["trials"] if t["episode"] is not None)
    episode = document(get(served + f"data/episodes/r0/{trial['episode']}.js")[2], "viewEpisode")
    path = episode["videos"][0]["path"]
    whole = (runs["noisy"] / "dataset" / path).read_bytes()
    status, headers, part = get(served + f"videos/r0/{path}", {"Range": "bytes=10-99"})
    assert status == 206 and part == whole[10:100] and headers["Content-Range"] == f"bytes 10-99/{len(whole)}"
    assert get(served + f"videos/r0/{path}")[2] == whole
    for missing in ("data/episodes/r0/99999.js", "videos/r0/../config.json", "view.py"):
        with pytest.raises(urllib.error.HTTPError):
            get(served + missing)


def test_a_run_in_progress_is_read_again_when_a_trial_comes_in(in_progress):
    run, lines = in_progress
    journal = run / "journal.jsonl"
    pages = Pages([str(run)])
    first = pages.current()
    assert first["live"] and len(first["runs"][0]["trials"]) == 5
    assert pages.current() is first  # nothing changed: nothing read again
    journal.write_text("".join(lines))
    assert len(pages.current()["runs"][0]["trials"]) == len(lines)


def test_the_bundle_holds_the_page_its_data_and_the_videos(runs, tmp_path, capsys):
    out = tmp_path / "site"
    assert main([str(runs["noisy"]), f"--bundle={out}"]) == 0
    assert capsys.readouterr().out.startswith(f"bundle: {out} (")
    doc = document((out / "data" / "runs.js").read_bytes(), "viewData")
    (run,) = doc["runs"]
    episodes = [t["episode"] for t in run["trials"] if t["episode"] is not None]
    assert episodes and all((out / "data" / "episodes" / "r0" / f"{e}.js").is_file() for e in episodes)
    assert len(list((out / "videos" / "r0").rglob("*.mp4"))) == len(episodes)
    assert (out / "index.html").is_file() and (out / "static" / "app.js").is_file() and not doc["live"]
    assert main([str(runs["noisy"]), f"--bundle={out}"]) == 0  # a bundle is replaced by a new one


def test_a_run_that_recorded_no_dataset_is_bundled_with_its_trials(runs, tmp_path, capsys):
    """As the README's default run: no dataset, so no episodes or videos, and still the page and every trial."""
    out = tmp_path / "site"
    assert main([str(runs["oracle"]), f"--bundle={out}"]) == 0, capsys.readouterr().err
    doc = document((out / "data" / "runs.js").read_bytes(), "viewData")
    (run,) = doc["runs"]
    assert run["trials"] and all(t["episode"] is None for t in run["trials"])
    assert not (out / "data" / "episodes").exists() and not (out / "videos").exists()
    assert (out / "index.html").is_file()


@pytest.mark.filterwarnings("ignore:Use 'content=<...>' to upload raw bytes:DeprecationWarning")  # the Hub client's
def test_publish_adds_the_bundle_reading_the_published_dataset_s_videos(hub, runs, copy_of):
    run = copy_of(runs["noisy"])
    assert publish.main([str(run), "--repo_id=tester/view"]) == 0
    files = hub.repo("tester/view").head[1]
    assert {"view/index.html", "view/static/app.js", "view/data/runs.js"} <= set(files)
    doc = document(files["view/data/runs.js"].content, "viewData")
    assert doc["runs"][0]["video_base"] == "../dataset/"
    episode = document(files["view/data/episodes/r0/0.js"].content, "viewEpisode")
    assert "dataset/" + episode["videos"][0]["path"] in files  # the page plays the dataset's own file
    assert not any(name.startswith("view/videos/") for name in files)
