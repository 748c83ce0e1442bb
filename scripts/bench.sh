#!/usr/bin/env bash
# Builds and runs the benchmarks (never part of `meson test`): the estimators at camera sizes
# (library level, with their agreement with the references) and the element chains with
# bayer2rgb on the same input. Prints frames per second, CPU time per frame and memory.
#
# Models: fully calibrated ones (pyrocam-calib's defaults) from simulated furnace campaigns,
# made once into build/bench-data (about 3 minutes) unless given:
#   RGB_MODEL, NIR_MODEL  model files to use instead
#   SCENE                 plate:T, filament:T or melt-pool [plate:1500]
#   FRAMES                frames per timed chain run [600] (the RSS growth is over this run)
#   SOAK                  run only the soak instead: the colour chain with the lookup table on
#                         SOAK frames of the simulated melt pool (320x240, every frame new),
#                         printing the resident memory at 1k, 2k, 5k, 10k, ... frames
# Wall-clock figures need a quiet machine: the CPU time per frame is the figure to compare
# across runs on a busy one.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh >/dev/null
ninja -C build bench/bench_estimators bench/bench_chain >/dev/null
tool=build/calib-tool/pyrocam-calib
data=build/bench-data
mkdir -p "$data"
export PYROCAM_PROFILE_DIR=$PWD/profiles

model() {  # profile, campaign size, model path
  if [[ ! -f "$3" ]]; then
    echo "bench: calibrating $1 once (simulated furnace campaign) into $3" >&2
    "$tool" -q simulate campaign --profile "$1" --unit typical --size "$2" \
      --out "$data/campaign-$1"
    "$tool" -q calibrate --dataset "$data/campaign-$1" --profile "$1" --out "$3" \
      --report "$data/report-$1"
    rm -rf "$data/campaign-$1"
  fi
}
rgb=${RGB_MODEL:-$data/model-rgb.json}
nir=${NIR_MODEL:-$data/model-nir5x5.json}
model rgb-reference 128x128 "$rgb"
if [[ -n ${SOAK:-} ]]; then
  GST_PLUGIN_PATH=$PWD/build/plugins exec build/bench/bench_chain --rgb-model "$rgb" --soak "$SOAK"
fi
model nir5x5-reference 130x130 "$nir"

scene=${SCENE:-plate:1500}
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)," \
  "load average $(cut -d' ' -f1-3 /proc/loadavg)"
build/bench/bench_estimators --rgb-model "$rgb" --nir-model "$nir" --scene "$scene" --frames 20
echo
GST_PLUGIN_PATH=$PWD/build/plugins build/bench/bench_chain --rgb-model "$rgb" --nir-model "$nir" \
  --scene "$scene" --frames "${FRAMES:-600}" --mlp-frames 3
echo "load average after the run: $(cut -d' ' -f1-3 /proc/loadavg)"
