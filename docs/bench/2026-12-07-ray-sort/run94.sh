#!/bin/bash
# run94: the diffuse-16 batches sorted on the host (untimed: an upper bound) by pixel tile and
# the direction's octahedral cell (CLTRACE_DIR_SORT=T,B: T x T pixel tiles, B x B cells;
# cltrace-dir.xz = branch dirsort), bin64 and cwbvh, alternated rounds; then tinybvh's
# kernels on the same sorted batches (raydump-dir.xz, the harness's dump against the branch).
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT; ROUNDS=${ROUNDS:-2}
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace-dir.xz > /tmp/cltrace-dir; chmod +x /tmp/cltrace-dir
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump-dir.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
TB=${TB:-none 16,4 32,8}
mkdir -p /tmp/data
(for v in $TB; do for m in bunny dragon; do
  if [ $v = none ]; then /tmp/raydump .gpu/scenes/stanford_$m.obj.gz /tmp/data/$v-$m; else CLTRACE_DIR_SORT=$v /tmp/raydump .gpu/scenes/stanford_$m.obj.gz /tmp/data/$v-$m; fi
done; done) > $OUT/raydump.txt 2>&1 &
row() { grep -E "^\| stanford|rror" | awk -F'|' -v t="$1" '{printf "%s %s %s %s median %s min %s Mrays/s %s\n", t, $2, $5, $8, $12, $13, $14}'; }
for r in $(seq $ROUNDS); do for v in ${SORTS:-none 16,1 16,4 16,8 32,8 c4096,8 d4,4 d5,4 d4,8 d5,8}; do
  [ $SECONDS -lt ${UNTIL:-330} ] || break
  unset CLTRACE_DIR_SORT CLTRACE_DEVICE_SORT
  case $v in none) ;; d*) export CLTRACE_DEVICE_SORT=${v#d};; *) export CLTRACE_DIR_SORT=$v;; esac
  env CLTRACE_SORT_VERBOSE=1 $([ $r = 1 ] && echo CLTRACE_SORT_CHECK=1) timeout 120 /tmp/cltrace-dir bench $B $D --methods cl-bvh --layouts bin64,cwbvh --rays diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 10 > /tmp/b.txt 2>&1
  row "[r$r sort $v]" < /tmp/b.txt | tee -a $OUT/dir.txt
  grep -E "device sort" /tmp/b.txt | awk 'NR%11==0' | sed "s/^/[r$r $v] /" | tee -a $OUT/dir.txt
  grep -E "CHECK" /tmp/b.txt | sort | uniq -c | sed "s/^/[r$r $v] /" | tee -a $OUT/dir.txt
done; done
unset CLTRACE_DIR_SORT CLTRACE_DEVICE_SORT
echo "bench done at ${SECONDS}s" | tee -a $OUT/dir.txt
wait
(cd .gpu/tinybvh && for v in $TB; do for m in bunny dragon; do timeout 100 /tmp/harness /tmp/data/$v-$m d16 2>&1 | grep -E "tinybvh|rror" | sed "s/^/[tinybvh sort $v] /"; done; done) | tee -a $OUT/tinybvh.txt
echo "run94 done at ${SECONDS}s" | tee -a $OUT/dir.txt
