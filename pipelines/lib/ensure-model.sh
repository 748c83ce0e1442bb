#!/usr/bin/env bash
# Calibrates a shipped profile's simulated camera once: when MODEL_FILE is missing, a simulated
# furnace campaign of a typical unit (pyrocam-calib simulate campaign), then pyrocam-calib
# calibrate, writing MODEL_FILE and its report (MODEL_FILE minus .json, -report.html/.json).
# Used by scripts/main-job.sh and by the pipelines for their default model.
# Usage: pipelines/lib/ensure-model.sh PROFILE MODEL_FILE
#   PYROCAM_CALIB  the pyrocam-calib to run [build/calib-tool/pyrocam-calib of this checkout, else the PATH's]
set -euo pipefail
profile=${1:?usage: ensure-model.sh PROFILE MODEL_FILE} model=${2:?usage: ensure-model.sh PROFILE MODEL_FILE}
[[ -f $model ]] && exit 0

tool=${PYROCAM_CALIB:-}
if [[ -z $tool ]]; then
  lib=$(cd "$(dirname "$0")" && pwd)
  if [[ -x $lib/../../build/calib-tool/pyrocam-calib ]]; then
    tool=$lib/../../build/calib-tool/pyrocam-calib
  elif command -v pyrocam-calib >/dev/null; then
    tool=pyrocam-calib
  else
    echo "ensure-model: pyrocam-calib not found: build the project (ninja -C build) or set PYROCAM_CALIB" >&2
    exit 1
  fi
fi

case $profile in
  rgb-reference) what="colour camera" ;;
  nir5x5-reference) what="5x5 multispectral camera" ;;
  *) echo "ensure-model: no simulated campaign for profile '$profile' (rgb-reference or nir5x5-reference)" >&2; exit 2 ;;
esac
dir=$(dirname "$model")
campaign=$dir/furnace-${profile%-reference}
mkdir -p "$dir"
echo "ensure-model: no model $model yet: simulated furnace campaign of the $what ($profile, a"
echo "              typical unit) in $campaign, then calibration; a minute or two, once"
rm -rf "$campaign"
"$tool" simulate campaign --profile "$profile" --unit typical --frames 3 --out "$campaign"
# Written under another name and renamed: a pipeline started meanwhile, or a calibration that
# fails half-way, never finds a partial model under the final name.
partial="${model%.json}.partial-$$.json"
trap 'rm -f "$partial" "$partial.lut"' EXIT
"$tool" calibrate --dataset "$campaign" --profile "$profile" --out "$partial" \
  --report "${model%.json}-report"
# A colour model's prebuilt lookup table goes with it, named after it (first: the model's name
# is what a pipeline waits for).
if [[ -f $partial.lut ]]; then mv -f "$partial.lut" "$model.lut"; fi
mv -f "$partial" "$model"
echo "ensure-model: wrote $model (report: ${model%.json}-report.html)"

# The colour model's first view starts with the lookup-table blocks that the simulated melt pool
# and a plate need (kept in ratiotemp's table cache), rather than filling them while its first
# frames wait; a few seconds, once.
if [[ $profile == rgb-reference ]]; then
  here=$(cd "$(dirname "$0")/.." && pwd)
  takes_arguments=1
  source "$here/lib/setup.sh"
  for scene in melt-pool "plate temperature=1300"; do
    # shellcheck disable=SC2086 # the scene's words are pyrocamsrc's properties
    "$launch" pyrocamsrc scene=$scene num-buffers=30 ! video/x-bayer,width=320,height=240 ! \
      darksub dark-level=50 ! demosaic25 ! ratiotemp "model=$model" ! fakesink >/dev/null ||
      echo "ensure-model: could not fill the lookup-table cache (the first frames will be slower)" >&2
  done
fi
