#!/usr/bin/env bash
# Builds and runs the benchmarks (never part of `meson test`): the estimators at camera sizes
# (library level, with their agreement with the references), their per-pixel scatter against
# the Cramer-Rao bound (the shot-noise limit), then per scene the element chains
# with bayer2rgb on the same frames in the same run (frames/s, CPU ms per frame, and the chain's
# rate as a multiple of bayer2rgb's), then a soak per chain: the resident memory over
# SOAK_FRAMES frames that all differ.
#
# Models: fully calibrated ones (pyrocam-calib's defaults) from simulated furnace campaigns,
# made once into build/bench-data (3 minutes or more each) unless given. Environment:
#   RGB_MODEL, NIR_MODEL  model files to use instead
#   SCENES       the per-scene table's scenes, comma-separated
#                [plate:1500:36,plate:1500:36@1.2,plate:1500:90,plate:1500:90@2,
#                plate:1500:90@3,melt-pool,filament:1800]:
#                plate:T[:P] a plate at T degC covering P % of the frame (36 unless given),
#                filament:T, melt-pool; a suffix @F exposes F times longer (e.g.
#                plate:1500:36@1.2: the colour camera's red band just below the saturation
#                level, where the saturation-edge check reads a ring around most pixels;
#                @1.3: the brightest bands of most hot pixels saturate; @2: most 5x5 bands of
#                the hot pixels saturate; @3: all but 7 of the 25)
#   FRAMES       frames per timed chain run, warm-up included [600] (the 5x5 chain: half)
#   SOAK_FRAMES  frames of each soak [10000]; 0: no soak. The soaks run the simulated camera
#                (pyrocamsrc, melt pool, 320x240, every frame new) through the colour chain with
#                the lookup table and the 5x5 chain with the likelihood fit, one process each,
#                printing the resident memory at 1k, 2k, 5k, 10k, ... frames and its growth
#   SCENE        the estimators' scene [plate:1500]; set, it also runs every stage and method of
#                both chains on that scene (darksub ! demosaic25 alone, demosaic25's mixed-pixel
#                check, the likelihood fit and the network on the colour chain too)
#   SOAK         run only the soaks, SOAK frames each
# Wall-clock figures need a quiet machine: the CPU time per frame is the figure to compare
# across runs on a busy one.
set -euo pipefail
cd "$(dirname "$0")/.."
# Only what the benchmarks run: the tests take long to build.
[[ -f build/build.ninja ]] || meson setup build --buildtype=release >/dev/null
ninja -C build bench/bench_estimators bench/bench_chain bench/bench_precision \
  plugins/libgstpyrocam.so >/dev/null
tool=build/calib-tool/pyrocam-calib
data=build/bench-data
mkdir -p "$data"
export PYROCAM_PROFILE_DIR=$PWD/profiles
export GST_PLUGIN_PATH=$PWD/build/plugins

model() {  # profile, campaign size, model path
  if [[ ! -f "$3" ]]; then
    echo "bench: calibrating $1 once (simulated furnace campaign) into $3" >&2
    ninja -C build calib-tool/pyrocam-calib >/dev/null
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
model nir5x5-reference 130x130 "$nir"

soaks() {  # frames
  for chain in colour 5x5; do
    build/bench/bench_chain --rgb-model "$rgb" --nir-model "$nir" --soak "$1" --only "$chain"
  done
}
if [[ -n ${SOAK:-} ]]; then
  soaks "$SOAK"
  exit
fi

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)," \
  "load average $(cut -d' ' -f1-3 /proc/loadavg)"
build/bench/bench_estimators --rgb-model "$rgb" --nir-model "$nir" --scene "${SCENE:-plate:1500}" \
  --frames 20
echo
build/bench/bench_precision --model "$rgb" --model "$nir"
if [[ -n ${SCENE:-} ]]; then
  echo
  build/bench/bench_chain --rgb-model "$rgb" --nir-model "$nir" --scene "$SCENE" \
    --frames "${FRAMES:-600}" --mlp-frames 3
fi
echo
build/bench/bench_chain --rgb-model "$rgb" --nir-model "$nir" --methods lut,likelihood \
  --scenes "${SCENES:-plate:1500:36,plate:1500:36@1.2,plate:1500:90,plate:1500:90@2,plate:1500:90@3,melt-pool,filament:1800}" \
  --frames "${FRAMES:-600}"
echo "load average after the chains: $(cut -d' ' -f1-3 /proc/loadavg)"
if ((${SOAK_FRAMES:-10000} > 0)); then
  soaks "${SOAK_FRAMES:-10000}"
  echo "load average after the soaks: $(cut -d' ' -f1-3 /proc/loadavg)"
fi
