"""Training the default learned policy: demonstrations, DAgger rounds and LeRobot training runs."""
