"""Several policies on one bench (`--policies=A,B[,C]`): the policy list, the interleaved session and its trial loop,
and its records: the pair directory, the per-pair sequential decisions, the combined comparison and publishing."""
