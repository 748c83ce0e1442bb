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
# The build tree's plugin and `launch` (pyrocam-launch, which never hangs after an error).
source "$here/lib/setup.sh"

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
