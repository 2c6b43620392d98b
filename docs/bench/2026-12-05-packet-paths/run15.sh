#!/bin/sh
# The second batch of the packet-paths runs: the packet kernel on Intel's runtime and at 4
# and 16 lanes, and the ray-setup variants, on the 2-core machine. As run14.sh.
set -e
here=$(cd "$(dirname "$0")" && pwd)
BIN=${BIN:-/work/main/target/release/cltrace}
export BIN CL_CONFIG_USE_VECTORIZER=False
python3 "$here/make-kernel-dirs.py" /work/main/cl /tmp/k14
A="--spp 64 --width 512 --height 512"
echo "## Intel's runtime"
DEV=Intel python3 "$here/matrix.py" /tmp/sc 3 "$A;$A K=/tmp/k14/packet" gold,cornell
echo "## PoCL: lanes, and the per-lane part twice"
DEV=Portable python3 "$here/matrix.py" /tmp/sc 3 "$A;$A K=/tmp/k14/packet;$A K=/tmp/k14/packet-4;$A K=/tmp/k14/packet-16;$A K=/tmp/k14/packet-lane-part-twice" gold
echo "## PoCL: ray setup"
DEV=Portable python3 "$here/matrix.py" /tmp/sc 3 "$A;$A K=/tmp/k14/ray-setup-twice;$A K=/tmp/k14/vector-divisions" gold,glass,cornell
