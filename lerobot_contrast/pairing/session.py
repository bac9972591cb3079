"""`python -m lerobot_contrast.eval --policies=A,B[,C]`: build every policy's evaluation on one robot and plan, run
them interleaved into one pair directory (or resume it), decide the pairs as bases close, and report."""

from __future__ import annotations

import dataclasses
from contextlib import ExitStack
from pathlib import Path
from typing import Any

from lerobot_contrast.contrast.trial import TrialRecord
from lerobot_contrast.lanes.choice import use_threads
from lerobot_contrast.pairing.decide import PairMonitor
from lerobot_contrast.pairing.interleave import Interleaver, Seat
from lerobot_contrast.pairing.pair_dir import is_pair_dir, restaging_cost, write_index, write_summary
from lerobot_contrast.pairing.policy_list import PolicySpec, parse_policies
from lerobot_contrast.policies import make_policy
from lerobot_contrast.record.plan_file import keep_plan
from lerobot_contrast.record.results import write_results
from lerobot_contrast.record.run_dir import RunDir, disk_full_said, open_run_dir, write_json_atomic
from lerobot_contrast.record.summary import summarize
from lerobot_contrast.record.third_party import third_party_output
from lerobot_contrast.spine.build import choose_robot, make_operator, make_robot, needs_camera
from lerobot_contrast.spine.config import ConfigError, EvalConfig, config_json
from lerobot_contrast.spine.evaluation import Evaluation
from lerobot_contrast.spine.run_end import ENDED_EARLY, finish, say_ended_early, tell_stopped
from lerobot_contrast.spine.run_setup import (
    connect,
    default_output_dir,
    dry_run,
    equipped,
    planned_evaluation,
    validate,
)
from lerobot_contrast.spine.runner import RobotRunner


def check_pair_flags(cfg: EvalConfig) -> list[PolicySpec]:
    if cfg.policy.path is not None or cfg.policy.type is not None:
        raise ConfigError("--policies names every policy; drop --policy.path/--policy.type (give options per entry)")
    if cfg.stop.width is not None or cfg.stop.compare is not None:
        raise ConfigError("--policies decides its pairs itself; drop --stop.width and --stop.compare")
    if cfg.order == "adaptive":
        raise ConfigError("--order=adaptive picks trials from one policy's outcomes; use iid or cost_aware")
    return parse_policies(cfg.policies, cfg.policy)


def policy_cfg(cfg: EvalConfig, spec: PolicySpec, path: Path | None) -> EvalConfig:
    """`cfg` for `spec` alone, recorded in its run directory inside the pair directory `path` (None: as given)."""
    return dataclasses.replace(
        cfg, policy=spec.args, output_dir=cfg.output_dir if path is None else path / spec.dirname
    )


def run_policies(cfg: EvalConfig, chosen_robot: str | None = None) -> int:
    """Plan once, then run every policy on it interleaved (or print the plan with --dry_run); the exit code."""
    specs = check_pair_flags(cfg)
    for spec in specs:
        validate(policy_cfg(cfg, spec, None))
    planned = planned_evaluation(cfg)
    if cfg.dry_run:
        dry_run(planned)
        names = ", ".join(s.label for s in specs)
        print(f"each trial runs {len(specs)} times, once per policy ({names}), the scene restaged between them")
        return 0
    if cfg.resume and not is_pair_dir(cfg.output_dir):  # e.g. one policy's run directory inside the session's
        raise ConfigError(
            f"--resume: {cfg.output_dir} holds no interleaved session (no pairs.json); resume the directory above it"
        )
    if not cfg.resume and cfg.output_dir is not None and cfg.output_dir.is_dir() and any(cfg.output_dir.iterdir()):
        raise ConfigError(
            f"--output_dir: {cfg.output_dir} already exists; pass --resume=true or choose a new directory"
        )
    if cfg.robot is None:  # render cameras if any policy reads images
        probe = policy_cfg(cfg, next((s for s in specs if needs_camera(policy_cfg(cfg, s, None))), specs[0]), None)
        choose_robot(probe)
        cfg.robot = probe.robot
    robot = make_robot(cfg, chosen_robot)
    connect(robot, cfg.clock)
    try:
        operator = make_operator(cfg, robot, planned.task, planned.cost_model.unit)
        use_threads()
        policies = [make_policy(s.args, robot, planned.task, cfg.rename_map) for s in specs]
        cfg.output_dir = cfg.output_dir or default_output_dir(cfg, planned.task)
        evaluations = [
            dataclasses.replace(
                equipped(policy_cfg(cfg, s, cfg.output_dir), planned, robot, p, operator),
                lanes=1, stop=None, verbose=False, labels={"strategy": cfg.strategy, "policy": s.label},
            )
            for s, p in zip(specs, policies, strict=True)
        ]  # fmt: skip
        return Session(cfg, specs, evaluations).run_and_report()
    finally:
        if robot.is_connected:
            robot.disconnect()


