#!/bin/bash
# Camera rays' spread: does the frame's read-back, or its fresh image buffers, move the next
# launch's time? An experimental binary (CLTRACE_EXP: reuse = image buffers kept between
# frames, noread = no read-back), modes alternated, three rounds, bin64, 30 launches.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace-exp.xz > /tmp/cltrace-exp; chmod +x /tmp/cltrace-exp
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
C="--methods cl-bvh --layouts bin64 --rays primary --resolutions 1920x1080 --devices gpu --repetitions 30"
for r in 1 2 3; do
  for m in main reuse noread reuse,noread; do
    CLTRACE_EXP=$m timeout 60 /tmp/cltrace-exp bench $B $D $C 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $m]" '{printf "%s %s median %s min %s Mrays/s %s\n", t, $2, $12, $13, $14}' | tee -a $OUT/modes.txt
  done
done
echo "done at ${SECONDS}s"
