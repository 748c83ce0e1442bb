#!/usr/bin/env bash
# Live view: the camera's own colour image with the calibrated temperature overlay and scale bar.
#
# Settings (environment variables, defaults in brackets):
#   MODEL        calibrated model from pyrocam-calib calibrate        [out/model-rgb.json]
#   SOURCE       camera element with its properties                   [pyrocamsrc is-live=true]
#   CAPS         caps after the camera: format, size, frame rate      [video/x-bayer,width=320,height=240,framerate=30/1]
#   DARK         darksub settings: dark-level=N or location=dark.pgm  [dark-level=50]
#   NUM_BUFFERS  frames before the view ends; -1 runs until Ctrl-C    [-1]
#   WATCHDOG_MS  end with an error when the camera sends nothing this long; 0: never [5000]
#   SINK         where the view goes                                  [autovideosink]
#
# Example (the simulated melt pool, after scripts/main-job.sh made the model):
#   pipelines/live-view.sh
#   SOURCE="pyrocamsrc is-live=true scene=filament temperature=1800" pipelines/live-view.sh
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
# The build tree's plugin and `launch` (pyrocam-launch, which never hangs after an error).
source "$here/lib/setup.sh"

MODEL=${MODEL:-out/model-rgb.json}
SOURCE=${SOURCE:-pyrocamsrc is-live=true}
CAPS=${CAPS:-video/x-bayer,width=320,height=240,framerate=30/1}
DARK=${DARK:-dark-level=50}
NUM_BUFFERS=${NUM_BUFFERS:--1}
WATCHDOG_MS=${WATCHDOG_MS:-5000}
SINK=${SINK:-autovideosink}

[[ -f $MODEL ]] || { echo "live-view: no model file $MODEL (set MODEL, or run scripts/main-job.sh)" >&2; exit 1; }

# The temperature overlay (transparent where there is no reading) over the camera's colour image.
# compositor, live: start-time-selection=first starts its output at the camera's first frame
# (not at 0, which adds frames before it and can negotiate a 1x1 picture); latency=100 ms waits
# that long for the slower temperature branch, so that no frame goes out without its overlay.
# The queue after it keeps its thread free: in a live pipeline the first sink to get a frame
# waits for the others, while compositor answers the tee's allocation queries from that thread,
# so without the queue the start can deadlock (GStreamer 1.22).
set -f # the fragments above split on spaces into the launcher's words
exec "$launch" -e \
  $SOURCE num-buffers="$NUM_BUFFERS" ! $CAPS ! \
    watchdog name=camera-sent-no-frame timeout="$WATCHDOG_MS" ! tee name=camera \
  camera. ! queue ! bayer2rgb ! video/x-raw,format=RGBA ! mix.sink_0 \
  camera. ! queue ! darksub $DARK ! demosaic25 ! ratiotemp "model=$MODEL" ! \
    thermalcolormap scale-bar=true ! video/x-raw,format=RGBA ! mix.sink_1 \
  compositor name=mix start-time-selection=first latency=100000000 \
    sink_0::zorder=0 sink_1::zorder=1 ! video/x-raw,format=RGBA ! queue ! videoconvert ! $SINK
