#!/usr/bin/env bash
# README command 1: install what is missing, build, calibrate the simulated colour camera once
# (a furnace campaign, then pyrocam-calib calibrate), and record a simulated melt pool through
# the full chain (pyrocamsrc -> darksub -> demosaic25 -> ratiotemp -> thermalcolormap): a
# radiometric recording (FFV1/Matroska segments), its statistics every 0.1 s as CSV and a
# colour-mapped snapshot PNG.
#
# Settings (environment variables, defaults in brackets):
#   PYROCAM_OUT  folder for everything it writes                         [out]
#   MODEL        the model to use; calibrated first if the file is missing [PYROCAM_OUT/model-rgb.json]
#   FRAMES       melt-pool frames to record (30 a second)               [300]
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh

out=${PYROCAM_OUT:-out}
model=${MODEL:-$out/model-rgb.json}
frames=${FRAMES:-300}
tool=build/calib-tool/pyrocam-calib
mkdir -p "$out"

if [[ -f $model ]]; then
  echo "main-job: using the model $model (delete it to calibrate again)"
else
  # The campaign and calibration the pipelines also run for their default model on first use.
  PYROCAM_CALIB=$tool pipelines/lib/ensure-model.sh rgb-reference "$model"
fi

recording=$out/melt-pool-$(date +%Y%m%d-%H%M%S)
echo "main-job: recording $frames frames of the simulated melt pool into $recording"
# Not live: the frames are computed as fast as the machine can, with the same timestamps.
MODEL=$model OUT=$recording NUM_BUFFERS=$frames SEGMENT_SECONDS=2 SNAPSHOT_RATE=1 \
  STATS_CSV=$recording/stats.csv STATS_INTERVAL_MS=100 \
  CAPS=video/x-bayer,width=320,height=240,framerate=30/1 \
  EXPOSURE_CONTROL=1 PEAK_MARKER=1 SOURCE="pyrocamsrc scene=melt-pool" pipelines/record.sh >"$out/record.log" 2>&1 || {
  cat "$out/record.log" >&2
  echo "main-job: the recording failed (log: $out/record.log)" >&2
  exit 1
}

# Read the recording back: every frame must decode.
shopt -s nullglob
segments=("$recording"/temperature-*.mkv)
# pyrocam-launch, not gst-launch-1.0, which can hang after an early error.
bytes=$(build/launcher/pyrocam-launch splitmuxsrc "location=$recording/temperature-*.mkv" ! \
  avdec_ffv1 ! video/x-raw,format=GRAY16_LE ! fdsink fd=1 | wc -c)
decoded=$((bytes / (320 * 240 * 2)))
if ((decoded != frames)); then
  echo "main-job: the recording decodes to $decoded frames, not $frames" >&2
  exit 1
fi

# The statistics: rows, and the most pixels a row had without a reading because of saturation
# (the core hotter than anything read; exposure control should keep it at 0).
stats=$recording/stats.csv
read -r rows most_saturated < <(awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == "saturated") c = i; next }
  { ++n; if (c && $c + 0 > m) m = $c + 0 } END { print n + 0, m + 0 }' "$stats")
if ((rows == 0)); then
  echo "main-job: no statistics in $stats" >&2
  exit 1
fi

report=${model%.json}-report.html
echo
echo "model:             $model"
[[ -f $report ]] && echo "calibration:       $report"
echo "thermal recording: $recording/ (${#segments[@]} segments, $decoded frames, all decoded back:"
echo "                   320x240 GRAY16_LE in FFV1/Matroska, 0.1 K per step, 0 = no reading)"
printf '                   %s\n' "${segments[@]}"
echo "statistics:        $stats ($rows rows, every 0.1 s: median, peak, ...;"
echo "                   at most $most_saturated pixels without a reading because of saturation)"
echo "colour snapshot:   $recording/view.png"
echo "play it back:      pipelines/playback.sh $recording"
