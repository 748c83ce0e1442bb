#!/usr/bin/env bash
# Makes a small calibrated model for the element and pipeline tests: a short simulated furnace
# campaign of a typical unit, calibrated with a short MLP training. Plumbing tests only: its
# network is not trained to the product's accuracy (pyrocam-calib's defaults are).
# Usage: make-test-model.sh PYROCAM_CALIB PROFILE SIZE ROI_AREA OUT_MODEL
set -euo pipefail
tool=$1 profile=$2 size=$3 roi_area=$4 out=$5
work="$out.d"
rm -rf "$work"
"$tool" -q simulate campaign --profile "$profile" --unit typical --frames 2 --size "$size" \
  --roi-area "$roi_area" --out "$work/campaign"
"$tool" -q calibrate --dataset "$work/campaign" --profile "$profile" --solver regularised \
  --epochs 30 --polish-iterations 50 --mc-refits 0 --locus-step 2 --out "$out" \
  --report "$work/report"
rm -rf "$work/campaign"
