#!/usr/bin/env bash
# Benchmark: the calibration targets (paper Table 4 on the calibration data, MLP locus fit,
# held-out plates and filaments by range) for the colour and the 5x5 camera, from 10-frame
# simulated campaigns of typical units, printed with the paper's figures.
# Usage: bench/targets.sh [--keep FOLDER]   (env PYROCAM_CALIB=...)
set -euo pipefail
cd "$(dirname "$0")/.."
tool=${PYROCAM_CALIB:-build/calib-tool/pyrocam-calib}
exec python3 tests/targets/targets.py --tool "$tool" --mode bench "$@"
