# Sourced by every script in pipelines/ after it sets `here` to its own folder: uses the plugin of
# the build tree unless GST_PLUGIN_PATH says otherwise, and sets `launch` to pyrocam-launch
# (built with the plugin). Unlike gst-launch-1.0 of GStreamer 1.22 it never hangs after an error
# (exit 1 with the message); with -e SIGINT or SIGTERM sends EOS so that the files are finalised,
# without it they stop the pipeline.
# -h or --help: the script's header comment (what it does, its settings, examples). Settings are
# environment variables: an argument a script does not take (all but playback.sh's RECORDING;
# a script that takes one sets takes_arguments=1) is refused rather than ignored.
for arg in "$@"; do
  if [[ $arg == -h || $arg == --help ]]; then
    sed -n '2,/^[^#]/{/^#/{s/^# \{0,1\}//;p}}' "$0"
    exit 0
  fi
done
if [[ ${takes_arguments:-0} != 1 && $# -gt 0 ]]; then
  echo "$(basename "$0" .sh): no arguments are taken, not '$*': the settings are environment variables (--help lists them)" >&2
  exit 2
fi
if [[ -z ${GST_PLUGIN_PATH:-} && -f $here/../build/plugins/libgstpyrocam.so ]]; then
  export GST_PLUGIN_PATH=$here/../build/plugins
fi
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

# Ends the script with a clear message when the view would go to autovideosink without a display:
# on a machine without one, autovideosink of GStreamer 1.22 falls back to sinks that fail or
# crash (dfbvideosink: segmentation fault). Usage: require_display "$SINK".
require_display() {
  [[ $1 =~ (^|[[:space:]!])autovideosink([[:space:]!]|$) ]] || return 0
  [[ -n ${DISPLAY:-} || -n ${WAYLAND_DISPLAY:-} ]] && return 0
  echo "$(basename "$0" .sh): no display to show the view on (DISPLAY and WAYLAND_DISPLAY are unset):" \
    "run it on a desktop or under Xvfb, or set SINK (e.g. SINK=fakesink; docs/live-view.md)" >&2
  exit 1
}
