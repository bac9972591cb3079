"""The tabletop simulator's camera as a bench camera: its own table-to-pixel homography, and a frame with the printed
board rendered lying on the table."""

from __future__ import annotations

import cv2
import numpy as np

from lerobot_contrast.domains.language_table.render import TabletopRenderer
from lerobot_contrast.staging import board
from lerobot_contrast.staging.board import BoardArgs

# Sample points spanning the whole Language-Table board (metres), where the two homographies are compared.
TABLE_GRID = np.array([[x, y] for x in np.linspace(0.15, 0.60, 7) for y in np.linspace(-0.30, 0.30, 7)])
WHERE = BoardArgs(x=0.35, y=0.0, yaw_deg=10.0)


def sim_pixels(renderer: TabletopRenderer, xy: np.ndarray) -> np.ndarray:
    """The simulator's own projection of table points, in OpenCV's pixel convention (centres at integers)."""
    return renderer.project(np.column_stack([xy, np.zeros(len(xy))])) - 0.5


def board_frame(renderer: TabletopRenderer, where: BoardArgs = WHERE, blocks: dict | None = None) -> np.ndarray:
    """A camera frame of the table with the printable page lying on it as `where` says (and `blocks` on top)."""
    page, per_m = board.page_image(dpi=150)
    margin = round(board.MARGIN_M * per_m)
    height, width = page.shape
    corners = np.array([[0, 0], [width, 0], [width, height], [0, height]], float) - 0.5
    on_table = board.board_to_table((corners + 0.5 - margin) / per_m, where)
    page_to_pixels = cv2.getPerspectiveTransform(
        corners.astype(np.float32), sim_pixels(renderer, on_table).astype(np.float32)
    )
    size = (renderer.camera.width, renderer.camera.height)
    image = renderer.render({})
    painted = cv2.warpPerspective(cv2.cvtColor(page, cv2.COLOR_GRAY2RGB), page_to_pixels, size, flags=cv2.INTER_LINEAR)
    covered = cv2.warpPerspective(np.full(page.shape, 255, np.uint8), page_to_pixels, size) > 127
    image[covered] = painted[covered]
    if blocks:  # blocks on top of the page: painted over it where they show
        with_blocks, bare = renderer.render(blocks), renderer.render({})
        shown = np.any(with_blocks != bare, axis=2)
        image[shown] = with_blocks[shown]
    return image
