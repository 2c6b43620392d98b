#!/bin/bash
# On an H200 the gate (run47.sh) first. Then, on any card: does asking for diffuse-16 rows
# in the same process slow the camera rays measured before them? Bunny, bin64, six
# alternated pairs of processes: primary alone, primary and diffuse-16; the SM and memory
# clocks and the performance state logged every 50 ms meanwhile.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/which.txt
if grep -q H200 $OUT/which.txt; then COMPARE_BEFORE=200 bash .gpu/run47.sh; fi
[ -x /tmp/cltrace ] || { xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace; }
B=.gpu/scenes/stanford_bunny.obj.gz
C="--methods cl-bvh --layouts bin64 --resolutions 1920x1080 --devices gpu --repetitions 20"
nvidia-smi --query-gpu=timestamp,clocks.sm,clocks.mem,pstate,clocks_throttle_reasons.active,power.draw --format=csv,noheader -lms 50 > $OUT/clocks.txt 2>&1 &
SMI=$!
for r in 1 2 3 4 5 6; do
  for v in primary primary,diffuse-16; do
    echo "$(date +%T.%N | cut -c1-12) start r$r $v" >> $OUT/marks.txt
    timeout 60 /tmp/cltrace bench $B $C --rays $v 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $v]" '{printf "%s %s median %s min %s Mrays/s %s\n", t, $8, $12, $13, $14}' | tee -a $OUT/pairs.txt
  done
done
kill $SMI
echo "done at ${SECONDS}s"
