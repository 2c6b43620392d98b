#!/bin/bash
# Item 1 with compare.py speed's renderers alternated within each repetition: three runs of
# five repetitions (a warm-up and four timed) on 2 cores, Mitsuba 3 llvm_ad_rgb against
# cltrace on Intel's runtime (0:0) and PoCL (1:0).
cd "$(dirname "$0")/../../.."
for r in 1 2 3; do
  echo "## run $r $(date -u +%H:%M)"
  DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 timeout 1200 /opt/cltrace-mitsuba/bin/python scripts/mitsuba/compare.py speed --variant llvm_ad_rgb --cltrace target/release/cltrace --devices 0:0,1:0 --size 512x512 --spp 64 --max-bounces 8 --scenes cornell,gold,glass --repetitions 4 --out /tmp/spc
done
