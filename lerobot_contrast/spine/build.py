"""Build a run's parts from its config: the robot, the operator console and the episode observers."""

from __future__ import annotations

import importlib
import pkgutil
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from lerobot_contrast.contrast.staging import reports_scene
from lerobot_contrast.contrast.task import Task
from lerobot_contrast.operators.base import Operator
from lerobot_contrast.operators.channel import Channel
from lerobot_contrast.operators.console import Answers, OperatorConsole
from lerobot_contrast.operators.person_args import PersonArgs
from lerobot_contrast.policies import policy_entry
from lerobot_contrast.record.observer import EpisodeObserver
from lerobot_contrast.spine.config import ConfigError, EvalConfig

if TYPE_CHECKING:
    from lerobot.robots import Robot

# The robot each task runs on when no --robot is given: an in-process simulator.
TASK_ROBOTS = {
    "language_table": "language_table_sim",
    "vln": "vln_sim",
    "vln_paper": "vln_sim",
    **dict.fromkeys(("libero_spatial", "libero_object", "libero_goal", "libero_10"), "libero_sim"),
}
OPERATORS = ("auto", "console", "arm")
DEFAULT_HARDWARE_FPS = 10.0


def register_robots() -> dict[str, str]:
    """Make every robot type known before parsing: LeRobot's own robots and cameras, its plugins and this
    package's simulated robots. Returns the built-in packages that could not be imported here, with why."""
    from lerobot.utils.import_utils import register_third_party_plugins

    import lerobot_contrast.domains.language_table.config_language_table_sim  # noqa: F401
    import lerobot_contrast.domains.libero.config_libero_sim  # noqa: F401
    import lerobot_contrast.domains.vln.config_vln_sim  # noqa: F401

    unavailable = {}
    for family in ("lerobot.robots", "lerobot.cameras"):
        for module in pkgutil.iter_modules(importlib.import_module(family).__path__):
            if module.ispkg:
                try:
                    importlib.import_module(f"{family}.{module.name}")
                except ImportError as error:  # a robot whose optional SDK is not installed
                    unavailable[module.name] = str(error)
    register_third_party_plugins()
    return unavailable


def check_robot_type(argv: list[str], unavailable: dict[str, str]) -> None:
    """Name the known robot types when --robot.type is not one of them, instead of argparse's usage dump."""
    from lerobot.robots import RobotConfig

    given = [arg.split("=", 1)[1] for arg in argv if arg.startswith("--robot.type=")]
    known = sorted(RobotConfig.get_known_choices())
    for robot_type in given:
        if robot_type not in known:
            missing = "".join(f"; {name} could not be imported ({why})" for name, why in unavailable.items())
            raise ConfigError(
                f"--robot.type={robot_type} is not a known robot; known: {', '.join(known)}. A plugin robot "
                f"needs its package installed (pip install lerobot_robot_{robot_type}){missing}"
            )


def needs_camera(cfg: EvalConfig) -> bool:
    """Scripted policies read the scene, not images: render only for a learned policy or a recording."""
    return policy_entry(cfg.policy, cfg.task).reads_images or cfg.rerun or cfg.record_dataset


def choose_robot(cfg: EvalConfig) -> None:
    """Fill in the task's own robot when --robot is not given, so the run's config.json names it."""
    from lerobot.robots import RobotConfig

    if cfg.robot is not None:
        return
    if cfg.task not in TASK_ROBOTS:
        raise ConfigError(f"--task={cfg.task} has no simulator; name your robot with --robot.type=...")
    robot_class = RobotConfig.get_choice_class(TASK_ROBOTS[cfg.task])
    cfg.robot = robot_class(camera=needs_camera(cfg))


def make_robot(cfg: EvalConfig, chosen: str | None = None) -> Any:
    """The robot of cfg.robot; `chosen`: the --robot.type given, which errors name (one config class may serve
    several types, e.g. so100_follower and so101_follower, and knows only its first name)."""
    from lerobot.robots import make_robot_from_config

    choose_robot(cfg)
    try:
        return make_robot_from_config(cfg.robot)
    except Exception as error:
        raise ConfigError(
            f"--robot.type={chosen or cfg.robot.type}: cannot build the robot ({' '.join(str(error).split())})"
        ) from None


