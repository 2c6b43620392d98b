#!/bin/sh
# Installs what cltrace needs on Debian or Ubuntu: PoCL (an OpenCL driver for the CPU), the
# OpenCL ICD loader and headers, a C toolchain, and Rust through rustup if cargo is missing.
# Run as root or as a user with sudo.
set -eu
if [ "$(id -u)" -eq 0 ]; then SUDO=""; else SUDO="sudo"; fi
$SUDO apt-get update -qq
$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
    pocl-opencl-icd ocl-icd-opencl-dev clinfo build-essential curl ca-certificates >/dev/null
if ! command -v cargo >/dev/null 2>&1 && [ ! -x "$HOME/.cargo/bin/cargo" ]; then
    curl -sSf https://sh.rustup.rs | sh -s -- -y --profile minimal >/dev/null
fi
echo "set-up done: PoCL, the OpenCL loader and Rust are installed"
