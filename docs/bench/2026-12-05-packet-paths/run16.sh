#!/bin/sh
# The third batch: cachegrind's counts of the traversal variants (each with its trace a
# function of its own), their speed, main's trace as a function, and PoCL 7.1 (if
# build-pocl7.sh has run). PoCL 3.1 on the 2-core machine; as run14.sh.
set -e
here=$(cd "$(dirname "$0")" && pwd)
BIN=${BIN:-/work/main/target/release/cltrace}
export BIN CL_CONFIG_USE_VECTORIZER=False
python3 "$here/make-kernel-dirs.py" /work/main/cl /tmp/k14
echo "## cachegrind (--branch-sim=yes): the trace function's instructions, conditional"
echo "## branches and their simulated mispredicts; 128x128, 16 spp"
for s in glass gold; do
    for v in main shuffle movemask shuffle-movemask ordered-leaves vector-divisions; do
        k=/tmp/k14/$v-noinline
        # Compiled once outside valgrind, so that only the render is counted.
        CLTRACE_KERNEL_DIR=$k "$BIN" render /tmp/sc/$s/scene.toml -q --device Portable --spp 1 --width 8 --height 8 -o /tmp/cg.pfm
        CLTRACE_KERNEL_DIR=$k valgrind --tool=cachegrind --cache-sim=no --branch-sim=yes \
            --cachegrind-out-file=/tmp/cg.out "$BIN" render /tmp/sc/$s/scene.toml -q --device Portable \
            --spp 16 --width 128 --height 128 -o /tmp/cg.pfm >/dev/null 2>&1
        echo "$s $v: $(cg_annotate /tmp/cg.out | grep -E ':trace$' | tr -s ' ')"
    done
done
A="--spp 64 --width 512 --height 512"
echo "## PoCL 3.1: the variants' speed"
DEV=Portable python3 "$here/matrix.py" /tmp/sc 5 "$A;$A K=/tmp/k14/shuffle;$A K=/tmp/k14/shuffle-movemask" gold,glass,cornell
echo "## PoCL 3.1: main's trace as a function of its own; PoCL 7.1"
configs="$A;$A K=/tmp/k14/main-noinline"
[ -e /tmp/icd7/pocl7.icd ] && configs="$configs;$A E=OCL_ICD_VENDORS=/tmp/icd7"
DEV=Portable python3 "$here/matrix.py" /tmp/sc 3 "$configs" gold,glass,cornell
