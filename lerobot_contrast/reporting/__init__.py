"""Reports over run directories: loading runs, the analysis, the figures and report.md (see `build_report`)."""

from lerobot_contrast.reporting.build import Report, build_report
from lerobot_contrast.reporting.runs import Run, load_run

__all__ = ["Report", "Run", "build_report", "load_run"]
