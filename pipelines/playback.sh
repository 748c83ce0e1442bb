#!/usr/bin/env bash
# Playback: a radiometric recording (FFV1/Matroska segments from record.sh) back through thermalcolormap.
#
# Usage: pipelines/playback.sh [RECORDING]
#   RECORDING    a folder written by record.sh (all its segments in order) or one .mkv segment
#                [out/recording]
# Settings (environment variables, defaults in brackets):
#   COLORMAP     thermalcolormap settings                             [scale-bar=true]
#   PROFILE      the camera that recorded it; nir5x5-reference (one temperature per 5x5 macro-pixel)
#                scales the view up to VIEW_HEIGHT rows                [rgb-reference]
#   VIEW_HEIGHT  rows to scale the view to, by nearest neighbour (every code kept, none blended),
#                aspect kept; 0: as recorded                          [0; 5x5: 240]
#   SINK         where the colour frames go                           [autovideosink]
#
# Example: the melt pool between 1200 and 2600 degC in the rainbow palette
#   COLORMAP="scale-bar=true range-mode=fixed min-temperature=1200 max-temperature=2600 palette=rainbow" \
#     pipelines/playback.sh out/pool
# A recording of the 5x5 camera:
#   PROFILE=nir5x5-reference pipelines/playback.sh out/pool-5x5
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
# The build tree's plugin and `launch` (pyrocam-launch, which never hangs after an error).
takes_arguments=1
source "$here/lib/setup.sh"

RECORDING=${1:-out/recording}
COLORMAP=${COLORMAP:-scale-bar=true}
PROFILE=${PROFILE:-rgb-reference}
case $PROFILE in
  rgb-reference) VIEW_HEIGHT=${VIEW_HEIGHT:-0} ;;
  nir5x5-reference) VIEW_HEIGHT=${VIEW_HEIGHT:-240} ;;
  *) echo "playback: PROFILE must be rgb-reference or nir5x5-reference, not '$PROFILE'" >&2; exit 2 ;;
esac
[[ $VIEW_HEIGHT =~ ^[0-9]+$ ]] || { echo "playback: VIEW_HEIGHT must be a whole number of rows, not '$VIEW_HEIGHT'" >&2; exit 2; }
SINK=${SINK:-autovideosink}
require_display "$SINK"

(($# <= 1)) || { echo "playback: one RECORDING at a time, not $#: '$*'" >&2; exit 2; }

# Whether a segment holds a frame (one decoded within 10 s).
holds_frame() {
  local out
  out=$(timeout 10 gst-launch-1.0 -v filesrc "location=$1" ! matroskademux ! fakesink num-buffers=1 silent=false 2>&1) || true
  [[ $out == *chain* ]]
}

if [[ -d $RECORDING ]]; then
  compgen -G "$RECORDING/temperature-*.mkv" >/dev/null ||
    { echo "playback: no temperature-*.mkv segments in $RECORDING" >&2; exit 1; }
  files="$RECORDING/temperature-*.mkv"
  # A recording killed as a segment began leaves that segment empty, or with its header and no
  # frame (a full disk, a copy cut short): splitmuxsrc cannot open the one and waits for ever on
  # the other. The others are played, through links in a folder of their own.
  # A segment missing from the numbering (deleted, not copied) is a gap in time that splitmuxsrc
  # plays straight through: say so.
  expected=-1  # a recording may start later (its first segments deleted): gaps between them only
  while IFS= read -r f; do
    n=$(basename "$f" .mkv); n=${n#temperature-}
    [[ $n =~ ^[0-9]+$ ]] || continue
    n=$((10#$n))
    if ((expected < 0)); then
      :
    elif ((n == expected + 1)); then
      echo "playback: segment $expected of $RECORDING is missing: the playback jumps over its time" >&2
    elif ((n > expected)); then
      echo "playback: segments $expected..$((n - 1)) of $RECORDING are missing: the playback jumps over their time" >&2
    fi
    expected=$((n + 1))
  done < <(compgen -G "$RECORDING/temperature-*.mkv" | sort -V)  # -V: 100000 after 99999
  left_out=$(find "$RECORDING" -maxdepth 1 -name 'temperature-*.mkv' -empty -printf '%f\n' | sort)
  last=$(compgen -G "$RECORDING/temperature-*.mkv" | sort -V | tail -1)
  if [[ -s $last ]] && ! holds_frame "$last"; then left_out+=${left_out:+$'\n'}$(basename "$last"); fi
  if [[ -n $left_out ]]; then
    echo "playback: leaving out segments of $RECORDING without a frame (a recording cut off as they began): $(tr '\n' ' ' <<<"$left_out")" >&2
    kept=$(mktemp -d)
    trap 'rm -rf "$kept"' EXIT
    for f in "$RECORDING"/temperature-*.mkv; do
      if ! grep -qxF -- "$(basename "$f")" <<<"$left_out"; then ln -s "$(cd "$(dirname "$f")" && pwd)/$(basename "$f")" "$kept/"; fi
    done
    compgen -G "$kept/temperature-*.mkv" >/dev/null ||
      { echo "playback: no segment of $RECORDING holds a frame" >&2; exit 1; }
    files="$kept/temperature-*.mkv"
  fi
elif [[ -f $RECORDING ]]; then
  files=$RECORDING
else
  echo "playback: no recording $RECORDING" >&2
  exit 1
fi

# A 5x5 recording has one temperature per macro-pixel (64x48 from a 320x240 sensor): too small
# for a scale bar, so it is scaled up before the colour map, keeping every code.
scale=()
if ((VIEW_HEIGHT > 0)); then
  scale=(videoscale method=nearest-neighbour ! "video/x-raw,height=$VIEW_HEIGHT,pixel-aspect-ratio=1/1" !)
  # The peak marker's windows (peak-window, 5 pixels) would then cover a fraction of a recorded
  # pixel, and the marker show the hottest single one (a wild edge pixel): they are scaled too.
  if [[ " $COLORMAP " == *" peak-marker=true "* && $COLORMAP != *peak-window=* ]]; then
    first=$(compgen -G "$files" | head -1)
    rows=$(timeout 20 gst-launch-1.0 -v filesrc "location=$first" ! matroskademux ! fakesink num-buffers=1 2>/dev/null |
      sed -n 's/.*height=(int)\([0-9]*\).*/\1/p' | head -1) || true
    if [[ -n $rows && $rows -gt 0 ]]; then
      factor=$(((VIEW_HEIGHT + rows / 2) / rows))
      COLORMAP="$COLORMAP peak-window=$((5 * (factor > 0 ? factor : 1) | 1))"
      echo "playback: the peak marker over windows of 5 x 5 recorded pixels (${COLORMAP##* })" >&2
    fi
  fi
fi

# splitmuxsrc plays the segments (a glob, in name order) as one stream with continuous times.
set -f
pipeline=("$launch"
  splitmuxsrc "location=$files" ! avdec_ffv1 ! video/x-raw,format=GRAY16_LE ! "${scale[@]}"
  thermalcolormap $COLORMAP ! videoconvert ! $SINK)
[[ -n ${kept:-} ]] || exec "${pipeline[@]}"
"${pipeline[@]}"  # not exec: the links' folder goes when it ends
