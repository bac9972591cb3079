"""`python -m lerobot_contrast.report RUN_DIR [RUN_DIR ...]`: tables and figures for one or more runs."""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.metrics import METRICS
from lerobot_contrast.spine.flags import ConfigError, parse_config, usage_text, wants_help

USAGE = "python -m lerobot_contrast.report RUN_DIR [RUN_DIR ...] [--flag=value | --flag value] ..."


class ReportArgsError(ConfigError):
    pass


@dataclass
class ReportConfig:
    """Summarise run directories of lerobot_contrast.eval (or every cell of a lerobot_contrast.sweep folder):
    report.md with 95% intervals, and the paper's figures. Runs that differ only in --seed are pooled; a complete
    standard run of the same policy, evaluation set and seed serves as the full i.i.d. reference for the
    estimation error."""

    # Run directories written by lerobot_contrast.eval, sweep folders written by lerobot_contrast.sweep, or
    # hub:USER/NAME; usually given as arguments (required).
    runs: list[str] = field(default_factory=list)
    # Where to write the report (default: report/ in the first local run directory or sweep folder, else ./report).
    output_dir: Path | None = None
    # Main metric of the figures: success, spl or progress (default: spl where recorded, else progress).
    metric: str | None = None


def parse_args(argv: list[str] | None) -> ReportConfig:
    args = parse_config(ReportConfig, argv, positional="runs")
    if not args.runs:
        raise ReportArgsError(f"give the run directories to report on: {USAGE}")
    if args.metric is not None and args.metric not in METRICS:
        raise ReportArgsError(f"--metric must be one of {', '.join(METRICS)}, got {args.metric!r}")
    return args


def default_output_dir(specs: list[str], runs: list) -> Path:
    """report/ in the first local run directory or sweep folder; ./report when every input is downloaded (never the
    Hub cache)."""
    from lerobot_contrast.record.hub import parse_hub_spec
    from lerobot_contrast.record.sweep_dir import is_sweep_dir
    from lerobot_contrast.reporting.runs import run_specs

    if parse_hub_spec(specs[0]) is None and is_sweep_dir(Path(specs[0])):
        return Path(specs[0]) / "report"
    local = [run for spec, run in zip(run_specs(specs), runs, strict=True) if parse_hub_spec(spec) is None]
    return local[0].path / "report" if local else Path("report")


def main(argv: list[str] | None = None) -> int:
    try:
        argv = list(sys.argv[1:] if argv is None else argv)
        if wants_help(argv):
            print(usage_text(ReportConfig, USAGE))
            return 0
        path = report(parse_args(argv))  # the flags first: a mistyped one is named before pandas and matplotlib load
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    print(f"report: {path}")
    return 0


def report(args: ReportConfig) -> Path:
    """Write the report of the runs `args` names; returns the path of report.md."""
    from lerobot_contrast.pairing.comparison import append_comparisons
    from lerobot_contrast.pairing.pair_dir import expand, is_pair_dir
    from lerobot_contrast.reporting import build_report, load_run
    from lerobot_contrast.reporting.runs import distinct_runs, run_specs

    pairs = [Path(spec) for spec in args.runs if is_pair_dir(Path(spec))]  # interleaved runs: one run per policy
    specs = run_specs(expand(args.runs))
    given = [load_run(spec) for spec in specs]
    output_dir = args.output_dir or (pairs[0] / "report" if pairs else default_output_dir(args.runs, given))
    runs, repeats = distinct_runs(specs, given)
    for line in repeats:
        print(f"note: {line}")
    try:
        return append_comparisons(build_report(runs, output_dir, args.metric).path, pairs)
    except OSError as error:
        raise ReportArgsError(
            f"--output_dir: cannot write to {output_dir} ({error.strerror}); choose a writable directory"
        ) from None


if __name__ == "__main__":
    sys.exit(main())
