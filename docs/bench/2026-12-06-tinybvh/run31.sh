#!/bin/bash
# On an H200: run30.sh (items 2, 3 and 4 with the clock log). On another card: only what
# the pitched images' rows are padded to (CL_DEVICE_MEM_BASE_ADDR_ALIGN), then out.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid --format=csv,noheader | tee $OUT/which.txt
clinfo 2>/dev/null | grep -iE "Device Name|Base address alignment|Platform Name" | tee $OUT/align.txt
if grep -q H200 $OUT/which.txt; then bash .gpu/run30.sh; fi
