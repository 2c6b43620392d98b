#!/bin/bash
# Issue 19 on whichever card comes: the SM clock logged every 100 ms through run27.sh (items 3
# and 4, three alternated rounds against tinybvh); on an H200, item 2 against Mitsuba 3 after it.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm,clocks.applications.graphics,power.limit,temperature.gpu --format=csv | tee $OUT/card.txt
nvidia-smi -q -d PERFORMANCE,CLOCK > $OUT/clocks-before.txt 2>&1
nvidia-smi --query-gpu=timestamp,clocks.sm,clocks.mem,power.draw,temperature.gpu,utilization.gpu,clocks_event_reasons.active --format=csv -lms 100 > $OUT/clocks.csv 2>&1 &
LOG=$!
bash .gpu/run27.sh
kill $LOG
nvidia-smi -q -d PERFORMANCE,CLOCK > $OUT/clocks-after.txt 2>&1
if grep -q H200 $OUT/card.txt; then
  mkdir -p target/release
  xz -dc .gpu/cltrace.xz > target/release/cltrace; chmod +x target/release/cltrace
  (cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz)
  PYTHONPATH=/tmp/site timeout 400 python3 scripts/mitsuba/compare.py speed --variant cuda_ad_rgb --cltrace $PWD/target/release/cltrace --devices gpu \
    --size 1920x1080 --spp 256 --max-bounces 8 --scenes cornell,gold,glass --repetitions 2 --out /tmp/spm 2>&1 | tail -20 | tee $OUT/mitsuba.md
fi
