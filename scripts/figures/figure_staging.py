"""Draw the staging overlay on the tabletop simulator's camera for the docs (docs/figures/staging_overlay.png):
left, the so101_blocks first trial as the operator starts staging it; right, after staging with the red cube 5 cm
off, as the check reports it.

    .venv/bin/python scripts/figures/figure_staging.py [OUT.png]
"""

from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np

from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.domains.language_table import board as tabletop
from lerobot_contrast.domains.language_table.render import TabletopRenderer
from lerobot_contrast.domains.task_file.loader import load_task_file
from lerobot_contrast.staging import overlay
from lerobot_contrast.staging.homography import CameraCalibration

OUT = Path(__file__).resolve().parents[2] / "docs" / "figures" / "staging_overlay.png"
CUBE = tabletop.SHAPE_FOOTPRINT["cube"][0]


def simulator_calibration(renderer: TabletopRenderer) -> CameraCalibration:
    """The simulator camera's own table-to-pixel homography (what calibrating with the board gives, within a pixel)."""
    grid = np.array([[x, y] for x in np.linspace(0.15, 0.6, 5) for y in np.linspace(-0.3, 0.3, 5)])
    pixels = renderer.project(np.column_stack([grid, np.zeros(len(grid))])) - 0.5
    homography, _ = cv2.findHomography(grid, pixels, 0)
    return CameraCalibration("top", (renderer.camera.width, renderer.camera.height), homography, 0.0, 0)


def main() -> int:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else OUT
    task = load_task_file("so101_blocks")
    renderer = TabletopRenderer(360, 640)
    calibration = simulator_calibration(renderer)
    target = task.sample(1, np.random.default_rng(0))[0].scene
    current = task.storage_scene()
    before = overlay.draw(renderer.render(current, (0.2, 0.0)), overlay.marks(calibration, current, target, CUBE))
    red = target.objects["red_cube"]
    placed = target.with_object("red_cube", Pose(red.x, red.y + 0.05, red.yaw))
    off = {name: 0.0 for name in target.objects} | {"red_cube": 0.05}
    after = overlay.draw(renderer.render(placed, (0.2, 0.0)), overlay.marks(calibration, placed, target, CUBE, off))
    out.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(
        str(out), cv2.cvtColor(np.hstack([before, np.full((360, 8, 3), 255, np.uint8), after]), cv2.COLOR_RGB2BGR)
    )
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
