"""Reports over run directories: loading runs, the analysis, the figures and report.md (see `build_report`)."""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from lerobot_contrast.reporting.build import Report, build_report
    from lerobot_contrast.reporting.runs import Run, load_run

__all__ = ["Report", "Run", "build_report", "load_run"]
# Loaded on first use: the end of an evaluation needs only the run table, not matplotlib's figures.
_HOMES = {"Report": "build", "build_report": "build", "Run": "runs", "load_run": "runs"}


def __getattr__(name: str) -> Any:
    if name not in _HOMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(f"{__name__}.{_HOMES[name]}"), name)
