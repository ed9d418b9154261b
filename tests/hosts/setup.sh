#!/usr/bin/env bash
# Installs the print hosts that weft's "send to printer" tests talk to, from PyPI:
#   VENV_DIR               OctoPrint 1.11.8, Pillow, pybgcode (runs hosts.py and check_hosts.py)
#   VENV_DIR/moonraker-env Moonraker 0.11.0 (it pins pyserial==3.4, OctoPrint needs >=3.5)
# Usage: tests/hosts/setup.sh VENV_DIR        (weft passes target/hosts-venv)
# Idempotent: a stamp holds the hash of the requirement files, this script and the Python
# version; when it matches, nothing is done. When it does not, the venvs are made anew.
# PYTHON=... picks the interpreter (default python3; OctoPrint 1.11 needs 3.7-3.13, Moonraker
# 0.11 needs >= 3.10). netifaces (an OctoPrint dependency) has no wheel and builds with cc.
set -euo pipefail

if [ $# -ne 1 ]; then
  echo "usage: $0 VENV_DIR" >&2
  exit 2
fi
here=$(cd "$(dirname "$0")" && pwd)
venv=$1
py=${PYTHON:-python3}
start=$(date +%s.%N)

"$py" - <<'EOF' || { echo "setup.sh: $py must be Python 3.10 to 3.13" >&2; exit 1; }
import sys
sys.exit(0 if (3, 10) <= sys.version_info[:2] <= (3, 13) else 1)
EOF

want=$( { cat "$here/requirements-octoprint.txt" "$here/requirements-moonraker.txt" "$here/setup.sh"
          "$py" -c 'import sys; print(sys.version)'; } | sha256sum | cut -d' ' -f1)
stamp="$venv/.weft-hosts-stamp"

elapsed() { awk -v s="$start" -v e="$(date +%s.%N)" 'BEGIN { printf "%.1f", e - s }'; }

if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ] \
   && [ -x "$venv/bin/python" ] && [ -x "$venv/moonraker-env/bin/python" ]; then
  echo "hosts venv up to date: $venv ($(elapsed) s)"
  exit 0
fi

mkdir -p "$(dirname "$venv")"
# One install at a time for this VENV_DIR (two test runs starting together).
exec 9>"$venv.lock"
flock -w 600 9 || { echo "setup.sh: could not lock $venv.lock" >&2; exit 1; }
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  echo "hosts venv up to date: $venv ($(elapsed) s, installed by another run)"
  exit 0
fi

if [ -e "$venv" ]; then
  # Only ever remove what looks like a venv (never a wrong path given by mistake).
  if [ ! -f "$venv/pyvenv.cfg" ]; then
    echo "setup.sh: $venv exists and is not a venv; not touching it" >&2
    exit 1
  fi
  rm -rf "$venv"
fi

echo "== installing print hosts into $venv (OctoPrint, then Moonraker)"
pip_flags=(--disable-pip-version-check --no-input -q)
"$py" -m venv "$venv"
"$venv/bin/python" -m pip install "${pip_flags[@]}" -r "$here/requirements-octoprint.txt"
"$py" -m venv "$venv/moonraker-env"
"$venv/moonraker-env/bin/python" -m pip install "${pip_flags[@]}" -r "$here/requirements-moonraker.txt"

# Fail now, not at test time, if an import is broken.
"$venv/bin/python" -c 'import octoprint, PIL, pybgcode'
"$venv/moonraker-env/bin/python" -c 'import moonraker.server, libnacl'

echo "$want" > "$stamp"
echo "hosts venv installed: $venv ($(elapsed) s)"
