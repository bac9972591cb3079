"""What the terminal shows of a run: its header and progress bar, one line per trial, the dry-run plan, and how a run
that ends early is said."""
