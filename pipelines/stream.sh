#!/usr/bin/env bash
# Stream: the live temperature overlay to monitoring screens as H.264 over RTP/UDP (watch with watch-stream.sh).
#
# Settings (environment variables, defaults in brackets):
#   HOST         receiver address; a multicast group (239.x.y.z) reaches several screens  [127.0.0.1]
#   PORT         UDP port                                             [5004]
#   BITRATE      H.264 bit rate in kbit/s                             [2000]
#   KEY_SECONDS  seconds between key frames: how long a screen that joins waits for a picture [1]
#   PROFILE      camera: rgb-reference (colour) or nir5x5-reference (5x5 mosaic) [rgb-reference]
#   MODEL        calibrated model; the default is calibrated on first use [out/model-rgb.json,
#                5x5: out/model-nir5x5.json]
#   SOURCE       camera element with its properties                   [pyrocamsrc is-live=true profile=PROFILE;
#                    5x5: scene=plate too; a typical unit, seed 1: add unit=… seed=N
#                    for the simulated unit a model was calibrated on, as simulate --unit-seed N]
#   CAPS         caps after the camera: format, size, frame rate      [video/x-bayer,width=320,height=240,framerate=30/1;
#                5x5: video/x-raw,width=320,height=240,framerate=30/1]
#   DARK         darksub settings: dark-level=N or location=dark.pgm  [dark-level=50]
#   LATENCY_MS   how long the picture waits for its temperature overlay, ms [100]
#   EXPOSURE_CONTROL autoexposure after the camera: the hottest region neither saturates nor goes dim (1) [0]
#   EXPOSURE_LATENCY frames from setting an exposure to the first frame taken with it, for autoexposure [3]
#   PEAK_MARKER  ring the frame's peak and write its temperature on the overlay (1) [0]
#   ALARM_C      thermalalarm: a pyrocam-alarm message when the peak stays above this, degC []
#   BRACKET      exposure factors the camera cycles through, fused by thermalfuse (high dynamic range), e.g. 9,3,1,0.333,0.111,0.037; a camera other than the simulated one is bracketed by autoexposure, one frame passing per EXPOSURE_LATENCY + 1 []
#   BRACKET_FUSION readings: thermalfuse after ratiotemp, each pixel from one frame; mosaics: mosaicfuse before demosaic25, each sample from one frame, following a pool that moves (more of the pool reads; where its brightness changes over the bracket some read wild) [readings]
#   BLUR_CORRECTION ratiotemp blur-correction: steep sides read their footprint's mean temperature, not hotter (1; colour camera) [1 with BRACKET_FUSION=mosaics, else 0]
#   BRIGHTNESS_RADIUS ratiotemp brightness-radius: each pixel read from its own brightness, scaled over a window (colour: (4r+1) pixels; 5x5: (2r+1) cells); only for surfaces of one emissivity over the window (0 = off, 1-8) [0]
#   NUM_BUFFERS  frames to send; -1 streams until Ctrl-C              [-1]
#   WATCHDOG_MS  end with an error when the camera sends nothing this long; 0: never [5000]
#   STATS_CSV    write ratiotemp's statistics here as CSV, a row every STATS_INTERVAL_MS [none]
#   STATS_INTERVAL_MS  ms between statistics rows                   [1000]
#   ALARM_CSV    write alarm messages (thermalalarm) here as CSV    [none]
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
[[ $PORT =~ ^[0-9]+$ ]] && ((10#$PORT >= 1 && 10#$PORT <= 65535)) ||
  { echo "stream: PORT must be a UDP port, 1 to 65535, not '$PORT'" >&2; exit 2; }
[[ $BITRATE =~ ^[0-9]+$ ]] && ((10#$BITRATE >= 1 && 10#$BITRATE <= 2048000)) ||
  { echo "stream: BITRATE must be a whole number of kbit/s, 1 to 2048000, not '$BITRATE'" >&2; exit 2; }
[[ $KEY_SECONDS =~ ^[0-9]*[.]?[0-9]+$ ]] && awk -v s="$KEY_SECONDS" 'BEGIN { exit !(s > 0) }' ||
  { echo "stream: KEY_SECONDS must be a positive number of seconds, not '$KEY_SECONDS'" >&2; exit 2; }
getent ahosts "$HOST" >/dev/null ||
  { echo "stream: HOST '$HOST' is neither an address nor a name this machine resolves" >&2; exit 2; }
source "$here/lib/camera.sh"
fps=$(sed -n 's/.*framerate=\(([a-z]*)\)\{0,1\} *\([0-9]*\)\/\([0-9]*\).*/\2 \3/p' <<<"$CAPS")
key_int=$(awk -v f="${fps:-30 1}" -v s="$KEY_SECONDS" 'BEGIN { split(f, r, " "); k = int(s * r[1] / r[2] + 0.5); print (k < 1 ? 1 : k) }')

# zerolatency: no B-frames or look-ahead, each frame leaves as soon as it is encoded. SPS/PPS go
# with every key frame (config-interval=-1) so that a screen can join at any time.
set -f
exec "$launch" -e "${launch_options[@]}" "${camera_chain[@]}" \
  "${thermal_chain[@]}" ! "${colormap_to_mix[@]}" \
  "${overlay_mix[@]}" ! videoconvert ! video/x-raw,format=I420 ! \
  x264enc tune=zerolatency speed-preset=ultrafast bitrate="$BITRATE" key-int-max="$key_int" ! \
  rtph264pay config-interval=-1 pt=96 ! udpsink host="$HOST" port="$PORT"
