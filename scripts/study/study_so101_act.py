"""The contrast-set study of an ACT checkpoint on the virtual SO-101, run as a user runs it on the arm: LeRobot's
`so101_follower` driver and `zmq` camera against the twin, the operator console answered by the scripted operator,
the task `so101_red_left` (bases: "put the red cube in the left bin" in new placements; every perturbation). The
scripted demonstrator, which reads the words, runs the same plan as the reference. Each run resumes where a kill
left it; the report compares the two.

    python scripts/study/study_so101_act.py --checkpoint=DIR --output=DIR [--n_instances=30] [--max_episode_s=12]
        [--policies=act,demonstrator] [--compare=DIR --policies=ab] [--placement_error=none]
        [--width=160 --height=120] [--clock=sim|wall]

With `--policies=ab`, --checkpoint and --compare (a second ACT: more data, or trained longer) run one interleaved
session (`--policies=A,B` of the evaluator) on the same bases, stopped as soon as the sequential test tells them
apart (`--stop.decided=true`); its report says after how many bases.

Each run's console and scripted operator are kept in OUTPUT/POLICY.log; `report/where_it_ended.md` then says, per
perturbation, where each policy left the recorded task's cube (from the operator's view of the twin's true scene):
what a policy that cannot read keys on.

The twin's camera renders at the checkpoint's own frame size (what the policy was recorded with); without ACT,
at --width x --height. The report covers every policy's run in the folder, so the two runs may be made apart.
The twin runs on its simulated clock by default (as fast as the machine allows, the same under load); `--clock=wall`
rehearses in real time. Prints `runs=.. trials=.. wall_s=.. clock=.. report=..` last."""

from __future__ import annotations

import argparse
import json
import os
import shlex
import subprocess
import sys
import time
from pathlib import Path

from lerobot_contrast.spine.flags import ScriptParser

POLICIES = ("act", "demonstrator", "ab")


def frame_size(checkpoint: Path) -> tuple[int, int]:
    """The checkpoint's camera frame (width, height), from its config's visual input."""
    features = json.loads((checkpoint / "config.json").read_text())["input_features"]
    visual = [f["shape"] for f in features.values() if f["type"] == "VISUAL"]
    if len(visual) != 1:
        raise SystemExit(f"error: --checkpoint={checkpoint}: expected one camera input, found {len(visual)}")
    _, height, width = visual[0]
    return width, height


def eval_command(args: argparse.Namespace, twin, policy: str, run_dir: Path) -> list[str]:
    chosen = {
        "act": [f"--policy.path={args.checkpoint}", "--policy.device=cpu"],
        "demonstrator": ["--policy.type=so101_demonstrator", f"--policy.options={{placement: {twin.placement}}}"],
        "ab": [f"--policies={args.checkpoint}:device=cpu,{args.compare}:device=cpu", "--stop.decided=true"],
    }[policy]
    if started(run_dir):  # a killed run: the evaluator's own resume, on this twin's new ports
        new_port = chosen if policy == "demonstrator" else []  # its placement socket moved with the twin
        flags = ["--resume=true", f"--output_dir={run_dir}", *shlex.split(twin.robot_flags), *new_port]
    else:
        flags = [*shlex.split(twin.robot_flags), *chosen, "--task=so101_red_left", "--strategy=contrast",
                 f"--n_instances={args.n_instances}", f"--max_episode_s={args.max_episode_s}", "--fps=30",
                 f"--max_episode_steps={round(args.max_episode_s * 30)}",
                 "--staging.viewer=none", f"--seed={args.seed}", f"--output_dir={run_dir}"]  # fmt: skip
    return [sys.executable, "-m", "lerobot_contrast.twin.operator", f"--placement={twin.placement}",
            f"--placement_error={args.placement_error}", *flags]  # fmt: skip


def run_logged(command: list[str], log: Path) -> int:
    """Run `command`, its output shown and appended line by line to `log` (a resumed run's lines follow the
    killed one's)."""
    log.parent.mkdir(parents=True, exist_ok=True)
    with (
        log.open("a", buffering=1) as kept,
        subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) as child,
    ):
        for line in child.stdout:
            sys.stdout.write(line)
            kept.write(line)
        return child.wait()


def write_fates(output: Path, runs: list[Path], report: Path) -> None:
    """report/where_it_ended.md: per policy and perturbation, where the recorded task's cube ended."""
    from lerobot_contrast.domains.task_file import load_task_file
    from lerobot_contrast.twin.fates import fates, fates_markdown

    spec = load_task_file("so101_red_left").spec
    subject, regions = spec.base_slots["block"], list(spec.templates["place"].slots["bin"].candidates)
    parts = [f"# Where each policy left the {subject}\n"]
    for run_dir in runs:
        if (output / f"{run_dir.name}.log").is_file():
            table = fates(run_dir, output / f"{run_dir.name}.log", spec, subject)
            parts.append(f"## {run_dir.name}\n\n{fates_markdown(table, subject, regions)}")
    (report / "where_it_ended.md").write_text("\n".join(parts), encoding="utf-8")


