"""A virtual SO-101 bench: LeRobot's unmodified `so101_follower` driver and camera classes connect to it as to the arm
(a Feetech bus on a pseudo-terminal, a MuJoCo arm and table, a camera publisher, a scripted operator)."""
