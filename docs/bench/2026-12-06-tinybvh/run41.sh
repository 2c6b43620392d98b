#!/bin/bash
# Strips of 4 groups against rows on generated hillsides (bench --scaling, 10 thousand to 30
# million triangles), two rounds alternated; and what the card reports as its cache.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version --format=csv,noheader | tee $OUT/gpu.txt
clinfo 2>/dev/null | grep -iE "Device Name|Global memory cache|cache line" | tee $OUT/cache.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
one() { # name options
  env CLTRACE_KERNEL_DIR=$PWD/.gpu/k-order "CLTRACE_BUILD_OPTIONS=$2" timeout 200 /tmp/cltrace bench --scaling --scaling-to 30M --methods cl-bvh --layouts bin64 --rays primary --devices gpu --repetitions 10 2>&1 | grep -E "^\| hill|rror" | awk -F'|' -v r=$r -v n=$1 '{print "r" r, n, $3, $9, $11}' | tee -a $OUT/hills.txt
}
for r in 1 2; do
  one rows ""
  one S4 "-DSTRIP_GROUPS=4"
done
