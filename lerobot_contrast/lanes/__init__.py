"""Lanes: simulated trials side by side, the policy stepping every lane mid-episode in one call (runner.py), with
each lane's own view of the policy (seats.py) and the lane and thread counts an evaluation runs with (choice.py)."""
