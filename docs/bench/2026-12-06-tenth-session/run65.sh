#!/bin/bash
# On an H200 only: items 2 and 3 with the head's binary (run47.sh, one round, then compare.py
# against Mitsuba 3 cuda_ad_rgb); on another card nothing.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid --format=csv,noheader | tee $OUT/which.txt
if grep -q H200 $OUT/which.txt; then ROUNDS=1 COMPARE_BEFORE=100 COMPARE_LIMIT=240 bash .gpu/run47.sh; fi
