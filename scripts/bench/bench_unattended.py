"""Unattended sessions on the twin: the arm stages every trial and the camera labels it (`--operator=arm`), judged
against the twin's truth. Starts its own twin (640x480, wide-angle lens), lays the printed board and calibrates the
camera as a person would once, takes the board away, then runs a contrast set with the arm as operator; the scripted
person answers only when the arm rings for one. With `--operator=console` the same bases run with no arm: the
scripted person stages every trial and labels it, as the comparison. The twin's truth is read here, by the judge,
never by the arm; the judge takes each trial's instance and targets from what the evaluator says it runs (the
console's channel), and the truth of an outcome from the moment the episode ended, before the arm lets go.

    .venv/bin/python scripts/bench/bench_unattended.py [--bases=3] [--joint_offset_deg=D] [--task=so101_blocks]
        [--perturbations=L,SB] [--episode_s=S] [--seed=0] [--clock=sim|wall] [--operator=arm|console] [--work=DIR]

`--work=DIR` keeps the run and the judge's records there: run again with the same DIR to resume a session that
stopped (a kill, a bus that stopped answering), the figures counting every trial once. Prints the confusion table
of the camera's labels against the truth, then on its last line: unattended_share=... labelled_by_camera=...
label_agreement=... placement_median_cm=... placement_p95_cm=... camera_error_p95_cm=... person_calls=...
staging_s_per_trial=... person_s_per_trial=... trials_per_hour=... trials=... operator=... clock=... session_s=...
wall_s=... (person_s_per_trial: a person's seconds, from the task's reset-time model (its handling time per object
moved, plus the distance at its hand speed; a label a person gives counts one handling time); trials per hour: of
the twin's time from the first trial's staging to the last label, resumes included (the bench's hours on the wall
clock, the robot's on the simulated one), plus the person's modelled seconds; session_s: this machine's seconds for
the evaluation's runs, resumes included; wall_s: for the whole benchmark, the twin's start and the camera's
calibration too)
"""

from __future__ import annotations

import json
import math
import shlex
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.so101 import DEFAULT_PACE, PICK_AND_PLACE_S
from lerobot_contrast.spine.flags import ScriptParser
from lerobot_contrast.twin.console_session import run_answered
from lerobot_contrast.twin.launch import running_twin
from lerobot_contrast.twin.operator import Operator, OperatorError, PlacementError, Plan, held
from lerobot_contrast.twin.placement_client import PlacementClient
from lerobot_contrast.twin.table_calibration import calibrate_table

RESUMES = 3
FPS = 30
# The demonstrator's pick and place takes PICK_AND_PLACE_S at its pace; a second more lets it put the cube down
# and withdraw before the episode ends.
EPISODE_S = PICK_AND_PLACE_S * DEFAULT_PACE + 1.0


