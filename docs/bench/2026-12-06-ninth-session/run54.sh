#!/bin/bash
# Item 4's spread: is cltrace's camera-ray speed set per process, per allocation, or by the
# program cache? Separate processes (cache on, cache off), then one process measuring the
# bunny six times, then one alternating bunny and dragon; clocks sampled alongside.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
C="--methods cl-bvh --layouts bin64 --rays primary --resolutions 1920x1080 --devices gpu --repetitions 30"
nvidia-smi --query-gpu=timestamp,clocks.sm,clocks.mem,power.draw,temperature.gpu,clocks_throttle_reasons.active --format=csv -lms 250 > $OUT/smi.csv &
SMI=$!
row() { grep -E "^\| stanford" | awk -F'|' '{printf "%s median %s min %s Mrays/s %s\n", $2, $12, $13, $14}'; }
{
echo "A: eight processes, bunny, program cache on"
for i in 1 2 3 4 5 6 7 8; do timeout 60 /tmp/cltrace bench $B $C 2>&1 | row; done
echo "A2: four processes, bunny, program cache off"
for i in 1 2 3 4; do CLTRACE_KERNEL_CACHE=off timeout 60 /tmp/cltrace bench $B $C 2>&1 | row; done
echo "B: one process, the bunny six times"
timeout 90 /tmp/cltrace bench $B $B $B $B $B $B $C 2>&1 | row
echo "C: one process, bunny and dragon alternated"
timeout 90 /tmp/cltrace bench $B $D $B $D $B $D $C 2>&1 | row
echo "D: four processes, bunny then dragon"
for i in 1 2 3 4; do timeout 60 /tmp/cltrace bench $B $D $C 2>&1 | row; done
} | tee $OUT/spread.txt
kill $SMI
echo "done at ${SECONDS}s"
