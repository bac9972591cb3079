"""Bad input on LIBERO: each answered by one line naming what is wrong and the command that fixes it, never a
question on standard input and never a traceback."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from lerobot_contrast.domains.libero import assets, runtime


def _eval(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "lerobot_contrast.eval", *args, "--dry_run=true"],
        capture_output=True, text=True, timeout=600, stdin=subprocess.DEVNULL, env={**os.environ, **(env or {})},
    )  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["--task=libero_object", "--families=task12"], "--families: libero_object has no task 'task12'"),
        (["--task=libero_90"], "--task: unknown task 'libero_90'; choose from: "),
    ],
)
def test_an_unknown_suite_or_task_id_is_one_line(args, expected, capsys):
    pytest.importorskip("libero", reason="LIBERO is installed by the test set-up: bash scripts/setup.sh --dev")
    from lerobot_contrast.eval import main

    assert main([*args, "--dry_run=true"]) != 0
    out, err = capsys.readouterr()
    assert expected in err and "Traceback" not in out + err
    assert len([line for line in err.splitlines() if expected in line]) == 1


@pytest.mark.slow
def test_no_rendering_backend_is_one_line_naming_what_to_install():
    pytest.importorskip("libero", reason="LIBERO is installed by the test set-up: bash scripts/setup.sh --dev")
    result = _eval("--task=libero_goal", env={"MUJOCO_GL": "nonesuch"})
    expected = "no rendering backend: MUJOCO_GL=nonesuch"
    assert result.returncode != 0 and "apt-get install" in result.stderr
    # LeRobot imports every installed plugin at start and logs the traceback of each that fails to import (the twin's,
    # lerobot_env_so101 and lerobot_teleoperator_so101_demo, load MuJoCo too); after LeRobot's reports, none.
    theirs, _, ours = result.stderr.partition("\nerror: ")
    assert expected in ours and "Traceback" not in ours + result.stdout
    assert theirs.count("Traceback") == theirs.count("Could not import third-party plugin: ")
    assert len([line for line in result.stderr.splitlines() if expected in line]) == 1


def test_libero_missing_names_the_install_command(monkeypatch):
    monkeypatch.setattr(runtime.importlib.util, "find_spec", lambda name: None)
    with pytest.raises(runtime.LiberoMissingError, match=r"LIBERO is not installed; install it with: pip install"):
        runtime.load.__wrapped__()


def test_a_missing_or_altered_asset_is_named_with_the_reinstall_command(tmp_path, monkeypatch):
    folder = tmp_path / "assets"
    (folder / "scenes").mkdir(parents=True)
    (folder / "scenes" / "a.xml").write_text("<mujoco/>")
    (folder / "b.png").write_bytes(b"png")
    monkeypatch.setattr(assets, "HASH_LIST", tmp_path / "assets.sha256")
    assert assets.write_hash_list(folder) == 2
    assets.check(folder, full=True)
    (folder / "scenes" / "a.xml").write_text("<mujoco_>")  # same size, other bytes: only the hash tells
    assets.check(folder, full=False)
    with pytest.raises(assets.AssetError, match=r"LIBERO asset altered .*a\.xml; reinstall: bash scripts/setup.sh"):
        assets.check(folder, full=True)
    (folder / "b.png").unlink()
    with pytest.raises(assets.AssetError, match=r"LIBERO asset missing: .*b\.png; reinstall the assets"):
        assets.check(folder, full=False)
