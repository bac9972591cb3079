"""The distributions as a user gets them: wheels built here, installed into a fresh virtual environment without this
repository on its path (LeRobot and the rest from the registry, at the versions this environment holds), and run
from a directory of their own."""

import importlib.metadata
import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

# One worker builds the wheels and the venv once for the whole module (pytest-xdist, --dist loadgroup).
pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("wheels")]

ROOT = Path(__file__).resolve().parents[1]
SIBLINGS = ("protocols", "robots", "teleoperators", "policies", "envs")
DISTRIBUTIONS = [ROOT, *sorted(p.parent for p in ROOT.glob("*/*/pyproject.toml") if p.parts[-3] in SIBLINGS)]
EXTRA_ONLY = ("ray", "accelerate", "wandb", "jax", "mkdocs", "pytest", "mujoco")
# torch, torchvision and the CUDA libraries they bring (4.5 of the core's 6.2 GB) are this environment's own, linked
# rather than installed again: the same builds, minutes less of downloading and unpacking; pip checks all the rest.
LINKED = ("torch", "triton", "nvidia-", "cuda-")


def _run(command: list, timeout: float = 600, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run([str(part) for part in command], capture_output=True, text=True, timeout=timeout, **kwargs)


@pytest.fixture(scope="module")
def wheelhouse(tmp_path_factory) -> Path:
    """A wheel and an sdist of every distribution in the repository, built at once (a wheel from its sdist)."""
    out = tmp_path_factory.mktemp("wheelhouse")
    builds = [
        subprocess.Popen(
            [sys.executable, "-m", "build", "--no-isolation", "--outdir", str(out), str(folder)],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        for folder in DISTRIBUTIONS
    ]
    for folder, build in zip(DISTRIBUTIONS, builds, strict=True):
        log = build.communicate(timeout=600)[0]
        assert build.returncode == 0, f"{folder}: {log[-2000:]}"
    return out


@pytest.fixture(scope="module")
def core(tmp_path_factory, wheelhouse) -> dict:
    """A fresh venv holding `lerobot_contrast` and no extra, and the environment to run its commands in."""
    venv = tmp_path_factory.mktemp("core") / "venv"
    _run([sys.executable, "-m", "venv", venv]).check_returncode()
    _link_torch(venv)
    pins = venv.parent / "pins.txt"  # the versions this environment holds, as scripts/setup.sh --dev pins them
    frozen = _run([sys.executable, "-m", "pip", "freeze", "--exclude-editable"]).stdout.splitlines()
    pins.write_text("\n".join(line for line in frozen if " @ " not in line) + "\n")
    install = [venv / "bin/python", "-m", "pip", "install", "--disable-pip-version-check", "--no-compile", "-c", pins]
    # The core as the README installs it: every distribution but the demonstrator, which needs the [twin] extra.
    wheels = [wheel for wheel in sorted(wheelhouse.glob("*.whl")) if not wheel.name.startswith("lerobot_teleoperator")]
    done = _run([*install, "--find-links", wheelhouse, *wheels], timeout=1800)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    home = venv.parent / "home"
    env = {key: value for key, value in os.environ.items() if key not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env |= {"PATH": f"{venv / 'bin'}{os.pathsep}{env['PATH']}", "HF_HUB_OFFLINE": "1", "HF_HOME": str(home)}
    return {"bin": venv / "bin", "env": env, "cwd": home.parent}


def _link_torch(venv: Path) -> None:
    """Put this environment's torch (and what LINKED names) on the venv's path through a folder of links to it."""
    linked = venv / "linked"
    linked.mkdir()
    for dist in importlib.metadata.distributions():
        if dist.metadata["Name"].lower().startswith(LINKED):
            for top in {Path(file).parts[0] for file in dist.files or () if not str(file).startswith("..")}:
                if not (linked / top).exists():
                    (linked / top).symlink_to(Path(dist.locate_file(top)))
    (next(venv.glob("lib/python*/site-packages")) / "linked.pth").write_text(f"{linked}\n")


def test_every_distribution_builds_with_its_package_data_and_passes_twine_check(wheelhouse):
    wheels = sorted(wheelhouse.glob("*.whl"))
    assert len(wheels) == len(DISTRIBUTIONS) == len(list(wheelhouse.glob("*.tar.gz")))
    for folder in DISTRIBUTIONS:
        package = folder / ("lerobot_contrast" if folder == ROOT else folder.name)
        data = {
            path.relative_to(package.parent).as_posix()
            for path in package.rglob("*")
            if path.is_file() and path.suffix not in (".py", ".pyc")
        }
        wheel = next(w for w in wheels if w.name.startswith(f"{package.name}-"))
        assert data - set(zipfile.ZipFile(wheel).namelist()) == set(), wheel.name
    check = _run([sys.executable, "-m", "twine", "check", "--strict", *sorted(wheelhouse.iterdir())])
    assert check.returncode == 0, check.stdout + check.stderr


def test_the_core_install_finds_its_plugins_and_holds_no_extra(core):
    code = (
        "import json, importlib.util, lerobot_contrast, lerobot_policy_tabletop_pointer as pointer\n"
        "from lerobot.utils.import_utils import register_third_party_plugins\n"
        "from lerobot.envs.configs import EnvConfig\n"
        "from lerobot.configs.policies import PreTrainedConfig\n"
        "from lerobot.robots import RobotConfig\n"
        "register_third_party_plugins()\n"
        "print(json.dumps({'version': lerobot_contrast.__version__, 'package': lerobot_contrast.__file__,\n"
        "    'weights': str(pointer.WEIGHTS), 'env': 'language_table' in EnvConfig.get_known_choices(),\n"
        "    'policy': 'tabletop_pointer' in PreTrainedConfig.get_known_choices(),\n"
        f"    'robot': 'locobot' in RobotConfig.get_known_choices(), 'extras': [m for m in {EXTRA_ONLY!r}\n"
        "    if importlib.util.find_spec(m)]}))\n"
    )
    done = _run([core["bin"] / "python", "-c", code], env=core["env"], cwd=core["cwd"])
    assert done.returncode == 0, done.stderr[-3000:]
    found = json.loads(done.stdout.splitlines()[-1])
    venv = str(core["bin"].parent)
    assert found["package"].startswith(venv) and found["weights"].startswith(venv)
    here = _run([sys.executable, "-c", "import lerobot_contrast as m; print(m.__version__)"]).stdout.strip()
    assert found["version"] == here
    assert (found["env"], found["policy"], found["robot"]) == (True, True, True)
    assert found["extras"] == []


def test_sweep_without_its_extra_names_the_extra_in_one_line(core, tmp_path):
    done = _run([core["bin"] / "lerobot-contrast-sweep", tmp_path / "study.yaml"], env=core["env"], cwd=core["cwd"])
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.strip().splitlines() == [
        "error: python -m lerobot_contrast.sweep needs the [sweep] extra (ray not installed): "
        "pip install 'lerobot_contrast[sweep]'"
    ]


def test_the_default_evaluation_its_report_and_lerobot_eval_run_on_the_installed_wheels(core, tmp_path):
    run = tmp_path / "run"
    evaluate = ["--n_instances=2", "--max_episode_steps=20", f"--output_dir={run}"]
    done = _run([core["bin"] / "lerobot-contrast-eval", *evaluate], env=core["env"], cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "original" in done.stdout and (run / "results.parquet").is_file()
    done = _run([core["bin"] / "lerobot-contrast-report", run], env=core["env"], cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    assert (run / "report" / "report.md").is_file()
    weights = _run(
        [core["bin"] / "python", "-c", "import lerobot_policy_tabletop_pointer as p; print(p.WEIGHTS)"],
        env=core["env"],
        cwd=tmp_path,
    ).stdout.strip()
    lerobot_eval = [
        core["bin"] / "lerobot-eval", "--env.type=language_table", "--env.episode_length=20", f"--policy.path={weights}",
        "--policy.device=cpu", "--eval.n_episodes=2", "--eval.batch_size=1", f"--output_dir={tmp_path / 'lerobot'}",
    ]  # fmt: skip
    done = _run(lerobot_eval, env=core["env"], cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    info = json.loads((tmp_path / "lerobot" / "eval_info.json").read_text())
    assert info["overall"]["n_episodes"] == 2
