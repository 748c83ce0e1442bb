#!/usr/bin/env bash
# Stream: the live temperature overlay to monitoring screens as H.264 over RTP/UDP (watch with watch-stream.sh).
#
# Settings (environment variables, defaults in brackets):
#   HOST         receiver address; a multicast group (239.x.y.z) reaches several screens  [127.0.0.1]
#   PORT         UDP port                                             [5004]
#   BITRATE      H.264 bit rate in kbit/s                             [2000]
#   KEY_SECONDS  seconds between key frames: how long a screen that joins waits for a picture [1]
#   MODEL        calibrated model from pyrocam-calib calibrate        [out/model-rgb.json]
#   SOURCE       camera element with its properties                   [pyrocamsrc is-live=true]
#   CAPS         caps after the camera: format, size, frame rate      [video/x-bayer,width=320,height=240,framerate=30/1]
#   DARK         darksub settings: dark-level=N or location=dark.pgm  [dark-level=50]
#   LATENCY_MS   how long the picture waits for its temperature overlay, ms [100]
#   NUM_BUFFERS  frames to send; -1 streams until Ctrl-C              [-1]
#   WATCHDOG_MS  end with an error when the camera sends nothing this long; 0: never [5000]
#
# Example: to every screen listening on the multicast group 239.255.42.42, port 5004
#   HOST=239.255.42.42 pipelines/stream.sh
#   (on each screen) ADDRESS=239.255.42.42 pipelines/watch-stream.sh
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
# The build tree's plugin and `launch` (pyrocam-launch, which never hangs after an error).
source "$here/lib/setup.sh"

HOST=${HOST:-127.0.0.1}
PORT=${PORT:-5004}
BITRATE=${BITRATE:-2000}
KEY_SECONDS=${KEY_SECONDS:-1}
MODEL=${MODEL:-out/model-rgb.json}
SOURCE=${SOURCE:-pyrocamsrc is-live=true}
CAPS=${CAPS:-video/x-bayer,width=320,height=240,framerate=30/1}
DARK=${DARK:-dark-level=50}
NUM_BUFFERS=${NUM_BUFFERS:--1}
WATCHDOG_MS=${WATCHDOG_MS:-5000}
LATENCY_MS=${LATENCY_MS:-100}

[[ -f $MODEL ]] || { echo "stream: no model file $MODEL (set MODEL, or run scripts/main-job.sh)" >&2; exit 1; }
fps=$(sed -n 's/.*framerate=\(([a-z]*)\)\{0,1\} *\([0-9]*\)\/\([0-9]*\).*/\2 \3/p' <<<"$CAPS")
key_int=$(awk -v f="${fps:-30 1}" -v s="$KEY_SECONDS" 'BEGIN { split(f, r, " "); k = int(s * r[1] / r[2] + 0.5); print (k < 1 ? 1 : k) }')

# zerolatency: no B-frames or look-ahead, each frame leaves as soon as it is encoded. SPS/PPS go
# with every key frame (config-interval=-1) so that a screen can join at any time.
# compositor, live: start-time-selection=first starts its output at the camera's first frame
# (not at 0, which adds frames before it and can negotiate a 1x1 picture); it waits LATENCY_MS
# for the slower temperature branch, so that no frame goes out without its overlay (on a loaded
# machine the branch can take longer: raise it).
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
  compositor name=mix start-time-selection=first latency="$((LATENCY_MS * 1000000))" \
    sink_0::zorder=0 sink_1::zorder=1 ! video/x-raw,format=RGBA ! queue ! \
    videoconvert ! video/x-raw,format=I420 ! \
  x264enc tune=zerolatency speed-preset=ultrafast bitrate="$BITRATE" key-int-max="$key_int" ! \
  rtph264pay config-interval=-1 pt=96 ! udpsink host="$HOST" port="$PORT"
