"""`python -m lerobot_contrast.report RUN_DIR [RUN_DIR ...]`: tables and figures for one or more runs."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.metrics import METRICS
from lerobot_contrast.record.hub import parse_hub_spec
from lerobot_contrast.record.sweep_dir import is_sweep_dir
from lerobot_contrast.reporting import build_report, load_run
from lerobot_contrast.reporting.runs import distinct_runs, run_specs


class ReportArgsError(UserError):
    pass


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line naming the problem, like the eval command
        raise ReportArgsError(f"{message} (see --help)")


def parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="python -m lerobot_contrast.report",
        description="Summarise run directories of lerobot_contrast.eval (or every cell of a lerobot_contrast.sweep "
        "folder): report.md with 95% intervals, and the paper's figures. Runs that differ only in --seed are pooled; a complete standard run of the same "
        "policy, evaluation set and seed serves as the full i.i.d. reference for the estimation error.",
    )
    p.add_argument(
        "runs",
        nargs="+",
        metavar="RUN_DIR",
        help="run directories written by lerobot_contrast.eval, or sweep folders written by lerobot_contrast.sweep",
    )
    p.add_argument(
        "--output_dir",
        type=Path,
        default=None,
        help="where to write the report (default: report/ in the first local run directory or sweep folder, "
        "else ./report)",
    )
    p.add_argument(
        "--metric",
        choices=METRICS,
        default=None,
        help="main metric of the figures (default: spl where recorded, else progress)",
    )
    return p


def default_output_dir(specs: list[str], runs: list) -> Path:
    """report/ in the first local run directory or sweep folder; ./report when every input is downloaded (never the
    Hub cache)."""
    if parse_hub_spec(specs[0]) is None and is_sweep_dir(Path(specs[0])):
        return Path(specs[0]) / "report"
    local = [run for spec, run in zip(run_specs(specs), runs, strict=True) if parse_hub_spec(spec) is None]
    return local[0].path / "report" if local else Path("report")


def main(argv: list[str] | None = None) -> int:
    try:
        args = parser().parse_args(argv)
        specs = run_specs(args.runs)
        given = [load_run(spec) for spec in specs]
        output_dir = args.output_dir or default_output_dir(args.runs, given)
        runs, repeats = distinct_runs(specs, given)
        for line in repeats:
            print(f"note: {line}")
        try:
            path = build_report(runs, output_dir, args.metric).path
        except OSError as error:
            raise ReportArgsError(
                f"--output_dir: cannot write to {output_dir} ({error.strerror}); choose a writable directory"
            ) from None
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    print(f"report: {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