class Judge(Operator):
    """The scripted person (called only by the arm's bell) and the judge: where the arm put each object when the
    episode starts and where the camera saw it, and the true outcome when the episode ended, from the twin's truth.
    Every judgement is appended to `records` (JSON lines), and those already there are read back on a resume."""

    def __init__(self, *args, records: Path, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.records = records
        self.placement_m: dict[tuple[int, str], float] = {}  # (trial, object) -> metres from its target (truth)
        self.staged: dict[int, dict[str, list[float]]] = {}  # trial -> each object's true (x, y) when it ran
        self.labels: dict[int, tuple[bool, bool, bool]] = {}  # trial -> (camera's label, truth, camera sure)
        self.person: Counter = Counter()  # trial -> times a person was needed (calls and labels asked)
        self.calls: Counter = Counter()  # trial -> times the arm called a person to the bench while staging
        self.person_s: Counter = Counter()  # trial -> a person's seconds, from the task's reset-time model
        self.reset_model = self.plan.task.cost_model("reset_time")
        self.truth_at_end: tuple = (None, set())
        self._ended = self._labelled = None  # the trial whose end was read, and whose label kept
        # The twin's seconds of every labelled trial, from the one before it (or the session's start): the bench's
        # time, real on the wall clock, the robot's on the simulated one (where no machine's speed enters it).
        self.session_s = 0.0
        self._clock = self.placement.time()
        if records.is_file():
            for line in records.read_text().splitlines():
                self._keep(json.loads(line), write=False)

    def handle(self, message: dict) -> str | None:
        kind = message.get("prompt") or message.get("event")
        if kind in ("stage", "call", "label"):  # a person at the bench or the keyboard
            self._keep({"kind": "person", "trial": message["trial"], "why": kind})
        before = self.placement.scene() if kind in ("stage", "call") else None
        answer = super().handle(message)  # the trial's start sets self.index and self.instance
        if before is not None:
            self._keep({"kind": "person_s", "trial": self.index, "s": self.reset_model(before, self.placement.scene())})
        if kind == "label":
            self._keep({"kind": "person_s", "trial": self.index, "s": self.reset_model.per_object_s})
        if kind == "trial":
            self._ended = self._labelled = None
        if kind == "running":
            self._placed()
        if kind == "ended" or (kind == "label" and self._ended != self.index):  # a person labels the scene as left
            scene, heights, gripped = self.placement.look()
            self.truth_at_end, self._ended = (scene, set(held(heights, self.resting, gripped))), self.index
        if kind == "labelled" or (kind == "label" and self._labelled != self.index):  # the arm's label, or a person's
            truth = self.plan.judge(self.instance, *self.truth_at_end)
            now = self.placement.time()
            spent, self._clock, self._labelled = now - self._clock, now, self.index
            self._keep({"kind": "label", "trial": self.index, "camera": message.get("success"), "truth": truth,
                        "sure": message.get("sure", False), "s": spent})  # fmt: skip
        return answer

    def _placed(self) -> None:
        truth, self.resting, _ = self.placement.look()  # heights as staged: a cube lifted later is held
        workspace = self.plan.task.spec.workspace.area
        for name, target in self.instance.scene.objects.items():
            if name in truth.objects and workspace.contains(target.x, target.y):
                off = truth.objects[name].distance_to(target)
                self.said.append(f"judge: {name} {off * 100:.1f} cm from its target (truth)")
                self._keep({"kind": "placed", "trial": self.index, "object": name, "off_m": off,
                            "at": [truth.objects[name].x, truth.objects[name].y]})  # fmt: skip

    def _keep(self, record: dict, write: bool = True) -> None:
        trial = record["trial"]
        if record["kind"] == "person":
            self.person[trial] += 1
            self.calls[trial] += record["why"] == "call"
        elif record["kind"] == "person_s":
            self.person_s[trial] += record["s"]
        elif record["kind"] == "placed":
            self.placement_m[(trial, record["object"])] = record["off_m"]
            self.staged.setdefault(trial, {})[record["object"]] = record["at"]
        else:
            self.labels[trial] = (record["camera"], record["truth"], record["sure"])
            self.session_s += record["s"]
        if write:
            with self.records.open("a") as out:
                out.write(json.dumps(record) + "\n")


def complete(run_dir: Path) -> bool:
    summary = run_dir / "summary.json"
    return summary.is_file() and bool(json.loads(summary.read_text()).get("complete"))


def camera_errors(judge: Judge, done: list[dict]) -> list[float]:
    """Metres between where the camera saw each object it staged (the journal's staging record) and where the twin
    had it, for every object on the workspace when a trial ran."""
    errors = []
    for record in done:
        seen = record["extra"].get("staging", {}).get("placed", {})
        for name, (x, y) in judge.staged.get(record["index"], {}).items():
            if name in seen:
                errors.append(math.dist(seen[name], (x, y)))
    return errors


def figures(judge: Judge, run_dir: Path) -> dict[str, str]:
    journal = run_dir / "journal.jsonl"
    if not journal.is_file():
        raise UserError(f"the evaluation on the twin did not run (no {journal}); see the log above")
    records = [json.loads(line) for line in journal.read_text().splitlines()]
    done = [r for r in records if r["status"] == "done"]
    if not done:
        raise UserError(f"no trial finished in {run_dir}; see the log above")
    alone = [r for r in done if not judge.person[r["index"]]]
    labels = [judge.labels[r["index"]] for r in done if r["index"] in judge.labels]
    by_camera = [(camera, truth) for camera, truth, sure in labels if sure]
    staging = [r["extra"].get("robot_s", 0.0) for r in done]
    placed = np.array(list(judge.placement_m.values()) or [np.nan]) * 100
    seen = np.array(camera_errors(judge, done) or [np.nan]) * 100
    person_s = sum(judge.person_s[r["index"]] for r in done)
    hours = (judge.session_s + person_s) / 3600
    return {
        "unattended_share": f"{len(alone) / len(done):.3f}",
        "labelled_by_camera": f"{len(by_camera) / len(done):.3f}",
        "label_agreement": f"{np.mean([c == t for c, t in by_camera]):.3f}" if by_camera else "nan",
        "placement_median_cm": f"{np.median(placed):.2f}",
        "placement_p95_cm": f"{np.percentile(placed, 95):.2f}",
        "camera_error_p95_cm": f"{np.percentile(seen, 95):.2f}",
        "person_calls": str(sum(judge.person.values())),
        "staging_s_per_trial": f"{np.mean(staging):.1f}",
        "person_s_per_trial": f"{person_s / len(done):.1f}",
        "trials_per_hour": f"{len(labels) / hours:.1f}" if hours else "nan",
        "trials": str(len(done)),
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
    parser.add_argument("--bases", type=int, default=3, help="base instances of the contrast set")
    parser.add_argument("--joint_offset_deg", type=float, default=0.0, help="each joint's calibration off by up to D")
    parser.add_argument("--task", default="so101_blocks")
    parser.add_argument("--perturbations", default=None, help="the perturbations applied (default: the task's)")
    parser.add_argument("--episode_s", type=float, default=EPISODE_S,
                        help=f"each episode's length (default {EPISODE_S:g}: the demonstrator's pick and place)")  # fmt: skip
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--clock", choices=("sim", "wall"), default="sim",
                        help="the twin's clock: sim (as fast as the machine allows, the same under load) or wall")  # fmt: skip
    parser.add_argument("--operator", choices=("arm", "console"), default="arm",
                        help="who stages and labels: the arm (a person only when it calls) or the scripted person")  # fmt: skip
    parser.add_argument(
        "--work", type=Path, default=None, help="where the run and the judge's records go; again to resume"
    )
    args = parser.parse_args(argv)
    if args.bases < 1 or not 0 <= args.joint_offset_deg <= 10 or args.episode_s <= 0:
        parser.error("--bases must be at least 1, --joint_offset_deg within 0-10 and --episode_s above 0")
    work = args.work or Path(tempfile.mkdtemp(prefix="bench_unattended_"))
    work.mkdir(parents=True, exist_ok=True)
    run_dir = work / "run"
    try:
        began = time.monotonic()
        with running_twin(f"--task={args.task}", f"--joint_offset_deg={args.joint_offset_deg}",
                          f"--seed={args.seed}", f"--clock={args.clock}") as twin:  # fmt: skip
            table = calibrate_table(twin, args.task, work / "table.calibration.json")
            eval_argv = [f"--task={args.task}", *shlex.split(twin.robot_flags), f"--operator={args.operator}",
                         "--policy.type=so101_demonstrator", f"--policy.options={{placement: {twin.placement}}}",
                         "--strategy=contrast", f"--n_instances={args.bases}", f"--fps={FPS}",
                         f"--max_episode_steps={math.ceil(args.episode_s * FPS)}",
                         f"--staging.calibration={table}", "--staging.viewer=none", "--rerun=false",
                         f"--seed={args.seed}", f"--output_dir={run_dir}"]  # fmt: skip
            if args.perturbations:
                eval_argv.append(f"--perturbations={args.perturbations}")
            judge = Judge(Plan(eval_argv), PlacementClient(twin.placement), PlacementError(), args.seed, "accept",
                          records=work / "judge.jsonl")  # fmt: skip
            code, session_began = 0, time.monotonic()
            for _ in range(RESUMES + 1):  # a bus that stops answering on a loaded machine ends it resumably
                if complete(run_dir):
                    break
                resume = ["--resume=true"] if (run_dir / "journal.jsonl").is_file() else []
                if resume:
                    print(f"bench_unattended: resuming {run_dir}", flush=True)
                code = run_answered([*eval_argv, *resume], judge, (OperatorError,))
            session_s = time.monotonic() - session_began
        said = figures(judge, run_dir)
    except (UserError, OperatorError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    print(confusion(judge))
    print(f"eval exit {code}; bases={args.bases} joint_offset_deg={args.joint_offset_deg:g} "
          f"episode_s={args.episode_s:g} run: {run_dir}")  # fmt: skip
    said.update(
        operator=args.operator, clock=args.clock, session_s=f"{session_s:.0f}", wall_s=f"{time.monotonic() - began:.0f}"
    )
    print(" ".join(f"{key}={value}" for key, value in said.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
