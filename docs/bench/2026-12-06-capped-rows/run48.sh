#!/bin/bash
# Item 2: compare.py speed against Mitsuba 3 cuda_ad_rgb, 1080p, 256 spp, the three scenes.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
[ -x /tmp/cltrace ] || { xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace; }
[ -d /tmp/site ] || (cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz)
nvidia-smi --query-gpu=name,uuid --format=csv,noheader
PYTHONPATH=/tmp/site timeout ${COMPARE_LIMIT:-260} python3 scripts/mitsuba/compare.py speed --variant cuda_ad_rgb --cltrace /tmp/cltrace --devices gpu \
  --size 1920x1080 --spp 256 --max-bounces 8 --scenes cornell,gold,glass --repetitions 3 --out /tmp/spm 2>&1 | grep -vE "^\s*$" | tail -40 | tee -a $OUT/mitsuba.txt
