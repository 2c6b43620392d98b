#!/bin/sh
# Installs Intel's oneAPI OpenCL runtime for the CPU, a second OpenCL implementation beside
# PoCL, from its PyPI wheels: into a virtual environment in /opt/cltrace-intel-opencl, with an
# ICD file in /etc/OpenCL/vendors naming its libintelocl.so, so that the system's OpenCL
# loader (ocl-icd) lists it as the platform "Intel(R) OpenCL". Idempotent; run as root or as
# a user with sudo, after scripts/setup-debian.sh (which installs the loader and clinfo).
#
# /opt, not a home folder: the ICD file is system-wide, so the library it names must be at a
# fixed path that every user (and CI, whatever its HOME) can read.
#
# No LD_LIBRARY_PATH and no /etc/ld.so.conf.d entry: libintelocl.so finds its own libraries
# through its RUNPATH ($ORIGIN). Putting its folder on the library path would be harmful, as
# the wheel ships a libOpenCL.so.1 of its own that would then shadow the system's loader.
set -eu
VENV=/opt/cltrace-intel-opencl
ICD=/etc/OpenCL/vendors/cltrace-intel-cpu.icd
# Pinned, dependencies included: this runtime's compiler and results are what CI checks.
PACKAGES="intel-opencl-rt==2026.2.0 intel-cmplr-lib-rt==2026.2.0 intel-cmplr-lic-rt==2026.2.0
    tbb==2023.2.0 tcmlib==1.6.0"
if [ "$(id -u)" -eq 0 ]; then SUDO=""; else SUDO="sudo"; fi

# Debian's own Python, not whatever python3 comes first on PATH (pyenv, conda): the venv
# must outlive the user's environment.
if ! /usr/bin/python3 -c 'import ensurepip, venv' >/dev/null 2>&1; then
    $SUDO apt-get update -qq
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv >/dev/null
fi
if [ ! -x "$VENV/bin/pip" ]; then
    $SUDO /usr/bin/python3 -m venv "$VENV"
fi
# Already-installed pinned versions are not downloaded again.
# shellcheck disable=SC2086
$SUDO "$VENV/bin/pip" install -q --disable-pip-version-check --no-cache-dir $PACKAGES

LIB="$VENV/lib/libintelocl.so"
if ldd "$LIB" | grep -q "not found"; then
    echo "error: $LIB misses libraries:" >&2
    ldd "$LIB" | grep "not found" >&2
    exit 1
fi
if [ "$(cat "$ICD" 2>/dev/null || true)" != "$LIB" ]; then
    $SUDO mkdir -p /etc/OpenCL/vendors
    echo "$LIB" | $SUDO tee "$ICD" >/dev/null
fi

# The loader in use must stay the system's, and it must list the new platform.
if command -v clinfo >/dev/null 2>&1; then
    case "$(ldd "$(command -v clinfo)" | grep libOpenCL.so)" in
        *"$VENV"*)
            echo "error: clinfo loads the venv's libOpenCL.so, not the system's loader" >&2
            exit 1
            ;;
    esac
    if ! clinfo -l | grep -q "Intel(R) OpenCL"; then
        echo "error: the OpenCL loader does not list Intel's platform (see $ICD)" >&2
        exit 1
    fi
fi
echo "set-up done: Intel's OpenCL CPU runtime is in $VENV, listed by $ICD"
