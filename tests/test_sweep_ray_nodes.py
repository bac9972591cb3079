"""A sweep on a Ray cluster as a lab starts one: a head and a second node, each a `ray start` process on loopback with
Ray's default token authentication, both from an environment without this project (its code comes through Ray).
The second node, where the cells run, cannot see the driver's sweep folder (hidden by a mount namespace), so its cells
come back through Ray; a wrong address or token is one line; a sweep interrupted mid-way resumes."""

import json
import os
import shutil
import signal
import subprocess
import sys
import sysconfig
import tempfile
import time
import uuid
from pathlib import Path

import psutil
import pytest
import yaml

from lerobot_contrast.ports import free_port
from lerobot_contrast.record.journal import read_journal
from lerobot_contrast.sweep.carry import MARK
from lerobot_contrast.sweep.shipping import DISTRIBUTIONS

pytestmark = pytest.mark.slow

ORACLE = {"max_episode_steps": 30, "rerun": False, "policy": {"type": "oracle"}}
TINY = {"eval": {"n_instances": 2, **ORACLE}, "grid": {"seed": [0, 1]}}
# Three cells of 28 trials, one at a time on the node's one CPU: long enough to interrupt the second mid-way.
THREE = {"eval": {"n_instances": 4, **ORACLE, "max_episode_steps": 40}, "grid": {"seed": [0, 1, 2]}}
OURS = tuple(name.replace("-", "_") for name in DISTRIBUTIONS)


def namespace_command() -> list[str] | None:
    """A mount namespace of its own for the second node (root, or a user namespace), or None where neither works."""
    for command in (["unshare", "-m"], ["unshare", "-rm"]):
        if shutil.which("unshare") and subprocess.run([*command, "true"], capture_output=True).returncode == 0:
            return command
    return None


def worker_venv(root: Path) -> Path:
    """A venv holding this environment's third-party packages (symlinks) but none of this project's distributions:
    not its editable installs' finders, nor their metadata."""
    venv = root / "wv"
    subprocess.run([getattr(sys, "_base_executable", sys.executable), "-m", "venv", "--without-pip", venv], check=True)
    site = venv / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}" / "site-packages"
    for entry in Path(sysconfig.get_paths()["purelib"]).iterdir():
        if not entry.name.startswith(("__editable__", *OURS)):
            (site / entry.name).symlink_to(entry)
    return venv / "bin" / "python"


def stop(root: Path) -> None:
    """End the processes this module's Ray started: those whose RAY_TMPDIR is its own."""
    for proc in psutil.process_iter():
        try:
            if proc.environ().get("RAY_TMPDIR") == str(root / "rt"):
                proc.kill()
        except psutil.Error:
            continue


@pytest.fixture(scope="module")
def cluster():
    unshare = namespace_command()
    if unshare is None:
        pytest.skip("needs a mount namespace (unshare -m) to hide the sweep folder from the second node")
    root = Path(tempfile.mkdtemp(prefix="rn", dir="/tmp"))  # short: Ray's socket paths live under it
    for folder in ("home/.ray", "whome/.ray", "driver", "wlocal", "wtmp", "rt"):
        (root / folder).mkdir(parents=True)
    token = uuid.uuid4().hex
    for home in ("home", "whome"):  # the token where Ray looks first on each machine: ~/.ray/auth_token
        (root / home / ".ray" / "auth_token").write_text(token)
    gcs, client = free_port(), free_port()
    base = {**os.environ, "RAY_TMPDIR": str(root / "rt")}
    base.pop("RAY_AUTH_MODE", None)
    driver_env = {**base, "HOME": str(root / "home")}
    ports = ["--node-ip-address=127.0.0.1", "--disable-usage-stats", f"--dashboard-agent-listen-port={free_port()}"]
    try:
        python = worker_venv(root)
        # Neither node has this project: the head's Ray Client server, too, takes the driver's code from Ray.
        head = [python, "-m", "ray.scripts.scripts", "start", "--head", f"--port={gcs}", "--num-cpus=0"]
        head += [f"--ray-client-server-port={client}", "--include-dashboard=false", *ports]
        subprocess.run(head, env=driver_env, cwd=root / "wlocal", check=True, capture_output=True)
        node = f"{python} -m ray.scripts.scripts start --address=127.0.0.1:{gcs} --num-cpus=1 {' '.join(ports)}"
        hide = f"mount -t tmpfs none {root / 'driver'} && cd {root / 'wlocal'} && exec {node}"
        worker_env = {**base, "HOME": str(root / "whome"), "TMPDIR": str(root / "wtmp"), "RAY_AUTH_MODE": "token"}
        subprocess.run([*unshare, "sh", "-c", hide], env=worker_env, check=True, capture_output=True)
        yield {"root": root, "gcs": f"127.0.0.1:{gcs}", "client": f"ray://127.0.0.1:{client}", "env": driver_env}
    finally:
        stop(root)
        shutil.rmtree(root, ignore_errors=True)


def sweep(cluster, spec: dict, name: str, *flags: str, env: dict | None = None, **popen) -> subprocess.Popen:
    path = cluster["root"] / "driver" / f"{name}.yaml"
    path.write_text(yaml.safe_dump(spec), encoding="utf-8")
    command = [sys.executable, "-m", "lerobot_contrast.sweep", str(path), f"--output_dir={path.with_suffix('')}"]
    return subprocess.Popen(
        [*command, *flags], env=env or cluster["env"], cwd=cluster["root"] / "driver", text=True, **popen
    )


