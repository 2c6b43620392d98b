#!/bin/bash
# Which card: on an H200, items 2-4 (run47.sh); on another card, the z-axis camera rays (run59.sh).
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid --format=csv,noheader | tee $OUT/which.txt
if grep -q H200 $OUT/which.txt; then bash .gpu/run47.sh; else bash .gpu/run59.sh; fi
