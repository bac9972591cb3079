"""Unattended sessions on the twin: the arm stages every trial and the camera labels it (`--operator=arm`), judged
against the twin's truth. Starts its own twin (640x480, wide-angle lens), lays the printed board and calibrates the
camera as a person would once, takes the board away, then runs a contrast set with the arm as operator; the scripted
person answers only when the arm rings for one. The twin's truth is read here, by the judge, never by the arm.

    .venv/bin/python scripts/bench/bench_unattended.py --bases=N [--joint_offset_deg=D] [--task=so101_blocks]
        [--perturbations=L,SB] [--seed=0] [--work=DIR]

Prints the confusion table of the camera's labels against the truth, then on its last line: unattended_share=...
placement_median_cm=... placement_p95_cm=... label_agreement=... person_calls=... staging_s_per_trial=...
trials_per_hour=...
"""

from __future__ import annotations

import json
import shlex
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.spine.flags import ScriptParser
from lerobot_contrast.twin.console_session import run_answered
from lerobot_contrast.twin.launch import running_twin
from lerobot_contrast.twin.operator import Operator, OperatorError, PlacementError, Plan
from lerobot_contrast.twin.placement_client import PlacementClient
from lerobot_contrast.twin.table_calibration import calibrate_table

RESUMES = 3


class Judge(Operator):
    """The scripted person (called only by the arm's bell) and the judge: where the arm put each object when the
    episode starts, and the true outcome when the camera labels, both from the twin's truth."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.placement_m: list[float] = []
        self.labels: dict[int, tuple[bool, bool, bool]] = {}  # trial -> (camera's label, truth, camera sure)
        self.person: Counter = Counter()  # trial -> times a person was needed (calls and labels asked)

    def handle(self, message: dict) -> str | None:
        kind = message.get("prompt") or message.get("event")
        if kind == "trial":
            self.index, self.instruction = message["trial"], message["instruction"]
        if kind in ("call", "label"):
            self.person[message["trial"]] += 1
        if kind == "running":
            self._placed()
        if kind == "labelled":
            self.index, self.instruction = message["trial"], message["instruction"]
            self._judged(message["success"], message["sure"])
        return super().handle(message)

    def _placed(self) -> None:
        instance = self.plan.instances.get(self.index)
        truth, self.resting = self.placement.look()  # heights as staged: a cube lifted later is held
        for name, target in ({} if instance is None else instance.scene.objects).items():
            if name in truth.objects and self.plan.task.spec.workspace.area.contains(target.x, target.y):
                self.placement_m.append(truth.objects[name].distance_to(target))
                self.said.append(f"judge: {name} {self.placement_m[-1] * 100:.1f} cm from its target (truth)")

    def _judged(self, success: bool, sure: bool) -> None:
        scene, heights = self.placement.look()
        lifted = {name for name, z in heights.items() if z - self.resting.get(name, z) > 0.02}
        self.labels[self.index] = (success, self.plan.judge(self.index, self.instruction, scene, lifted), sure)


def complete(run_dir: Path) -> bool:
    summary = run_dir / "summary.json"
    return summary.is_file() and bool(json.loads(summary.read_text()).get("complete"))


def figures(judge: Judge, run_dir: Path, hours: float) -> dict[str, str]:
    journal = run_dir / "journal.jsonl"
    if not journal.is_file():
        raise UserError(f"the evaluation on the twin did not run (no {journal}); see the log above")
    records = [json.loads(line) for line in journal.read_text().splitlines()]
    done = [r for r in records if r["status"] == "done"]
    if not done:
        raise UserError(f"no trial finished in {run_dir}; see the log above")
    alone = [r for r in done if not judge.person[r["index"]]]
    agree = [judge.labels[r["index"]][0] == judge.labels[r["index"]][1] for r in done if r["index"] in judge.labels]
    staging = [r["extra"].get("robot_s", 0.0) for r in done]
    placed = np.array(judge.placement_m) * 100 if judge.placement_m else np.array([np.nan])
    return {
        "unattended_share": f"{len(alone) / len(done):.3f}",
        "placement_median_cm": f"{np.median(placed):.2f}",
        "placement_p95_cm": f"{np.percentile(placed, 95):.2f}",
        "label_agreement": f"{np.mean(agree):.3f}" if agree else "nan",
        "person_calls": str(sum(judge.person.values())),
        "staging_s_per_trial": f"{np.mean(staging):.1f}",
        "trials_per_hour": f"{len(done) / hours:.1f}",
    }


def confusion(judge: Judge) -> str:
    table = Counter((camera, truth) for camera, truth, _ in judge.labels.values())
    rows = [f"{'':>16} truth success  truth failure"]
    for said in (True, False):
        rows.append(
            f"camera {'success' if said else 'failure':>8} {table[(said, True)]:>13} {table[(said, False)]:>14}"
        )
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    parser = ScriptParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bases", type=int, default=30, help="base instances of the contrast set")
    parser.add_argument("--joint_offset_deg", type=float, default=0.0, help="each joint's calibration off by up to D")
    parser.add_argument("--task", default="so101_blocks")
    parser.add_argument("--perturbations", default=None, help="the perturbations applied (default: the task's)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--work", type=Path, default=None, help="where the run directory goes (default: a temporary one)"
    )
    args = parser.parse_args(argv)
    if args.bases < 1 or not 0 <= args.joint_offset_deg <= 10:
        parser.error("--bases must be at least 1 and --joint_offset_deg within 0-10")
    work = args.work or Path(tempfile.mkdtemp(prefix="bench_unattended_"))
    try:
        with running_twin(f"--task={args.task}", f"--joint_offset_deg={args.joint_offset_deg}",
                          f"--seed={args.seed}") as twin:  # fmt: skip
            table = calibrate_table(twin, args.task, work / "table.calibration.json")
            run_dir = work / "run"
            eval_argv = [f"--task={args.task}", *shlex.split(twin.robot_flags), "--operator=arm",
                         "--policy.type=so101_demonstrator", f"--policy.options={{placement: {twin.placement}}}",
                         "--strategy=contrast", f"--n_instances={args.bases}", "--fps=30", "--max_episode_s=20",
                         f"--staging.calibration={table}", "--staging.viewer=none", "--rerun=false",
                         f"--seed={args.seed}", f"--output_dir={run_dir}"]  # fmt: skip
            if args.perturbations:
                eval_argv.append(f"--perturbations={args.perturbations}")
            judge = Judge(Plan(eval_argv), PlacementClient(twin.placement), PlacementError(), args.seed, "accept")
            started = time.monotonic()
            code = run_answered(eval_argv, judge, (OperatorError,))
            for _ in range(RESUMES):  # a bus that stops answering on a loaded machine ends the session resumably
                if complete(run_dir):
                    break
                print(f"bench_unattended: the session stopped early; resuming {run_dir}", flush=True)
                code = run_answered([*eval_argv, "--resume=true"], judge, (OperatorError,))
            hours = (time.monotonic() - started) / 3600
        said = figures(judge, run_dir, hours)
    except (UserError, OperatorError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    print(confusion(judge))
    trials = len(judge.labels)
    print(f"eval exit {code}; bases={args.bases} trials labelled={trials} joint_offset_deg={args.joint_offset_deg:g} "
          f"run: {run_dir}")  # fmt: skip
    print(" ".join(f"{key}={value}" for key, value in said.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
