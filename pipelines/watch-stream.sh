#!/usr/bin/env bash
# Watch: a monitoring screen showing the RTP/UDP H.264 overlay stream sent by stream.sh.
#
# Settings (environment variables, defaults in brackets):
#   ADDRESS      address to listen on: this machine's, or the multicast group stream.sh sends to [0.0.0.0]
#   PORT         UDP port                                             [5004]
#   LATENCY_MS   jitter buffer: how late a packet may come, in ms     [100]
#   WATCHDOG_MS  end with an error after this long without a packet; 0 waits forever [10000]
#   SINK         where the frames go                                  [autovideosink]
#
# It shows the stream until Ctrl-C. When no packet comes for WATCHDOG_MS (the sender stopped, the
# network broke) it ends with an error from the element "no-stream-packets", so that a frozen
# picture is never taken for a live one.
#
# Example: pipelines/watch-stream.sh   (while pipelines/stream.sh runs on the camera machine)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
# The build tree's plugin and `launch` (pyrocam-launch, which never hangs after an error).
source "$here/lib/setup.sh"

ADDRESS=${ADDRESS:-0.0.0.0}
PORT=${PORT:-5004}
LATENCY_MS=${LATENCY_MS:-100}
WATCHDOG_MS=${WATCHDOG_MS:-10000}
SINK=${SINK:-autovideosink}
[[ $PORT =~ ^[0-9]+$ ]] && ((10#$PORT >= 1 && 10#$PORT <= 65535)) ||
  { echo "watch-stream: PORT must be a UDP port, 1 to 65535, not '$PORT'" >&2; exit 2; }
[[ $LATENCY_MS =~ ^[0-9]+$ ]] || { echo "watch-stream: LATENCY_MS must be a whole number of milliseconds, not '$LATENCY_MS'" >&2; exit 2; }
[[ $WATCHDOG_MS =~ ^[0-9]+$ ]] || { echo "watch-stream: WATCHDOG_MS must be a whole number of milliseconds, not '$WATCHDOG_MS'" >&2; exit 2; }
[[ $ADDRESS =~ ^[0-9]{1,3}([.][0-9]{1,3}){3}$ || $ADDRESS == *:* ]] && getent ahosts "$ADDRESS" >/dev/null ||
  { echo "watch-stream: ADDRESS must be an IP address of this machine or a multicast group, not '$ADDRESS'" >&2; exit 2; }
require_display "$SINK"

set -f # the fragments above split on spaces into the launcher's words
exec "$launch" \
  udpsrc address="$ADDRESS" port="$PORT" \
    caps=application/x-rtp,media=video,encoding-name=H264,clock-rate=90000,payload=96 ! \
  watchdog name=no-stream-packets timeout="$WATCHDOG_MS" ! \
  rtpjitterbuffer latency="$LATENCY_MS" ! rtph264depay ! h264parse ! avdec_h264 ! \
  videoconvert ! $SINK