def started(run_dir: Path) -> bool:
    """Whether the run (or the interleaved session) was begun, and so is resumed."""
    return (run_dir / "config.json").is_file() or (run_dir / "pairs.json").is_file()


def trials(run_dir: Path) -> int:
    """Episodes the run recorded (an interleaved session: every policy's)."""
    return sum(len(journal.read_text().splitlines()) for journal in run_dir.glob("**/journal.jsonl"))


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = ScriptParser(description=__doc__.splitlines()[0])
    parser.add_argument("--checkpoint", type=Path, help="ACT's pretrained_model directory (for --policies=act)")
    parser.add_argument("--compare", type=Path, help="a second ACT checkpoint, against --checkpoint (--policies=ab)")
    parser.add_argument("--output", type=Path, required=True, help="the study's folder: one run per policy")
    parser.add_argument("--n_instances", type=int, default=30, help="bases (each with its perturbations)")
    parser.add_argument("--max_episode_s", type=float, default=12.0, help="as long as a recorded episode")
    parser.add_argument("--policies", default="act,demonstrator",
                        help="which of act, demonstrator and ab (--checkpoint against --compare, interleaved) to run")  # fmt: skip
    parser.add_argument("--placement_error", default="none", help="the scripted operator's: none or normal:SIGMA")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--clock", choices=("sim", "wall"), default="sim",
                        help="the twin's clock: sim (as fast as the machine allows, the same under load) or wall")  # fmt: skip
    parser.add_argument("--width", type=int, default=160, help="the camera's frame without a checkpoint")
    parser.add_argument("--height", type=int, default=120)
    args = parser.parse_args(argv)
    args.policies = [p for p in args.policies.split(",") if p]
    unknown = sorted(set(args.policies) - set(POLICIES))
    if unknown or not args.policies:
        parser.error(f"--policies: {','.join(unknown) or 'none given'}; choose from {','.join(POLICIES)}")
    if args.n_instances < 1 or args.max_episode_s <= 0:
        parser.error("--n_instances must be at least 1 and --max_episode_s above 0")
    needs = {"checkpoint": {"act", "ab"}, "compare": {"ab"}}
    for flag, policies in needs.items():
        path, needed = getattr(args, flag), sorted(policies & set(args.policies))
        if needed and path is None:
            parser.error(f"--policies={needed[0]} needs --{flag}: lerobot-train's pretrained_model directory")
        if needed and not (path / "config.json").is_file():
            parser.error(f"--{flag}={path} holds no config.json; give lerobot-train's pretrained_model")
        if path is not None:  # lerobot-train's `last` moves on as training goes on: the run names the step
            setattr(args, flag, path.resolve())
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    os.environ.setdefault("HF_HUB_OFFLINE", "1")
    from lerobot_contrast.contrast.errors import UserError
    from lerobot_contrast.domains.task_file import load_task_file
    from lerobot_contrast.so101.scene import start_poses
    from lerobot_contrast.twin.launch import running_twin
    from lerobot_contrast.twin.placement_client import PlacementClient

    width, height = (args.width, args.height) if args.checkpoint is None else frame_size(args.checkpoint)
    began = time.monotonic()
    runs = [args.output / policy for policy in args.policies]
    flags = ["--task=so101_red_left", f"--seed={args.seed}", "--fps=30", f"--width={width}", f"--height={height}",
             f"--clock={args.clock}"]  # fmt: skip
    try:
        with running_twin(*flags) as twin:
            placement, storage = (
                PlacementClient(twin.placement),
                start_poses(load_task_file("so101_red_left").spec, None),
            )
            for policy, run_dir in zip(args.policies, runs, strict=True):
                if not started(run_dir):  # the objects wait in their storage row, where a new run's plan starts
                    for name, pose in storage.items():
                        placement.place(name, pose.x, pose.y)
                status = run_logged(eval_command(args, twin, policy, run_dir), args.output / f"{policy}.log")
                if status != 0:
                    print(f"error: the {policy} run stopped ({status}); run the same command again to resume",
                          file=sys.stderr)  # fmt: skip
                    return 1
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    report = args.output / "report"
    every = [args.output / p for p in ("act", "demonstrator") if (args.output / p / "journal.jsonl").is_file()]
    if every:
        subprocess.run([sys.executable, "-m", "lerobot_contrast.report", *map(str, every), f"--output_dir={report}"],
                       check=True)  # fmt: skip
        write_fates(args.output, every, report)
    if "ab" in args.policies:  # the interleaved session's own report: the paired comparison and when it was decided
        subprocess.run([sys.executable, "-m", "lerobot_contrast.report", str(args.output / "ab")], check=True)
    print(f"runs={len(runs)} trials={sum(trials(r) for r in runs)} wall_s={time.monotonic() - began:.0f} "
          f"clock={args.clock} report={report / 'report.md'}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
