"""The SO-101 arm as the evaluator knows it: its model and motors (arm), inverse kinematics (reach) and the
pick-and-place planner (plan), shared by the twin, the demonstrator and the arm that stages trials itself."""

# Each motion's time, as a multiple of the planned one (larger: slower, surer on a loaded machine).
DEFAULT_PACE = 1.5
