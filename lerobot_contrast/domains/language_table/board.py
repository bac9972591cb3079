"""Language-Table board facts: workspace bounds, blocks, block sets and camera (robot base frame, metres).

Axis semantics used by the language: "up/top" is -x (towards the robot base), "down/bottom" is +x,
"left" is -y, "right" is +y.
"""

from __future__ import annotations

from dataclasses import dataclass

X_MIN, X_MAX = 0.15, 0.60
Y_MIN, Y_MAX = -0.3048, 0.3048
CENTER_X, CENTER_Y = 0.375, 0.0
WORKSPACE_BOUNDS = ((X_MIN, Y_MIN), (X_MAX, Y_MAX))
WORKSPACE_BOUNDS_BUFFER = 0.08
# Sampling box for the effector start, blocks and reward targets (bounds inset by the buffer).
INNER_X_MIN, INNER_X_MAX = X_MIN + WORKSPACE_BOUNDS_BUFFER, X_MAX - WORKSPACE_BOUNDS_BUFFER
INNER_Y_MIN, INNER_Y_MAX = Y_MIN + WORKSPACE_BOUNDS_BUFFER, Y_MAX - WORKSPACE_BOUNDS_BUFFER
BLOCK_DISTANCE_THRESHOLD = 0.0175
ARM_DISTANCE_THRESHOLD = 0.06
INSTRUCTION_LENGTH = 512

# Visual board (a 18 x 24 inch dark plate centred at (0.35, 0)).
BOARD_CENTER = (0.35, 0.0)
BOARD_SIZE = (0.4572, 0.6096)

EFFECTOR_RADIUS = 0.0127
EFFECTOR_HEIGHT = 0.145
BLOCK_HEIGHT = 0.0381
BLOCK_MASS = 0.01
BLOCK_FRICTION = 0.5
EFFECTOR_FRICTION = 1.0

CONTROL_HZ = 10.0
MAX_ACTION = 0.1
MAX_EPISODE_STEPS = 200

IMAGE_HEIGHT, IMAGE_WIDTH = 180, 320
CAMERA_POSITION = (0.75, 0.0, 0.5)
CAMERA_EULER_XYZ = (3.141592653589793 / 5, 3.141592653589793, -3.141592653589793 / 2)
CAMERA_FOCAL_FRACTION = 0.803  # fx = fy = 0.803 * image width (RealSense D415-like)

COLORS = ("red", "blue", "green", "yellow")
SHAPES = ("moon", "cube", "star", "pentagon")

# Rendered colours (RGB, 0-255) as they appear in the benchmark's camera image.
COLOR_RGB = {"red": (239, 95, 95), "blue": (95, 95, 239), "green": (63, 159, 63), "yellow": (188, 188, 75)}
BOARD_RGB = (47, 47, 47)

# Footprint (extent along the block's local x, extent along its local y) of each shape's mesh.
SHAPE_FOOTPRINT = {
    "cube": (0.0397, 0.0397),
    "moon": (0.0525, 0.0257),
    "star": (0.0444, 0.0408),
    "pentagon": (0.0444, 0.0413),
}


@dataclass(frozen=True)
class Block:
    name: str
    color: str
    shape: str

    @property
    def text(self) -> str:
        return f"{self.color} {self.shape}"

    @property
    def footprint(self) -> tuple[float, float]:
        return SHAPE_FOOTPRINT[self.shape]


def block(name: str) -> Block:
    color, shape = name.split("_")
    return Block(name, color, shape)


ALL_BLOCKS = tuple(f"{c}_{s}" for c in COLORS for s in SHAPES)

BLOCK_MODES = {
    "BLOCK_4": ("red_moon", "blue_cube", "green_star", "yellow_pentagon"),
    "BLOCK_8": (
        "red_moon",
        "red_pentagon",
        "blue_moon",
        "blue_cube",
        "green_cube",
        "green_star",
        "yellow_star",
        "yellow_pentagon",
    ),
}


def blocks_for_mode(mode: str) -> tuple[str, ...]:
    try:
        return BLOCK_MODES[mode]
    except KeyError:
        raise ValueError(f"unknown block mode {mode!r}; choose from: {', '.join(BLOCK_MODES)}") from None


# --- Task-family geometry (the benchmark's reward classes) ---
# Reward targets must lie strictly inside this box (`target_inside_bounds`); it equals the sampling box.
TARGET_X_MIN, TARGET_X_MAX = INNER_X_MIN, INNER_X_MAX
TARGET_Y_MIN, TARGET_Y_MAX = INNER_Y_MIN, INNER_Y_MAX

# block2block
BLOCK2BLOCK_DISTANCE = 0.05  # success: pushed block centre closer than this to the target block
BLOCK2BLOCK_MIN_START_DISTANCE = 0.06  # goal sampling: the pair starts at least this far apart

# block2absolutelocation: the location table is shifted by X_BUFFER because the arm's reach is off-centre.
X_BUFFER = 0.025
_LOC_X = (X_MIN - X_BUFFER, (X_MIN + X_MAX) / 2 - X_BUFFER, X_MAX - X_BUFFER)
LOCATIONS = {
    "top": (_LOC_X[0], CENTER_Y),
    "top_left": (_LOC_X[0], Y_MIN),
    "top_right": (_LOC_X[0], Y_MAX),
    "center": (_LOC_X[1], CENTER_Y),
    "center_left": (_LOC_X[1], Y_MIN),
    "center_right": (_LOC_X[1], Y_MAX),
    "bottom": (_LOC_X[2], CENTER_Y),
    "bottom_left": (_LOC_X[2], Y_MIN),
    "bottom_right": (_LOC_X[2], Y_MAX),
}
ABSOLUTE_LOCATION_DISTANCE = 0.115
ABSOLUTE_CENTER_DISTANCE = 0.10

# Direction signs in (x, y): up is -x, left is -y. block2relativelocation normalises them.
DIRECTION_SIGNS = {
    "up": (-1.0, 0.0),
    "down": (1.0, 0.0),
    "left": (0.0, -1.0),
    "right": (0.0, 1.0),
    "diagonal_up_left": (-1.0, -1.0),
    "diagonal_up_right": (-1.0, 1.0),
    "diagonal_down_left": (1.0, -1.0),
    "diagonal_down_right": (1.0, 1.0),
}
DIRECTIONS = tuple(DIRECTION_SIGNS)

# block2relativelocation
RELATIVE_MAGNITUDES = {"near": 0.15, "far": 0.25}
RELATIVE_LOCATION_DISTANCE = 0.10

# block2blockrelativelocation: offsets from the target block, cardinal 0.08, diagonal (+-0.04, +-0.04).
B2B_RELATIVE_CARDINAL_OFFSET = 0.08
B2B_RELATIVE_DIAGONAL_OFFSET = 0.04
B2B_RELATIVE_DISTANCE = 0.04
B2B_RELATIVE_SCALES = (0.5, 1.1, 10)  # linspace(start, stop, num) of offset scales counted as "on the line"
B2B_RELATIVE_PUSH_SCALE = 0.8  # where a scripted pusher aims: mid-band, so small overshoot still succeeds
B2B_RELATIVE_DRAGGED = 0.05  # the target block may move at most this far

# separate
SEPARATE_JOINED_DISTANCE = 0.08  # blocks closer than this (centres) are neighbours
SEPARATE_MAGNITUDE = 0.1
SEPARATE_DISTANCE = 0.025
