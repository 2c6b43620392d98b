#!/bin/sh
# Installs the peer renderer of scripts/mitsuba/compare.py: Mitsuba 3 (variant scalar_rgb, CPU
# only) and Dr.Jit from PyPI, with numpy, in a virtual environment at /opt/cltrace-mitsuba
# (override with CLTRACE_MITSUBA_VENV). Idempotent and quiet: when the pinned versions are already
# there it only checks them (well under a second) and prints one line.
set -eu
VENV="${CLTRACE_MITSUBA_VENV:-/opt/cltrace-mitsuba}"
MITSUBA=3.9.1
DRJIT=1.5.0
PY="$VENV/bin/python"

installed() {
    [ -x "$PY" ] && "$PY" - "$MITSUBA" "$DRJIT" <<'EOF' 2>/dev/null
import sys
from importlib.metadata import version
ok = version("mitsuba") == sys.argv[1] and version("drjit") == sys.argv[2]
import numpy  # noqa: F401
sys.exit(0 if ok else 1)
EOF
}

if installed; then
    echo "mitsuba $MITSUBA and drjit $DRJIT are installed in $VENV"
    exit 0
fi

if ! python3 -c 'import venv, ensurepip' >/dev/null 2>&1; then
    if [ "$(id -u)" -eq 0 ]; then SUDO=""; else SUDO="sudo"; fi
    $SUDO apt-get update -qq
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv >/dev/null
fi
[ -x "$PY" ] || python3 -m venv "$VENV"
"$PY" -m pip install -q --disable-pip-version-check \
    "mitsuba==$MITSUBA" "drjit==$DRJIT" numpy
installed || { echo "mitsuba set-up failed: $VENV lacks mitsuba $MITSUBA or drjit $DRJIT" >&2; exit 1; }
echo "mitsuba $MITSUBA and drjit $DRJIT installed in $VENV"
