#!/usr/bin/env bash
# ROS Noetic runs Python 3.8: run the ROS-free unit tests under a Python 3.8 interpreter, in .venv38/
# with requirements.txt (its Python 3.8 pins), and byte-compile every Python file of the package with it.
# Uses python3.8 from PATH, or pyenv's; says so and fails when there is none.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"

py=
# (a pyenv shim on PATH may exist and still refuse to run, so each candidate is tried)
for candidate in $(command -v python3.8 || true) "${PYENV_ROOT:-$HOME/.pyenv}"/versions/3.8*/bin/python3.8; do
  if [ -x "$candidate" ] && "$candidate" -c 'import sys; assert sys.version_info[:2] == (3, 8)' 2>/dev/null; then
    py=$candidate
    break
  fi
done
if [ -z "$py" ]; then
  echo "compat: no Python 3.8 found (python3.8 on PATH or in pyenv); nothing checked" >&2
  exit 1
fi
venv=.venv38
stamp="$venv/.requirements.sha256"
want=$(cat requirements.txt tools/compat.sh | sha256sum | cut -d' ' -f1)
if [ ! -x "$venv/bin/python" ] || [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  echo "compat: making $venv from $py"
  rm -rf "$venv"
  "$py" -m venv "$venv"
  # Beside the pinned PyPI packages, what Debian gives the main venv that the unit tests import: PyYAML, and
  # cryptography at Debian bookworm's version (python3-cryptography 38.0.4; the certificates' tests).
  "$venv/bin/python" -m pip install -q --disable-pip-version-check -r requirements.txt \
    PyYAML==6.0.2 pytest==8.3.5 cryptography==38.0.4
  echo "$want" > "$stamp"
fi
"$venv/bin/python" --version
"$venv/bin/python" -m compileall -q -x '/\.' src scripts test tools setup.py >/dev/null
find src scripts test tools -name '*.cpython-38.pyc' -delete
echo "compat: every Python file compiles under Python 3.8"
PYTHONDONTWRITEBYTECODE=1 "$venv/bin/python" -m pytest -q -p no:cacheprovider test/unit
