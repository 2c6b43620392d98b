#!/bin/bash
# CPU (this 2-core AVX-512 EPYC): diffuse-16 at 1920x1080, the batch as given, sorted on the host
# (untimed) and sorted on the device (timed); PoCL (1:0) and Intel's runtime (0:0), wide8 and bin64.
cd /work/main
row() { grep -E "^\| stanford|rror" | awk -F'|' -v t="$1" '{printf "%s %s %s %s median %s min %s Mrays/s %s\n", t, $2, $5, $7, $12, $13, $14}'; }
for r in 1 2; do for v in none 16,1 16,4 16,8 c4096,8 d4,4 d5,4 d5,8; do
  unset CLTRACE_DIR_SORT CLTRACE_DEVICE_SORT
  case $v in none) ;; d*) export CLTRACE_DEVICE_SORT=${v#d};; *) export CLTRACE_DIR_SORT=$v;; esac
  env CLTRACE_SORT_VERBOSE=1 timeout 900 ./target/release/cltrace bench ../shared/scenes/stanford_bunny.obj ../shared/scenes/stanford_dragon.obj.gz --methods cl-bvh --layouts wide8,bin64 --rays diffuse-16 --resolutions 1920x1080 --devices 1:0,0:0 --repetitions 3 > /tmp/cpusort/b.txt 2>&1
  row "[r$r $v]" < /tmp/cpusort/b.txt
  grep "device sort" /tmp/cpusort/b.txt | awk 'NR%4==0' | sed "s/^/[r$r $v] /"
done; done
