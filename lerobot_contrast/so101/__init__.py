"""The SO-101 arm as the evaluator knows it: its model and motors (arm), inverse kinematics (reach) and the
pick-and-place planner (plan), shared by the twin, the demonstrator and the arm that stages trials itself."""

# Each motion's time, as a multiple of the planned one (larger: slower, surer on a loaded machine).
DEFAULT_PACE = 1.5
# Each planned motion of one pick and place (seconds, before the pace): so101/reach.py moves by them, and the
# robot-time cost model plans with their sum.
PICK_AND_PLACE_STEPS = {"open": 1.0, "descend": 0.8, "close": 0.6, "lift": 0.8, "carry": 1.0, "lower": 0.8,
                        "release": 0.5, "clear": 0.3, "retreat": 0.6, "rest": 1.0}  # fmt: skip
PICK_AND_PLACE_S = sum(PICK_AND_PLACE_STEPS.values())
