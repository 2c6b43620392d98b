#!/bin/bash
# Item 2's glass (and gold, box) on the GPU: layouts and leaf sizes of the path programs;
# on an H200 also Mitsuba 3 cuda_ad_rgb in the same run.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
[ -e /work/main ] || { mkdir -p /work; ln -s $REPO /work/main; }
mkdir -p /work/main/target/release
xz -dc .gpu/cltrace.xz > /work/main/target/release/cltrace; chmod +x /work/main/target/release/cltrace
B=/work/main/target/release/cltrace
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
cp -r .gpu/sp /tmp/sp
BIN=$B timeout 330 python3 .gpu/matrix.py /tmp/sp 3 "--layout bin64;--layout cwbvh;--layout bin32;--layout wide4;--layout wide8;--max-leaf-size 1;--max-leaf-size 2;--max-leaf-size 4" glass,gold,cornell 2>&1 | tee $OUT/layouts.txt
if nvidia-smi --query-gpu=name --format=csv,noheader | grep -q H200 && [ -e .gpu/site.tar.xz ]; then
  (cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz)
  PYTHONPATH=/tmp/site timeout 200 python3 scripts/mitsuba/compare.py speed --variant cuda_ad_rgb --cltrace $B --devices gpu \
    --size 1920x1080 --spp 256 --max-bounces 8 --scenes cornell,gold,glass --repetitions 3 --out /tmp/spm 2>&1 | tail -14 | tee $OUT/mitsuba.md
fi
