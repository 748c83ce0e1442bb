#!/usr/bin/env bash
# GenICam live view: a real camera (aravissrc) through the calibrated chain; a camera that stops sending ends in an error.
#
# A watchdog ends the pipeline with an error, and this script with exit status 1, when no frame
# comes for WATCHDOG_MS: a camera unplugged, switched off, or losing packets never leaves a
# frozen picture that looks live; when Aravis notices the loss first, aravissrc's own error
# does the same. The diagnosis comes at once; Aravis then spends about 12 s on control timeouts
# to the vanished camera before the process exits.
#
# Settings (environment variables, defaults in brackets):
#   MODEL        calibrated model of THIS camera (required)
#   DARK         darksub settings for this camera (required): location=dark.pgm or dark-level=N
#   CAMERA       camera name (arv-tool-0.8 lists them) or IP address  [the first camera found]
#   PROFILE      rgb-reference (colour Bayer) or nir5x5-reference (5x5 mosaic) [rgb-reference]
#   CAPS         caps after the camera: format, size, frame rate      [video/x-bayer,format=rggb;
#                5x5: video/x-raw,format=GRAY8,pattern=5x5, and the size is required (multiples of 5)]
#   EXPOSURE_US  exposure time in microseconds                        [the camera's setting]
#   GAIN_DB      gain in dB                                           [the camera's setting]
#   WATCHDOG_MS  longest wait for a frame, in ms                      [2000]
#   NUM_BUFFERS  frames before the view ends; -1 runs until Ctrl-C    [-1]
#   LATENCY_MS   how long the picture waits for its temperature overlay, ms [100]
#   EXPOSURE_CONTROL autoexposure after the camera: the hottest region neither saturates nor goes dim (1) [0]
#   EXPOSURE_LATENCY frames from setting an exposure to the first frame taken with it, for autoexposure [3]
#   BRACKET          exposure factors the camera cycles through (autoexposure brackets it; one frame passes per EXPOSURE_LATENCY + 1), fused by thermalfuse (high dynamic range), e.g. 1,8 []
#   BRACKET_FUSION   readings: thermalfuse after ratiotemp, each pixel from one frame; mosaics: mosaicfuse before demosaic25, each sample from one frame, following a pool that moves (more of the pool reads; where its brightness changes over the bracket some read wild) [readings]
#   BLUR_CORRECTION ratiotemp blur-correction: steep sides read their footprint's mean temperature, not hotter (1; colour camera) [1 with BRACKET_FUSION=mosaics, else 0]
#   BRIGHTNESS_RADIUS ratiotemp brightness-radius: each pixel read from its own brightness, scaled over a window (colour: (4r+1) pixels; 5x5: (2r+1) cells); only for surfaces of one emissivity over the window (0 = off, 1-8) [0]
#   PEAK_MARKER  ring the frame's peak and write its temperature on the overlay (1) [0]
#   ALARM_C      thermalalarm: a pyrocam-alarm message when the peak stays above this, degC []
#   SINK         where the view goes                                  [autovideosink]
#   STATS_CSV    write ratiotemp's statistics here as CSV, a row every STATS_INTERVAL_MS [none]
#   STATS_INTERVAL_MS  ms between statistics rows                   [1000]
#   ALARM_CSV    write alarm messages (thermalalarm) here as CSV    [none]
#
# Example:
#   MODEL=cam42.json DARK=location=cam42-dark.pgm CAMERA=192.168.1.42 \
#     CAPS=video/x-bayer,format=rggb,width=1024,height=768 pipelines/genicam-live.sh
#   PROFILE=nir5x5-reference MODEL=nir.json DARK=location=nir-dark.pgm \
#     CAPS=video/x-raw,format=GRAY8,pattern=5x5,width=2045,height=1085 pipelines/genicam-live.sh
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
# The build tree's plugin and `launch` (pyrocam-launch, which never hangs after an error).
source "$here/lib/setup.sh"

MODEL=${MODEL:-}
DARK=${DARK:-}
CAMERA=${CAMERA:-}
if [[ ${PROFILE:-} == nir5x5-reference ]]; then
  CAPS=${CAPS:-video/x-raw,format=GRAY8,pattern=5x5}
else
  CAPS=${CAPS:-video/x-bayer,format=rggb}
