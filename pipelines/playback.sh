#!/usr/bin/env bash
# Playback: a radiometric recording (FFV1/Matroska segments from record.sh) back through thermalcolormap.
#
# Usage: pipelines/playback.sh [RECORDING]
#   RECORDING    a folder written by record.sh (all its segments in order) or one .mkv segment
#                [out/recording]
# Settings (environment variables, defaults in brackets):
#   COLORMAP     thermalcolormap settings                             [scale-bar=true]
#   SINK         where the colour frames go                           [autovideosink]
#
# Example: the melt pool between 1200 and 2600 degC in the rainbow palette
#   COLORMAP="scale-bar=true range-mode=fixed min-temperature=1200 max-temperature=2600 palette=rainbow" \
#     pipelines/playback.sh out/pool
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
if [[ -z ${GST_PLUGIN_PATH:-} && -f $here/../build/plugins/libgstpyrocam.so ]]; then
  export GST_PLUGIN_PATH=$here/../build/plugins
fi
# Pipelines run through pyrocam-launch (built with the plugin): unlike gst-launch-1.0 of
# GStreamer 1.22 it never hangs after an error (exit 1 with the message); with -e SIGINT or
# SIGTERM sends EOS so that the files are finalised, without it they stop the pipeline.
launch=${PYROCAM_LAUNCH:-}
if [[ -z $launch ]]; then
  if [[ -x $here/../build/launcher/pyrocam-launch ]]; then
    launch=$here/../build/launcher/pyrocam-launch
  elif command -v pyrocam-launch >/dev/null; then
    launch=pyrocam-launch
  else
    echo "$(basename "$0" .sh): pyrocam-launch not found: build the project (ninja -C build) or set PYROCAM_LAUNCH" >&2
    exit 1
  fi
fi

RECORDING=${1:-out/recording}
COLORMAP=${COLORMAP:-scale-bar=true}
SINK=${SINK:-autovideosink}

if [[ -d $RECORDING ]]; then
  compgen -G "$RECORDING/temperature-*.mkv" >/dev/null ||
    { echo "playback: no temperature-*.mkv segments in $RECORDING" >&2; exit 1; }
  files="$RECORDING/temperature-*.mkv"
elif [[ -f $RECORDING ]]; then
  files=$RECORDING
else
  echo "playback: no recording $RECORDING" >&2
  exit 1
fi

# splitmuxsrc plays the segments (a glob, in name order) as one stream with continuous times.
set -f
exec "$launch" \
  splitmuxsrc "location=$files" ! avdec_ffv1 ! video/x-raw,format=GRAY16_LE ! \
  thermalcolormap $COLORMAP ! videoconvert ! $SINK
