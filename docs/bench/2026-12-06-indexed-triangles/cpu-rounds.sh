#!/bin/bash
# three rounds of compare.py speed on 2 cores (Mitsuba llvm_ad_rgb, Intel 0:0, PoCL 1:0)
cd "$(dirname "$0")/../../.."
for r in 1 2 3; do
  echo "## round $r $(date -u +%H:%M)"
  DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 timeout 1200 /opt/cltrace-mitsuba/bin/python scripts/mitsuba/compare.py speed --variant llvm_ad_rgb --cltrace target/release/cltrace --devices 0:0,1:0 --size 512x512 --spp 64 --max-bounces 8 --scenes cornell,gold,glass --repetitions 3 --out /tmp/spc
done
