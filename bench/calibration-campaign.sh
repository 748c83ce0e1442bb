#!/usr/bin/env bash
# Benchmark: calibrates a paper-sized colour furnace campaign (41 temperatures x 30 exposures x
# 10 frames of 2048x2048, 8 bit, plus 30 x 10 dark frames) and prints the wall time and peak memory.
#
# The simulator needs a few tenths of a second per 2048x2048 frame, so it renders one frame per
# setting (1260 files, 5 GB, once: kept in the work folder) and the manifest lists each file
# FRAMES times. Calibration then reads and averages as many frames as the paper's campaign
# (12 600), one at a time; repeated files come from the page cache, as a fast disk would give them.
# Usage: bench/calibration-campaign.sh [WORK_FOLDER]   (env FRAMES=10, PYROCAM_CALIB=...)
set -euo pipefail
cd "$(dirname "$0")/.."
tool=${PYROCAM_CALIB:-build/calib-tool/pyrocam-calib}
work=${1:-${TMPDIR:-/tmp}/pyrocam-bench-campaign}
frames=${FRAMES:-10}
campaign=$work/campaign
mkdir -p "$work"
if [[ ! -f $campaign/manifest-one-frame.csv ]]; then
  echo "simulating one 2048x2048 frame per setting into $campaign (once) ..."
  python3 bench/run-measured.py "$tool" -q simulate campaign --profile rgb-reference \
    --unit typical --frames 1 --size 2048x2048 --roi-area 10000 --out "$campaign"
  mv "$campaign/manifest.csv" "$campaign/manifest-one-frame.csv"
fi
awk -v n="$frames" 'NR == 1 { print; next } { for (i = 0; i < n; ++i) print }' \
  "$campaign/manifest-one-frame.csv" > "$campaign/manifest.csv"
rows=$(($(wc -l < "$campaign/manifest.csv") - 1))
echo "calibrating $rows frames of 2048x2048 ($(nproc) cores) ..."
python3 bench/run-measured.py "$tool" calibrate --dataset "$campaign" --profile rgb-reference \
  --out "$work/model.json"
