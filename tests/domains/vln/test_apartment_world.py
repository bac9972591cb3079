"""The simulated apartment: furniture placement, a disc robot that stops at or slides along obstacles."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.domains.vln.apartment import Apartment, furniture_for


def room_with(collision: str, **objects: Pose) -> Apartment:
    apartment = Apartment(collision=collision)
    apartment.set_scene(objects, Pose(1.0, 3.0, 0.0))
    return apartment


def test_driving_into_furniture_stops_at_contact_in_stop_mode():
    apartment = room_with("stop", couch=Pose(3.0, 3.0, math.pi / 2))  # its near face at x = 3 - 0.425
    assert apartment.forward(2.0)
    assert apartment.bumped
    assert apartment.pose.x == pytest.approx(3.0 - 0.425 - 0.18, abs=0.021)
    assert apartment.clearance(np.array([apartment.pose.x, apartment.pose.y])) >= 0
    apartment.rotate(math.pi)  # turning in place never collides
    assert not apartment.bumped and not apartment.forward(0.5)
    assert apartment.pose.x == pytest.approx(3.0 - 0.425 - 0.18 - 0.5, abs=0.021)


def test_sliding_keeps_the_motion_along_a_wall():
    slide, stop = room_with("slide"), room_with("stop")
    for apartment in (slide, stop):
        apartment.place_robot(Pose(1.0, 5.5, math.radians(60)))  # towards the wall at y = 6, at an angle
        assert apartment.forward(1.0)
    assert stop.pose.y == pytest.approx(6.0 - 0.18, abs=0.02) and stop.pose.x < 1.3
    assert slide.pose.y == pytest.approx(6.0 - 0.18, abs=0.02) and slide.pose.x > stop.pose.x + 0.2


def test_velocity_driving_integrates_turn_and_speed():
    apartment = room_with("slide")
    for _ in range(10):
        apartment.drive(0.2, math.radians(90), 0.1)
    assert apartment.pose.yaw == pytest.approx(math.radians(90))
    assert math.dist((apartment.pose.x, apartment.pose.y), (1.0, 3.0)) == pytest.approx(
        0.2 * 2 * math.sqrt(2) / math.pi, abs=0.02
    )


def test_bad_scenes_are_refused_naming_the_problem():
    apartment = Apartment()
    with pytest.raises(ValueError, match="collides with bed"):
        apartment.set_scene({"bed": Pose(4.0, 3.0)}, Pose(4.0, 3.5))
    with pytest.raises(ValueError, match="bookshelf at .* is outside the room"):
        apartment.set_scene({"bookshelf": Pose(0.1, 3.0)}, None)
    with pytest.raises(ValueError, match="unknown furniture 'piano'"):
        apartment.set_scene({"piano": Pose(4.0, 3.0)}, None)
    with pytest.raises(ValueError, match="collision must be one of"):
        Apartment(collision="bounce")
    assert furniture_for("chair_2").category == "chair"
