"""The `--staging.*` flags of `python -m lerobot_contrast.eval` (light: read before anything heavy loads)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path


@dataclass
class StagingArgs:
    """Staging with a calibrated camera (operator console only): targets shown in Rerun, placements measured."""

    # Table calibration from python -m lerobot_contrast.calibrate (default: where calibrate writes it, when it
    # exists). Without one, staging is the console's list of moves alone.
    calibration: Path | None = None
    # How far (metres) a coloured object may sit from its target before the operator is asked to fix or accept it.
    tolerance: float = 0.02
    # Side and height of the objects (metres): the outline drawn at each target, and the height they are seen at.
    object_size: float = 0.03
    # The live staging view: serve (a Rerun gRPC server; the console prints how to connect), spawn (open the
    # Rerun viewer), or none.
    viewer: str = "serve"
