# Sourced by the scripts in pipelines/ that read a camera through the thermal chain and show the
# overlay (live-view.sh, record.sh, stream.sh), after setup.sh: the camera settings' defaults
# (documented in each script's header) and the pipeline fragments they share, as arrays of the
# launcher's words. `name` is the script's name for messages.
name=$(basename "$0" .sh)

MODEL=${MODEL:-out/model-rgb.json}
SOURCE=${SOURCE:-pyrocamsrc is-live=true}
CAPS=${CAPS:-video/x-bayer,width=320,height=240,framerate=30/1}
DARK=${DARK:-dark-level=50}
NUM_BUFFERS=${NUM_BUFFERS:--1}
WATCHDOG_MS=${WATCHDOG_MS:-5000}
LATENCY_MS=${LATENCY_MS:-100}

[[ -f $MODEL ]] || { echo "$name: no model file $MODEL (set MODEL, or run scripts/main-job.sh)" >&2; exit 1; }
[[ $LATENCY_MS =~ ^[0-9]+$ ]] || { echo "$name: LATENCY_MS must be a whole number of milliseconds, not '$LATENCY_MS'" >&2; exit 2; }

set -f # SOURCE, CAPS and DARK split on spaces into the launcher's words
# The camera, ending in the tee `camera`; the watchdog ends the pipeline with an error when the
# camera sends nothing for WATCHDOG_MS.
camera_chain=($SOURCE num-buffers="$NUM_BUFFERS" ! $CAPS !
  watchdog name=camera-sent-no-frame timeout="$WATCHDOG_MS" ! tee name=camera)
# Camera frames to temperatures (0.1 K codes): `"${thermal_chain[@]}" ! ...`.
thermal_chain=(camera. ! queue ! darksub $DARK ! demosaic25 ! ratiotemp "model=$MODEL")
# The temperature overlay (transparent where there is no reading) over the camera's colour image:
# link a colour-mapped branch to mix.sink_1, then `"${overlay_mix[@]}" ! ...` gives RGBA frames.
# compositor, live: start-time-selection=first starts its output at the camera's first frame
# (not at 0, which adds frames before it and can negotiate a 1x1 picture); it waits LATENCY_MS
# for the slower temperature branch, so that no frame goes out without its overlay (on a loaded
# machine the branch can take longer: raise it).
# The queue after it keeps its thread free: in a live pipeline the first sink to get a frame
# waits for the others, while compositor answers the tee's allocation queries from that thread,
# so without the queue the start can deadlock (GStreamer 1.22).
overlay_mix=(camera. ! queue ! bayer2rgb ! video/x-raw,format=RGBA ! mix.sink_0
  compositor name=mix start-time-selection=first latency="$((LATENCY_MS * 1000000))"
  sink_0::zorder=0 sink_1::zorder=1 ! video/x-raw,format=RGBA ! queue)
colormap_to_mix=(thermalcolormap scale-bar=true ! video/x-raw,format=RGBA ! mix.sink_1)
set +f

# STATS_CSV: ratiotemp's statistics (a message every STATS_INTERVAL_MS) written by the launcher as
# CSV rows, flushed row by row; ALARM_CSV: alarm messages (thermalalarm) likewise. Scripts pass
# `"${launch_options[@]}"` to the launcher.
STATS_CSV=${STATS_CSV:-}
ALARM_CSV=${ALARM_CSV:-}
STATS_INTERVAL_MS=${STATS_INTERVAL_MS:-1000}
launch_options=()
if [[ -n $STATS_CSV ]]; then
  [[ $STATS_INTERVAL_MS =~ ^[0-9]+$ && $STATS_INTERVAL_MS -gt 0 ]] ||
    { echo "$name: STATS_INTERVAL_MS must be a whole number of milliseconds above 0, not '$STATS_INTERVAL_MS'" >&2; exit 2; }
  thermal_chain+=(stats-interval="$((STATS_INTERVAL_MS * 1000000))")  # words for ratiotemp
  launch_options+=("--stats-csv=$STATS_CSV")
fi
[[ -z $ALARM_CSV ]] || launch_options+=("--alarm-csv=$ALARM_CSV")