def make_observers(cfg: EvalConfig, task: Task, robot: Robot, run_dir: Path) -> list[EpisodeObserver]:
    observers: list[EpisodeObserver] = []
    if cfg.rerun:
        from lerobot_contrast.record.rerun_log import RerunEpisodeRecorder

        observers.append(RerunEpisodeRecorder(run_dir, task=task))
    if cfg.record_dataset:
        from lerobot_contrast.record.dataset import DatasetRecorder

        fps = round(cfg.fps or DEFAULT_HARDWARE_FPS)  # a simulator's control rate, however fast it is stepped
        observers.append(DatasetRecorder(run_dir, fps=fps, robot_type=robot.name))
    return observers


def make_operator(cfg: EvalConfig, robot: Robot, task: Task, unit: str) -> Operator | None:
    """Who stages and labels each trial: the person at the console, the arm with its camera (--operator=arm), or
    None where the robot does it in software (--operator=auto)."""
    scene_io = reports_scene(robot, task.storage_scene().objects)
    mode = cfg.operator or ("auto" if scene_io else "console")
    if mode == "auto" and not scene_io:
        raise ConfigError(
            f"--operator=auto needs a robot that reports and stages this task's scene; {robot.name} cannot, "
            "so use --operator=console"
        )
    if cfg.cost in ("robot_time", "interventions") and mode != "arm":
        raise ConfigError(f"--cost={cfg.cost} counts what the arm's own staging spends: it needs --operator=arm")
    if mode == "auto" and (cfg.person.page or cfg.person.notify):
        raise ConfigError(
            "--person.page and --person.notify reach the person who stages: they need --operator=console or arm"
        )
    if not 0 <= cfg.person.port <= 65535:
        raise ConfigError(f"--person.port must be from 0 to 65535, got {cfg.person.port}")
    if mode == "auto":
        if cfg.cost == "measured":
            raise ConfigError("--cost=measured needs --operator=console: it is what a camera measured of the staging")
        return None
    from lerobot_contrast.staging.setup import make_bench

    # The run directory is chosen after the console is built; the bench reads it when it first keeps a measurement.
    run_dir = lambda: cfg.output_dir  # noqa: E731
    bench = make_bench(cfg.staging, cfg.task, task, robot, cfg.cost, run_dir)
    answers = Answers(sys.stdin)
    channels = [] if cfg.operator_channel is None else [Channel(cfg.operator_channel)]
    console = OperatorConsole(answers, unit=unit, bench=bench, channels=channels)
    console.channels += person_channels(cfg.person, answers, console.say, run_dir, bench)
    if mode == "console":
        return console
    from lerobot_contrast.operators.arm.setup import arm_operator

    return arm_operator(cfg.arm, robot, task, bench, console, run_dir, cfg.seed)


def person_channels(args: PersonArgs, answers: Answers, say, run_dir, bench) -> list[Any]:
    """The person's page and notifications (--person.*), where asked for; the page's link printed, with its QR code
    where it serves the local network. The page shows `bench`'s overlay where it draws one (a calibrated camera)."""
    out: list[Any] = []
    told = None  # the page's link in messages: without its token, which would pass through the service's hands
    if args.page:
        from lerobot_contrast.operators.person_page import PersonPage

        pictured = hasattr(bench, "wants_picture")
        if pictured:
            bench.wants_picture = True
        page = PersonPage(
            args.port, args.lan, answers, run_dir, (lambda: bench.picture) if pictured else (lambda: None)
        )
        answers.taken.append(page.answered_elsewhere)
        link, told = page.link(), page.link(token=False)
        print(f"the person's page: {link}", flush=True)
        if args.lan:
            import segno

            segno.make(link, error="m").terminal(compact=True)
        out.append(page)
    if args.notify is not None:
        from lerobot_contrast.operators.notify import Notifier

        out.append(Notifier(args.notify, args.notify_format, say, told))
    return out


def run_fps(cfg: EvalConfig, robot: Robot) -> float | None:
    """Simulated robots step as fast as they can unless asked for a rate; hardware runs at a fixed one."""
    if cfg.fps is not None:
        return cfg.fps
    return None if getattr(robot, "simulated", False) else DEFAULT_HARDWARE_FPS
