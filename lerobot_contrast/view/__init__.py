"""The run viewer (`python -m lerobot_contrast.view`): a web page of a run's pairs, served or bundled."""
