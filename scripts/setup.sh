#!/usr/bin/env bash
# Create .venv (Python 3.12, chosen by .python-version) and install the repository's distributions editable.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -x .venv/bin/python ]; then
  "${PYTHON:-python3.12}" -m venv .venv
fi
.venv/bin/python -m pip install --quiet --disable-pip-version-check \
  -e protocols/navigation_protocol \
  -e robots/lerobot_robot_locobot \
  -e policies/lerobot_policy_language_table \
  -e policies/lerobot_policy_tabletop_pointer \
  -e envs/lerobot_env_language_table \
  -e policies/lerobot_policy_vln_navigator \
  -e '.[dev]'