fi
EXPOSURE_US=${EXPOSURE_US:-}
GAIN_DB=${GAIN_DB:-}
WATCHDOG_MS=${WATCHDOG_MS:-2000}
NUM_BUFFERS=${NUM_BUFFERS:--1}
SINK=${SINK:-autovideosink}
require_display "$SINK"

# A model or dark level that belongs to another camera gives temperatures that look right and are
# wrong: no defaults for these two.
[[ $WATCHDOG_MS =~ ^[1-9][0-9]*$ ]] || { echo "genicam-live: WATCHDOG_MS must be a whole number of milliseconds, 1 or more, not '$WATCHDOG_MS'" >&2; exit 2; }
[[ -n $MODEL ]] || { echo "genicam-live: set MODEL to the calibrated model of this camera" >&2; exit 2; }
[[ -f $MODEL ]] || { echo "genicam-live: no model file $MODEL" >&2; exit 1; }
[[ -n $DARK ]] || { echo "genicam-live: set DARK to this camera's dark: DARK=location=dark.pgm or DARK=dark-level=N" >&2; exit 2; }

camera=(aravissrc num-buffers="$NUM_BUFFERS")
[[ -n $CAMERA ]] && camera+=("camera-name=$CAMERA")
[[ -n $EXPOSURE_US ]] && camera+=("exposure=$EXPOSURE_US")
[[ -n $GAIN_DB ]] && camera+=("gain=$GAIN_DB")

# The chain and the overlay (thermaloverlay) as in live-view.sh (pipelines/lib/camera.sh).
source "$here/lib/camera.sh"
set -f # the fragments above split on spaces into the launcher's words
set +e
# The launcher's messages pass through a filter that adds a plain diagnosis at once to the
# watchdog's error, or to aravissrc's own (when Aravis notices the camera's loss first, its
# streaming stops with a bare "Internal data stream error"); Aravis may then take seconds to let
# go of the vanished camera. The filter ignores Ctrl-C so that the launcher can still print while
# it stops.
"$launch" "${launch_options[@]}" \
  "${camera[@]}" ! $CAPS ! "${exposure_control[@]}" watchdog name=camera-sent-no-frame timeout="$WATCHDOG_MS" ! tee name=camera \
  "${thermal_chain[@]}" ! "${colormap_to_mix[@]}" \
  "${overlay_mix[@]}" ! videoconvert ! $SINK \
  2>&1 | (
  trap '' INT
  stopped=0
  # aravissrc's error says why in the lines after it: caps the camera cannot give (not-negotiated)
  # are no lost camera.
  pending=0
  lost="genicam-live: camera ${CAMERA:-(first found)} stopped streaming (aravissrc's error above): unplugged, switched off, or losing packets"
  while IFS= read -r line; do
    printf '%s\n' "$line"
    if ((pending > 0)); then
      if [[ $line == *"reason not-negotiated"* ]]; then
        echo "genicam-live: camera ${CAMERA:-(first found)} cannot send CAPS ($CAPS): check the size and format against what the camera offers (arv-tool-0.8 control Width Height PixelFormat)" >&2
        pending=0 stopped=1
      elif [[ $line == *"streaming stopped, reason"* ]] || ((--pending == 0)); then
        pending=0
        echo "$lost" >&2
        stopped=1
      fi
    elif ((stopped == 0)); then
      if [[ $line == *GstWatchdog:camera-sent-no-frame:* ]]; then
        echo "genicam-live: camera ${CAMERA:-(first found)} sent no frame for $WATCHDOG_MS ms: unplugged, switched off, or losing packets" >&2
        stopped=1
      elif [[ $line == "ERROR: from element "*/GstAravis:*"Could not find camera"* ]]; then
        echo "genicam-live: camera ${CAMERA:-(first found)} not found: is it on, on this network and named as arv-tool-0.8 lists it?" >&2
        stopped=1
      elif [[ $line == "ERROR: from element "*/GstAravis:* ]]; then
        pending=4
      fi
    fi
  done
  if ((pending > 0)); then echo "$lost" >&2; stopped=1; fi
  exit $((stopped ? 3 : 0)))
statuses=("${PIPESTATUS[@]}")
set -e
if ((statuses[1] == 3)); then exit 1; fi
exit "${statuses[0]}"
