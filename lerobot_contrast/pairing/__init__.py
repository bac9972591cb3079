"""Interleaved comparisons (`--policies=A,B[,C]`): every planned trial run by each policy in turn from the same staged
scene, one normal run directory per policy inside one pair directory, decided pair by pair as the bases close."""
