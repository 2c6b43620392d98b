#!/bin/bash
# Which card: on an H200, items 2-4 (run47.sh, which runs run48.sh if time allows); on another
# card, the vload3 rows in render's path program (run49.sh) unless NO_EXPERIMENT is set.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid --format=csv,noheader | tee $OUT/which.txt
if grep -q H200 $OUT/which.txt; then bash .gpu/run47.sh; elif [ -z "${NO_EXPERIMENT:-}" ]; then bash .gpu/run49.sh; fi
