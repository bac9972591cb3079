"""Whose time the robot runs on: the wall clock, or the virtual SO-101's simulated clock (robot_clock.py), and the
simulated clock's client (simulated.py). Below every folder that waits for the robot, so each may import it."""
