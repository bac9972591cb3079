"""Runners: how a trial is executed (in a gymnasium simulator, or on a LeRobot robot)."""
