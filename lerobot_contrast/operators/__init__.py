"""Who stages and labels trials on a real robot: the operator interface (base.py), the person at the console
(console.py, pair.py for interleaved policies) with its structured channel (channel.py), and the arm that stages and
labels by itself with the calibrated camera."""
