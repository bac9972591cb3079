"""The printed calibration board on the twin's table: the staging board's page as a texture on a thin box, its size
exactly the printed page's, lying where `python -m lerobot_contrast.calibrate --board.*` is told it lies.
"""

from __future__ import annotations

import math

import numpy as np

from lerobot_contrast.staging import board

NAME = "calibration_board"  # the geom's, material's and texture's name in the spec
THICKNESS_M = 0.0005
TEXTURE_DPI = 150  # a 640x480 webcam sees the board at under 10 pixels per millimetre; 150 dpi keeps edges crisp


def add_board(spec, x: float, y: float, yaw_deg: float, surface_z: float = 0.0) -> None:
    """Lay the printed board on the table of `spec` (a `mujoco.MjSpec`), its marker grid centred at (x, y) metres
    in the task's frame and turned `yaw_deg` as `BoardArgs` says; `surface_z` is the table top's height. A board
    already there is moved. Recompile the spec afterwards."""
    import mujoco

    remove_board(spec)
    page, per_m = board.page_image(TEXTURE_DPI)
    height_px, width_px = page.shape
    margin = round(board.MARGIN_M * per_m)
    texture = spec.add_texture(name=NAME, type=mujoco.mjtTexture.mjTEXTURE_2D, width=width_px, height=height_px,
                               nchannel=3)  # fmt: skip
    texture.data = np.repeat(page[..., None], 3, axis=2).tobytes()
    # Matte paper: no highlight from the lamps washes the markers out.
    material = spec.add_material(name=NAME, specular=0.0, shininess=0.0, reflectance=0.0)
    material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = NAME
    # The page's centre, in the marker grid's frame, then on the table.
    centre = np.array([[width_px / 2 - margin, height_px / 2 - margin]]) / per_m
    table_xy = board.board_to_table(centre, board.BoardArgs(x=x, y=y, yaw_deg=yaw_deg))[0]
    # MuJoCo maps a 2D texture onto a box's top face with the image's columns along the box's x and its rows down
    # its -y: the box's x is the page's right edge direction, which lies at yaw - 90 degrees on the table.
    turn = math.radians(yaw_deg - 90) / 2
    spec.worldbody.add_geom(
        name=NAME,
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[width_px / per_m / 2, height_px / per_m / 2, THICKNESS_M / 2],
        pos=[table_xy[0], table_xy[1], surface_z + THICKNESS_M / 2],
        quat=[math.cos(turn), 0.0, 0.0, math.sin(turn)],
        material=NAME,
        # Paper does not push cubes about: the board is seen, never collided with.
        contype=0,
        conaffinity=0,
    )


def remove_board(spec) -> bool:
    """Take the board off the table of `spec`; False if there was none."""
    found = False
    for element in (spec.geom(NAME), spec.material(NAME), spec.texture(NAME)):
        if element is not None:
            spec.delete(element)
            found = True
    return found
