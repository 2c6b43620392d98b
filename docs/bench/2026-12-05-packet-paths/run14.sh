#!/bin/sh
# The packet-paths runs (2026-12-05, tenth session): PoCL on the 2-core machine, main's
# binary (BIN) with kernel directories made from main's cl/ by make-kernel-dirs.py.
# Needs compare.py's scenes in /tmp/sc (scripts/mitsuba/compare.py scenes --out /tmp/sc).
set -e
here=$(cd "$(dirname "$0")" && pwd)
BIN=${BIN:-/work/main/target/release/cltrace}
export BIN CL_CONFIG_USE_VECTORIZER=False DEV=Portable
python3 "$here/make-kernel-dirs.py" /work/main/cl /tmp/k14
# Same random streams: the packet kernel's image against main's (64 spp, 128x128).
for s in gold cornell; do
    "$BIN" render /tmp/sc/$s/scene.toml -q --device Portable --spp 64 --width 128 --height 128 -o /tmp/main_$s.pfm
    CLTRACE_KERNEL_DIR=/tmp/k14/packet "$BIN" render /tmp/sc/$s/scene.toml -q --device Portable --spp 64 --width 128 --height 128 -o /tmp/packet_$s.pfm
    echo "$s: main against packet"
    /opt/cltrace-mitsuba/bin/python "$here/compare-images.py" /tmp/main_$s.pfm /tmp/packet_$s.pfm
done
A="--spp 64 --width 512 --height 512"
python3 "$here/matrix.py" /tmp/sc 3 "$A;$A K=/tmp/k14/packet;$A K=/tmp/k14/packet-bsdf-twice" gold,cornell
python3 "$here/matrix.py" /tmp/sc 3 "$A;$A K=/tmp/k14/movemask;$A K=/tmp/k14/ordered-leaves" gold,glass,cornell
