"""`python -m lerobot_contrast.eval`: plan, run, record and summarise a contrast-set evaluation."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.stopping import summary_line
from lerobot_contrast.lanes.choice import use_threads
from lerobot_contrast.policies import make_policy
from lerobot_contrast.record.journal import read_journal
from lerobot_contrast.spine.build import (
    check_robot_type,
    make_operator,
    make_robot,
    register_robots,
)
from lerobot_contrast.spine.config import EvalConfig, resume_args
from lerobot_contrast.spine.flags import (
    bool_flags,
    check_names,
    flag_names,
    help_text,
    join_values,
    parse_config,
    robot_type,
    wants_help,
)
from lerobot_contrast.spine.run_setup import (
    check_new_run_dir,
    connect,
    default_output_dir,
    dry_run,
    equipped,
    planned_evaluation,
)
from lerobot_contrast.terminal.progress import RunProgress, header_lines

if TYPE_CHECKING:
    from lerobot_contrast.spine.evaluation import Evaluation


def plan_and_run(cfg: EvalConfig, chosen_robot: str | None = None) -> int:
    """Plan, then either print the plan (--dry_run) or run it into a run directory; returns the exit code.
    `chosen_robot`: the --robot.type as given, for messages."""
    if cfg.policies is not None:
        from lerobot_contrast.pairing.session import run_policies

        return run_policies(cfg, chosen_robot)
    planned = planned_evaluation(cfg)
    task = planned.task
    if cfg.dry_run:
        dry_run(planned)
        return 0
    check_new_run_dir(cfg)  # before the robot connects and the policy's weights load
    robot = make_robot(cfg, chosen_robot)
    # Connect before creating the run directory: an unreachable robot leaves nothing behind to resume.
    # A remote robot also says on connecting whether it can stage scenes.
    connect(robot, cfg.clock)
    try:
        operator = make_operator(cfg, robot, task, planned.cost_model.unit)
        use_threads()  # chosen, not inherited from the machine (lane_choice.py)
        policy = make_policy(cfg.policy, robot, task, cfg.rename_map)  # one that cannot load leaves no run directory
        cfg.output_dir = cfg.output_dir or default_output_dir(cfg, task)
        return run_and_report(cfg, equipped(cfg, planned, robot, policy, operator))
    finally:
        if robot.is_connected:
            from lerobot_contrast.spine.runner import release

            # A lost robot cannot disconnect cleanly (its servos do not answer): one line after the error, no traceback.
            failed = release(robot)
            if failed is not None:
                print(
                    f"the robot ({robot.name}) did not disconnect cleanly: {' '.join(str(failed).split())}",
                    file=sys.stderr,
                )


def run_and_report(cfg: EvalConfig, evaluation: Evaluation) -> int:
    from lerobot_contrast.spine.evaluation import run
    from lerobot_contrast.spine.run_end import ENDED_EARLY, finish, say_ended_early, tell_stopped

    path, unit = Path(evaluation.output_dir), evaluation.cost_model.unit
    resume = f"--output_dir={path} --resume=true"
    print("\n".join(header_lines(evaluation.settings, path, f"python -m lerobot_contrast.eval {resume}")), flush=True)
    journal = path / "journal.jsonl"
    already = read_journal(journal) if cfg.resume and journal.is_file() else []
    # The operator console prompts between trials, so a redrawn bar would tear its prompts: plain lines there.
    live = False if evaluation.operator is not None else None
    progress = RunProgress(len(evaluation.plan), unit, verbose=cfg.verbose, already=already, live=live)
    try:
        with progress:
            results = run(dataclasses.replace(evaluation, progress=progress))
    except BaseException as error:  # told on the person's page and in a message, however the session stops
        tell_stopped(evaluation.operator, error, f"python -m lerobot_contrast.eval {resume}")
        if not isinstance(error, ENDED_EARLY):
            raise
        return say_ended_early(error, resume, f"in {journal}", recorded=lambda: len(read_journal(journal)))
    finish(evaluation.operator, f"the session ended: {len(results.records)} trials in {path}")
    from lerobot_contrast.reporting.run_table import results_table  # pandas and scipy, needed only now

    print(results_table(results.records, results.summary, unit))
    if "stopping" in results.summary:
        print(summary_line(results.summary["stopping"]))
    spent, ran = results.summary["overall"]["cumulative_cost"], len(results.records)
    if cfg.budget is not None and spent > cfg.budget:
        print(
            f"stopped at the budget: {spent:.2f} of {cfg.budget:g} {unit} spent, {ran} of {len(evaluation.plan)} planned trials reached"
        )
    print(f"run directory: {path}")
    if cfg.push_to_hub:
        from lerobot_contrast.record.hub import publish_run

        print(f"published: {publish_run(path, cfg.repo_id, private=cfg.private)}")
    return 0


def main(argv: list[str] | None = None) -> int:
    try:
        argv = join_values(list(sys.argv[1:] if argv is None else argv), bool_flags(EvalConfig))
        if not wants_help(argv):  # a mistyped flag is named before LeRobot, torch and the robot plugins load
            check_names(argv, flag_names(EvalConfig), robots=False)
        check_robot_type(argv, register_robots())
        if wants_help(argv):
            # join_values made `--operator arm` one argument
            operator = next((a.split("=", 1)[1] for a in argv if a.startswith("--operator=")), None)
            print(help_text(EvalConfig, "python -m lerobot_contrast.eval", robot_type(argv), operator))
            return 0
        return plan_and_run(parse_config(EvalConfig, resume_args(argv)), robot_type(argv))
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