class Session:
    """One interleaved session in its pair directory."""

    def __init__(self, cfg: EvalConfig, specs: list[PolicySpec], evaluations: list[Evaluation]) -> None:
        self.cfg, self.specs, self.evaluations = cfg, specs, evaluations
        self.path = Path(cfg.output_dir)
        self.first = evaluations[0]
        self.resume_hint = f"--output_dir={self.path} --resume=true"
        self.consoles: list[Any] = []  # the operator's view per policy (PairConsole), told where the session stands

    def run_and_report(self) -> int:
        print(f"interleaved: {', '.join(s.label for s in self.specs)} on {len(self.first.plan)} planned trials")
        print(f"run directory: {self.path} (continue with python -m lerobot_contrast.eval {self.resume_hint})")
        try:
            with disk_full_said(self.path, f"resume with {self.resume_hint}"):
                monitor, records, reason = self.run()
        except BaseException as error:  # told on the person's page and in a message, however the session stops
            tell_stopped(self.first.operator, error, f"python -m lerobot_contrast.eval {self.resume_hint}")
            if not isinstance(error, ENDED_EARLY):
                raise
            return say_ended_early(error, self.resume_hint, "journalled")
        self.print_end(monitor, records, reason)
        ran = sum(len(seat) for seat in records.values())
        finish(
            self.first.operator,
            f"the interleaved session ended: {ran} trials of {len(records)} policies in {self.path}",
        )
        return 0

    def _start(self) -> None:
        if not self.cfg.resume:
            self.path.mkdir(parents=True, exist_ok=True)
            write_json_atomic(self.path / "config.json", config_json(self.cfg))
            write_index(self.path, [
                {"label": s.label, "name": s.dirname, "policy": dataclasses.asdict(s.args)} for s in self.specs
            ])  # fmt: skip

    def _open(self, stack: ExitStack, ev: Evaluation) -> RunDir:
        path = Path(ev.output_dir)
        resume = self.cfg.resume and (path / "config.json").is_file()
        run_dir = stack.enter_context(open_run_dir(path, dict(ev.config), resume, defaults=ev.config_defaults))
        keep_plan(path, ev.plan)
        for observer in ev.observers:
            observer.rollback(run_dir.journal.records)
        return run_dir

    def _seat(self, spec: PolicySpec, ev: Evaluation, run_dir: RunDir) -> Seat:
        from lerobot_contrast.operators.pair import PairConsole

        operator = None if ev.operator is None else PairConsole(ev.operator, spec.label, self.cfg.blind)
        runner = RobotRunner(
            ev.robot, ev.policy, ev.task, operator=operator, fps=ev.fps, max_steps=ev.max_steps,
            max_episode_s=ev.max_episode_s, observers=ev.observers, cost_unit=ev.cost_model.unit, cost_model=ev.cost_model,
            say=print,
        )  # fmt: skip
        if operator is not None:
            self.consoles.append(operator)
        return Seat(spec.label, ev, run_dir.journal.records, runner, run_dir.journal.append, ev.observers)

    def run(self) -> tuple[PairMonitor, dict[str, list[TrialRecord]], str]:
        self._start()
        ev = self.first
        monitor = PairMonitor(ev.plan, [s.label for s in self.specs], self.cfg.stop.alpha)
        complete, reason = False, "not_stopped"
        with ExitStack() as stack:
            stack.enter_context(third_party_output(self.path))
            dirs = [self._open(stack, e) for e in self.evaluations]
            seats = [self._seat(s, e, d) for s, e, d in zip(self.specs, self.evaluations, dirs, strict=True)]
            session = Interleaver(seats, ev.plan, ev.cost_model, ev.budget, ev.task.storage_scene())
            for console in self.consoles:
                console.session = session
            known = {seat.label: len(seat.records) for seat in seats}  # trials journalled before this session
            stop = lambda: self.cfg.stop.decided and monitor.all_decided  # noqa: E731
            try:
                for trial in session.run(stop):
                    closed = monitor.bases
                    monitor.observe(trial)
                    if any(record.index >= known[label] for label, record in trial.items()):
                        print(trial_line(trial, ev.cost_model.unit), flush=True)
                        if monitor.bases > closed and monitor.metric is not None:
                            print(f"{'':>7}{monitor.line()}", flush=True)
                complete = True
                reason = "decided" if stop() else "plan_end"
            finally:
                for seat, run_dir in zip(seats, dirs, strict=True):
                    summary = summarize(seat.records, settings=seat.evaluation.settings, complete=complete)
                    settings = {k: str(v) for k, v in seat.evaluation.settings.items()}
                    write_results(run_dir.results_path, seat.records, settings)
                    run_dir.write_summary(summary)
                    for observer in seat.evaluation.observers:
                        observer.close()
                self.write_summary(monitor, {s.label: s.records for s in seats}, complete, reason)
        return monitor, {s.label: list(s.records) for s in seats}, reason

    def write_summary(
        self, monitor: PairMonitor, records: dict[str, list[TrialRecord]], complete: bool, reason: str
    ) -> None:
        stopping = monitor.report() | {"reason": reason, "why": WHY[reason], "stop_when_decided": self.cfg.stop.decided}
        write_summary(self.path, {
            "policies": list(records), "complete": complete, "planned_trials": len(self.first.plan),
            "trials": min(len(r) for r in records.values()), "cost_unit": self.first.cost_model.unit,
            "cost": restaging_cost([r for rs in records.values() for r in rs]), "stopping": stopping,
        })  # fmt: skip

    def print_end(self, monitor: PairMonitor, records: dict[str, list[TrialRecord]], reason: str) -> None:
        from lerobot_contrast.pairing.comparison import write_comparison
        from lerobot_contrast.reporting.run_table import results_table

        unit = self.first.cost_model.unit
        for seat_label, seat_records in records.items():
            print(f"\n{seat_label}:")
            print(results_table(seat_records, summarize(seat_records, settings={}, complete=True), unit))
        cost = restaging_cost([r for rs in records.values() for r in rs])
        print(f"\nsequential: {WHY[reason]}; {monitor.line()}")
        for pair in monitor.report()["pairs"]:
            print(f"  {pair['first']} vs {pair['second']}: {pair['verdict']} at alpha {pair['alpha']:g}")
        print(
            f"cost: staging {cost['staging']:.2f} {unit}, restaging {cost['restaging']:.2f} {unit} "
            f"({100 * cost['restage_share']:.0f}% of the session's cost)"
        )
        print(f"comparison: {write_comparison(self.path)}")
        print(f"run directory: {self.path}")
        if self.cfg.push_to_hub:
            from lerobot_contrast.pairing.publish import publish_pair

            for url in publish_pair(self.path, self.cfg.repo_id, private=self.cfg.private):
                print(f"published: {url}")


WHY: dict[str, Any] = {
    "decided": "every pair was decided, and --stop.decided=true ended the session there",
    "plan_end": "the plan (or its budget) ended",
    "not_stopped": "the session was interrupted before its plan ended",
}


def trial_line(trial: dict[str, TrialRecord], unit: str) -> str:
    first = next(iter(trial.values()))
    head = f"trial {first.index + 1:>4} {first.base_id} {first.perturbation or 'original'}:"
    parts = []
    for label, record in trial.items():
        if record.status != "done":
            parts.append(f"{label} {record.status}")
            continue
        restage = " restaged" if record.extra.get("pairing", {}).get("restage") else ""
        parts.append(f"{label} {'success' if record.success else 'failure'} ({record.cost:.2f} {unit}{restage})")
    return f"{head} " + " | ".join(parts)
