"""Sweeps: many contrast-set evaluations (a grid or list of eval settings) run as Ray tasks, each into its own run
directory under one sweep folder.

- `command`: `python -m lerobot_contrast.sweep SWEEP.yaml`, its flags, the progress view and the sweep's results;
- `cells`: the sweep file, read and expanded into cells (one eval config each);
- `ray_pool`: Ray, local or a cluster, scheduling the cells;
- `worker`: one cell on a worker, through the spine (a policy loads once per worker).
"""
