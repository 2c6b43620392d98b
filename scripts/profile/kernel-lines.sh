#!/bin/sh
# Exact instruction counts of one PoCL kernel by source line (kernel_lines.py), for a
# render on one thread:
#
#   scripts/profile/kernel-lines.sh KERNEL SAMPLES -- CLTRACE_RENDER_ARGS...
#   scripts/profile/kernel-lines.sh sample_path 262144 -- scene.toml -q -o /tmp/p.pfm
#
# SAMPLES divides the counts (width x height x spp for a sample kernel). Needs valgrind
# and a release build. The first run, under valgrind's no-op tool, fills a fresh PoCL
# cache with the kernel built for the CPU valgrind shows PoCL (which may lack the host's
# widest vectors) and with line tables (-g); the second counts the kernel alone.
# CLTRACE_KERNEL_DIR and CLTRACE_BUILD_OPTIONS pass on (-g is added).
set -eu
if [ $# -lt 4 ] || [ "$3" != "--" ]; then
    echo "usage: $0 KERNEL SAMPLES -- CLTRACE_RENDER_ARGS..." >&2
    exit 2
fi
kernel=$1 samples=$2
shift 3
root=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d)
export POCL_CACHE_DIR="$work/pocl" POCL_MAX_PTHREAD_COUNT=1 CLTRACE_KERNEL_CACHE=off
export CLTRACE_DEVICE="${CLTRACE_DEVICE:-Portable Computing Language}"
export CLTRACE_BUILD_OPTIONS="-g ${CLTRACE_BUILD_OPTIONS:-}"
valgrind --tool=none -q "$root/target/release/cltrace" render "$@" > /dev/null
valgrind --tool=callgrind --dump-instr=yes --toggle-collect="_pocl_kernel_${kernel}_workgroup" \
    --callgrind-out-file="$work/callgrind.out" -q "$root/target/release/cltrace" render "$@" > /dev/null
so=$(find "$work/pocl" -name "$kernel.so" | head -n 1)
python3 "$root/scripts/profile/kernel_lines.py" "$work/callgrind.out" "$so" "${CLTRACE_KERNEL_DIR:-$root/cl}" "$kernel" "$samples" "${LINES:-40}"
rm -rf "$work"
