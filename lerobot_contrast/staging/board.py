"""The printed ArUco calibration board: its layout, where it lies on the table, and the printable page that shows it.

Board frame (OpenCV's GridBoard): origin at the first marker's top-left corner, x to the page's right, y down it.
Placed on the table with the page's top edge away from the robot, its right edge to the robot's right (-y).
"""

from __future__ import annotations

import math
from contextlib import suppress
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from lerobot_contrast.contrast.errors import UserError

DICTIONARY = cv2.aruco.DICT_4X4_50
COLUMNS, ROWS = 4, 3
MARKER_M, GAP_M = 0.05, 0.01  # printed marker side and the gap between markers
DPI = 300
MARGIN_M = 0.012  # white quiet zone around the markers, part of the printed board


@dataclass
class BoardArgs:
    """Where the printed board lies on the table, in the task's frame (metres, degrees)."""

    # The board's centre, forward from the robot's base (x) and to its left (y).
    x: float = 0.30
    y: float = 0.0
    # Turn of the board about the table's normal, counter-clockwise seen from above (0: page top away from the robot).
    yaw_deg: float = 0.0


def dictionary() -> cv2.aruco.Dictionary:
    return cv2.aruco.getPredefinedDictionary(DICTIONARY)


def grid_board() -> cv2.aruco.GridBoard:
    return cv2.aruco.GridBoard((COLUMNS, ROWS), MARKER_M, GAP_M, dictionary())


def board_size_m() -> tuple[float, float]:
    """Width and height of the marker grid, metres."""
    return COLUMNS * MARKER_M + (COLUMNS - 1) * GAP_M, ROWS * MARKER_M + (ROWS - 1) * GAP_M


def printed_size_text() -> str:
    width, height = board_size_m()
    return (
        f"ArUco 4x4_50 grid {COLUMNS}x{ROWS}: markers {MARKER_M * 1000:.0f} mm, gaps {GAP_M * 1000:.0f} mm, "
        f"grid {width * 1000:.0f} x {height * 1000:.0f} mm; print at 100% (no fit-to-page) on A4 or Letter, landscape"
    )


def board_to_table(points: np.ndarray, where: BoardArgs) -> np.ndarray:
    """Board-frame points (N, 2), metres, -> table (x, y) where the board lies as `where` says."""
    width, height = board_size_m()
    page_right, page_down = points[:, 0] - width / 2, points[:, 1] - height / 2
    local = np.stack([-page_down, -page_right], axis=1)  # page down points at the robot, page right to its right
    yaw = math.radians(where.yaw_deg)
    rotation = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
    return local @ rotation.T + (where.x, where.y)


def page_image(dpi: int = DPI) -> tuple[np.ndarray, float]:
    """The printable page (greyscale) and its pixels per metre: the grid, its quiet zone and the printed size."""
    per_m = dpi / 0.0254
    width, height = board_size_m()
    margin = round(MARGIN_M * per_m)
    size = (round(width * per_m) + 2 * margin, round(height * per_m) + 2 * margin)
    grid = grid_board().generateImage(size, marginSize=margin, borderBits=1)
    caption = np.full((round(0.02 * per_m), size[0]), 255, np.uint8)
    text = f"{printed_size_text().split(';')[0]}. This edge towards the robot."
    cv2.putText(caption, text, (margin, caption.shape[0] - margin // 2), cv2.FONT_HERSHEY_SIMPLEX, dpi / 300, 0, 2)
    return np.vstack([grid, caption]), per_m


def write_page(path: Path, dpi: int = DPI) -> str:
    """Write the printable board (PNG or PDF, by suffix) at `dpi`; returns what to print it as. A suffix other than
    .pdf or .png, or a folder that cannot be written, is one line and writes nothing."""
    from PIL import Image

    kind = path.suffix.lower().lstrip(".")
    if kind not in ("pdf", "png"):
        raise UserError(f"--write_board={path}: writes a .pdf or a .png, not {path.suffix or 'a file without one'}")
    image, _ = page_image(dpi)
    # A PDF carries its print size in its resolution, a PNG in its dpi field: either prints at 100% as stated.
    options = {"resolution": dpi} if kind == "pdf" else {"dpi": (dpi, dpi)}
    temporary = path.with_name(f".{path.name}.tmp")  # a page cut short is never left under the name asked for
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(image).save(temporary, format=kind.upper(), **options)
        temporary.replace(path)
    except OSError as error:
        with suppress(OSError):  # where the folder is not one, there is nothing to remove
            temporary.unlink(missing_ok=True)
        nearest = next(folder for folder in path.parents if folder.exists())  # a file where a folder should be?
        reason = error.strerror or error if nearest.is_dir() else f"{nearest} is not a folder"
        raise UserError(
            f"--write_board={path}: cannot write it ({reason}); name a file in a folder you can write"
        ) from None
    return f"{path}: {printed_size_text()}"
