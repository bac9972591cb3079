"""Simulated chains of trials side by side in one process (`--lanes`): how many, each lane's seat on the policy, and
the loop that steps them."""
