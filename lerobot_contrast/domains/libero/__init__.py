"""LIBERO through LeRobot's own environment: the four suites as contrast-set tasks (`--task=libero_spatial` ...),
their ΔL/ΔLB/ΔS/ΔSB perturbations, and `--robot.type=libero_sim`. Needs `pip install 'lerobot_contrast[libero]'`."""
