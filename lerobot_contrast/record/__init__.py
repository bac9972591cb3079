"""Run directories: the append-only journal, the results table and the summary."""
