import pytest

from lerobot_contrast.contrast.cost import DistanceCost, ResetTimeCost, make_cost_model
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.scene import Pose, Scene


def scene(**objects):
    return Scene({k: Pose(*v) for k, v in objects.items()}, robot=Pose(0.3, 0.0))


def test_distance_is_the_sum_of_planar_displacements():
    before = scene(a=(0.0, 0.0), b=(1.0, 1.0), c=(0.2, 0.2))
    after = scene(a=(0.3, 0.4), b=(1.0, 0.0), c=(0.2, 0.2))
    assert DistanceCost()(before, after) == pytest.approx(0.5 + 1.0)


def test_displacements_within_tolerance_and_yaw_and_robot_are_free():
    before = scene(a=(0.0, 0.0, 0.0))
    after = Scene({"a": Pose(0.004, 0.0, 1.5)}, robot=Pose(9.0, 9.0))
    assert DistanceCost(tolerance=0.005)(before, after) == 0.0
    assert DistanceCost(tolerance=0.001)(before, after) == pytest.approx(0.004)


def test_added_and_removed_objects_are_priced_by_the_handling_distance():
    before = scene(a=(0.0, 0.0))
    after = scene(b=(0.0, 0.0))
    assert DistanceCost()(before, after) == 0.0
    assert DistanceCost(add_remove_m=0.3)(before, after) == pytest.approx(0.6)


def test_reset_time_charges_handling_plus_travel_per_moved_object():
    before = scene(a=(0.0, 0.0), b=(0.0, 1.0))
    after = scene(a=(0.5, 0.0), b=(0.0, 1.0))
    model = ResetTimeCost(per_object_s=2.0, hand_speed_m_s=0.25)
    assert model(before, after) == pytest.approx(2.0 + 0.5 / 0.25)
    assert model(before, before) == 0.0


def test_unknown_cost_model_names_the_flag():
    with pytest.raises(UserError, match="--cost: unknown cost model 'metres'"):
        make_cost_model("metres")
