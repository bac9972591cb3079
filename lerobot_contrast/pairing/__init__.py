"""Interleaved comparisons' records (`--policies=A,B[,C]`): the pair directory, the per-pair sequential decisions, the
combined comparison and publishing. The session itself runs in `interleaved_run.py`, beside the single-policy loop."""