def run(cluster, spec: dict, name: str, *flags: str, env: dict | None = None) -> tuple[int, str, float]:
    start = time.monotonic()
    proc = sweep(cluster, spec, name, *flags, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out, err = proc.communicate(timeout=300)
    return proc.returncode, out + err, time.monotonic() - start


def trials(run_dir: Path) -> int:
    journal = run_dir / "journal.jsonl"
    return journal.read_bytes().count(b"\n") if journal.exists() else 0


def cells(out: Path) -> dict[str, dict]:
    return {cell["name"]: cell for cell in json.loads((out / "sweep.json").read_text())["cells"]}


def assert_whole(out: Path, planned: int) -> None:
    for name, cell in cells(out).items():
        assert cell["status"] == "complete", (name, cell["error"])
        assert [r.index for r in read_journal(out / name / "journal.jsonl")] == list(range(planned)), name
        assert json.loads((out / name / "summary.json").read_text())["complete"] is True
        assert {"config.json", "plan.json", "results.parquet"} <= {p.name for p in (out / name).iterdir()}


def test_the_second_node_cannot_import_this_project_but_its_cells_run_there(cluster):
    python = cluster["root"] / "wv" / "bin" / "python"
    for module in OURS:
        found = subprocess.run([python, "-c", f"import {module}"], cwd=cluster["root"] / "wlocal", capture_output=True)
        assert found.returncode != 0 and b"ModuleNotFoundError" in found.stderr, module
    code, output, _ = run(cluster, TINY, "auto", "--ray.address=auto")
    assert code == 0, output
    out = cluster["root"] / "driver" / "auto"
    assert_whole(out, planned=14)
    assert len({cell["node"] for cell in cells(out).values()}) == 1  # the head has no CPU: all on the second node
    # The second node wrote them on its own disk, under the sweep's id, and sent them back.
    local = cluster["root"] / "wtmp" / "lerobot_contrast_sweeps" / (out / MARK).read_text()
    assert sorted(p.name for p in local.iterdir()) == ["seed=0", "seed=1"]
    assert "Token authentication" not in output


def test_a_sweep_through_ray_client_interrupted_mid_way_resumes_with_nothing_lost_or_repeated(cluster):
    out = cluster["root"] / "driver" / "client"
    driver = sweep(cluster, THREE, "client", f"--ray.address={cluster['client']}", stdout=subprocess.DEVNULL)
    deadline = time.monotonic() + 240
    while not (out / "seed=0" / "summary.json").exists():
        assert driver.poll() is None and time.monotonic() < deadline, "the first cell never came back"
        time.sleep(0.1)
    first = (out / "seed=0" / "journal.jsonl").read_bytes()
    running = cluster["root"] / "wtmp" / "lerobot_contrast_sweeps" / (out / MARK).read_text() / "seed=1"
    while not trials(running):  # the second cell begun on the node's own disk
        assert driver.poll() is None and time.monotonic() < deadline, "the second cell never began"
        time.sleep(0.1)
    driver.send_signal(signal.SIGINT)
    assert driver.wait(timeout=60) == 130
    # The trials the node recorded for the running cell, on its own disk: the resumed sweep keeps them.
    begun = (running / "journal.jsonl").read_bytes() if (running / "journal.jsonl").exists() else b""
    code, output, _ = run(cluster, THREE, "client", f"--ray.address={cluster['client']}", "--resume=true")
    assert code == 0, output
    assert_whole(out, planned=28)
    assert (out / "seed=0" / "journal.jsonl").read_bytes() == first  # complete, so not run again
    assert (out / "seed=1" / "journal.jsonl").read_bytes().startswith(begun[: begun.rfind(b"\n") + 1])


def test_a_wrong_address_or_token_is_one_line_in_seconds(cluster):
    closed = free_port()
    no_token = {**cluster["env"], "HOME": str(cluster["root"] / "wlocal")}
    cases = [
        (f"ray://127.0.0.1:{closed}", cluster["env"], "no Ray cluster answers at 127.0.0.1:"),
        (f"127.0.0.1:{closed}", cluster["env"], "start one there with `ray start --head`"),
        ("auto", {**cluster["env"], "RAY_TMPDIR": str(cluster["root"] / "wlocal")}, "no Ray runs on this machine"),
        (cluster["client"], no_token, "the Ray cluster needs a token and this machine has none; "),
        (cluster["gcs"], {**no_token, "RAY_AUTH_TOKEN": "wrong"}, "refused the token from RAY_AUTH_TOKEN"),
    ]
    for number, (address, env, expected) in enumerate(cases):
        code, output, seconds = run(cluster, TINY, f"wrong{number}", f"--ray.address={address}", env=env)
        assert code == 2 and output.startswith(f"error: --ray.address={address}: ") and expected in output, output
        assert output.count("\n") == 1 and seconds < 10, (output, seconds)
        assert "~/.ray/auth_token" in output or "token" not in expected


def test_a_plain_sweep_runs_on_a_ray_of_its_own_beside_a_head_on_this_machine(cluster):
    """No --ray.address is this machine only: the head `ray start --head` left running here (its address in
    RAY_TMPDIR's ray_current_cluster, which a plain ray.init() joins) is neither joined nor disturbed."""
    assert (cluster["root"] / "rt" / "ray" / "ray_current_cluster").exists()
    code, output, _ = run(cluster, TINY, "plain")
    assert code == 0, output
    assert_whole(cluster["root"] / "driver" / "plain", planned=14)
    sweep_id = (cluster["root"] / "driver" / "plain" / MARK).read_text()
    assert not (cluster["root"] / "wtmp" / "lerobot_contrast_sweeps" / sweep_id).exists()  # none ran on its node
