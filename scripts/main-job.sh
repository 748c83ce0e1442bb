#!/usr/bin/env bash
# README command 1: install what is missing, build, and run the main job on the built-in default
# (the simulated colour camera): a furnace calibration campaign and a melt-pool scene sequence.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
out=${PYROCAM_OUT:-out}
mkdir -p "$out"
tool=build/calib-tool/pyrocam-calib
$tool simulate campaign --profile rgb-reference --unit typical --frames 3 --out "$out/furnace-rgb"
$tool simulate scene --scene melt-pool --profile rgb-reference --unit typical --frames 30 \
  --out "$out/melt-pool"
echo
echo "calibration dataset: $out/furnace-rgb/manifest.csv"
echo "melt-pool sequence:  $out/melt-pool/manifest.csv (true temperatures in $out/melt-pool/truth/)"
