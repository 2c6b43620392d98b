#!/bin/bash
# Registers of bin64's trace_rays and its speed: kernel copies K (V1: trace_rays reads its
# ray's direction again after the traversal instead of keeping it live; V2: V1 and leaves
# tested one triangle at a time for incoherent rays too) at register caps, as K or K/N
# (CLTRACE_BUILD_OPTIONS=-cl-nv-maxrregcount=N). Round 1 writes each program's PTX
# (cldump.so) and ptxas's registers and spills for it; rounds alternate; tinybvh each round.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT; ROUNDS=${ROUNDS:-2}
CONFIGS=${CONFIGS:-head V1 V2 V2/56 V2/48 head/56}
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
export PATH=$PATH:$(ls -d /usr/local/cuda*/bin 2>/dev/null | head -1)
xz -dc .gpu/cltrace-head.xz > /tmp/cltrace; chmod +x /tmp/cltrace
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1 &
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
C="--methods cl-bvh --layouts bin64 --rays primary,diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 20"
export CLTRACE_KERNEL_CACHE=off
for r in $(seq $ROUNDS); do
  for c in $CONFIGS; do
    k=${c%/*}; cap=""; [ "$c" != "$k" ] && cap="-cl-nv-maxrregcount=${c#*/}"
    kd=""; [ $k != head ] && kd="CLTRACE_KERNEL_DIR=$REPO/.gpu/k-$k"
    pre=""; if [ $r = 1 ]; then d=/tmp/dump/${c//\//-}; mkdir -p $d; pre="LD_PRELOAD=$REPO/.gpu/bin/cldump.so CLDUMP_DIR=$d"; fi
    env $kd $pre CLTRACE_BUILD_OPTIONS="$cap" timeout 120 /tmp/cltrace bench $B $D $C 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $c]" '{printf "%s %s %s median %s min %s Mrays/s %s\n", t, $2, $8, $12, $13, $14}' | tee -a $OUT/bench.txt
  done
  [ $r = 1 ] && wait
  (cd .gpu/tinybvh && for m in bunny dragon; do timeout 150 /tmp/harness /tmp/data/$m tiles scan d16 2>&1 | grep -E "tinybvh gpu|rror" | sed "s/^/[tinybvh r$r] /"; done) | tee -a $OUT/tinybvh.txt
  echo "round $r done at ${SECONDS}s" | tee -a $OUT/bench.txt
done
for d in /tmp/dump/*; do for b in $d/prog-*.bin; do
  cap=$(grep -o "maxrregcount=[0-9]*" ${b%.bin}.opts | sed 's/.*=/-maxrregcount=/')
  cp $b /tmp/x.ptx; ptxas -arch=sm_90 -v $cap /tmp/x.ptx -o /tmp/x.cubin 2>&1 | grep -E "entry|Used|stack" | sed "s|^|[$(basename $d)] |"
done; done | tee $OUT/registers.txt
echo "all done at ${SECONDS}s" | tee -a $OUT/bench.txt
