"""The spine of an evaluation: its settings and flags (config, flags), the robot, policy and operator it builds
(build), the plan and the run directory it sets up (run_setup), the trial loop (evaluation), one trial on a LeRobot
robot (runner), and how a run that ends early is said (run_end). The commands at the package's root call it."""
