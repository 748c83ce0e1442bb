# Sourced by the scripts in pipelines/ that read a camera through the thermal chain and show the
# overlay (live-view.sh, record.sh, stream.sh, genicam-live.sh), after setup.sh: the camera
# settings' defaults (documented in each script's header) and the pipeline fragments they share,
# as arrays of the launcher's words. `name` is the script's name for messages.
#
# PROFILE picks the camera: rgb-reference (colour Bayer, the default) or nir5x5-reference (5x5
# snapshot mosaic, 25 NIR bands). It sets the defaults of MODEL, SOURCE and CAPS and the camera
# view under the overlay. The default MODEL of a shipped profile is calibrated from a simulated
# furnace campaign on first use (lib/ensure-model.sh); a MODEL set by the user must exist.
name=$(basename "$0" .sh)

PROFILE=${PROFILE:-rgb-reference}
case $PROFILE in
  rgb-reference)
    default_model=out/model-rgb.json
    default_caps=video/x-bayer,width=320,height=240,framerate=30/1 ;;
  nir5x5-reference)
    default_model=out/model-nir5x5.json
    default_caps=video/x-raw,width=320,height=240,framerate=30/1 ;;
  *)
    echo "$name: PROFILE must be rgb-reference (colour camera) or nir5x5-reference (5x5 mosaic), not '$PROFILE'" >&2
    exit 2 ;;
esac

model_given=${MODEL:+yes}
camera_given=${SOURCE:+yes}${CAPS:+yes}  # empty: the simulated camera as its profile makes it
MODEL=${MODEL:-$default_model}
# The simulated 5x5 camera looks at a plate: its melt pool is a few macro-pixels across, most of
# them straddling the pool's edge (no reading).
[[ $PROFILE == nir5x5-reference ]] && default_scene=" scene=plate" || default_scene=""
SOURCE=${SOURCE:-pyrocamsrc is-live=true profile=$PROFILE$default_scene}
CAPS=${CAPS:-$default_caps}
DARK=${DARK:-dark-level=50}
NUM_BUFFERS=${NUM_BUFFERS:--1}
WATCHDOG_MS=${WATCHDOG_MS:-5000}
LATENCY_MS=${LATENCY_MS:-100}
EXPOSURE_CONTROL=${EXPOSURE_CONTROL:-0}
PEAK_MARKER=${PEAK_MARKER:-0}
ALARM_C=${ALARM_C:-}
BRACKET=${BRACKET:-}

[[ $NUM_BUFFERS =~ ^(-1|[0-9]+)$ ]] || { echo "$name: NUM_BUFFERS must be a whole number of frames (-1: until stopped), not '$NUM_BUFFERS'" >&2; exit 2; }
[[ $EXPOSURE_CONTROL =~ ^[01]$ ]] || { echo "$name: EXPOSURE_CONTROL must be 0 or 1, not '$EXPOSURE_CONTROL'" >&2; exit 2; }
[[ $PEAK_MARKER =~ ^[01]$ ]] || { echo "$name: PEAK_MARKER must be 0 or 1, not '$PEAK_MARKER'" >&2; exit 2; }
[[ -z $ALARM_C || $ALARM_C =~ ^[0-9]+([.][0-9]+)?$ ]] || { echo "$name: ALARM_C must be a temperature in degC, not '$ALARM_C'" >&2; exit 2; }
[[ $LATENCY_MS =~ ^[0-9]+$ ]] || { echo "$name: LATENCY_MS must be a whole number of milliseconds, not '$LATENCY_MS'" >&2; exit 2; }
[[ $WATCHDOG_MS =~ ^[0-9]+$ ]] || { echo "$name: WATCHDOG_MS must be a whole number of milliseconds (0: never), not '$WATCHDOG_MS'" >&2; exit 2; }
# BRACKET: the camera cycles through these exposure factors and thermalfuse fuses each cycle
# (high dynamic range). The simulated camera brackets itself (its frames say their exposure);
# another camera (aravissrc, genicam-live) is bracketed by autoexposure, which holds each
# exposure for EXPOSURE_LATENCY + 1 frames and passes the last frame of each, with its exposure.
# BRACKET_FUSION=mosaics fuses the dark-subtracted mosaics instead (mosaicfuse before
# demosaic25): more of the pool's hot pixels read (a moving pool followed as a shift), but where
# its brightness changes over the bracket some read wild.
BRACKET_FUSION=${BRACKET_FUSION:-readings}
[[ $BRACKET_FUSION == readings || $BRACKET_FUSION == mosaics ]] || { echo "$name: BRACKET_FUSION must be readings or mosaics, not '$BRACKET_FUSION'" >&2; exit 2; }
BLUR_CORRECTION=${BLUR_CORRECTION:-}
[[ -z $BLUR_CORRECTION || $BLUR_CORRECTION =~ ^[01]$ ]] || { echo "$name: BLUR_CORRECTION must be 0 or 1, not '$BLUR_CORRECTION'" >&2; exit 2; }
BRIGHTNESS_RADIUS=${BRIGHTNESS_RADIUS:-0}
[[ $BRIGHTNESS_RADIUS =~ ^[0-8]$ ]] || { echo "$name: BRIGHTNESS_RADIUS must be 0 to 8 (Bayer or 5x5 cells), not '$BRIGHTNESS_RADIUS'" >&2; exit 2; }
EXPOSURE_LATENCY=${EXPOSURE_LATENCY:-}
[[ -z $EXPOSURE_LATENCY || $EXPOSURE_LATENCY =~ ^[0-9]+$ ]] || { echo "$name: EXPOSURE_LATENCY must be a whole number of frames, not '$EXPOSURE_LATENCY'" >&2; exit 2; }
bracket_frames=0
bracket_by_autoexposure=0
if [[ -n $BRACKET ]]; then
  [[ $BRACKET =~ ^[0-9.]+(,[0-9.]+)*$ ]] || { echo "$name: BRACKET must be exposure factors separated by commas (e.g. 9,3,1,0.333,0.111,0.037), not '$BRACKET'" >&2; exit 2; }
  if [[ $SOURCE == pyrocamsrc* && $name != genicam-live ]]; then
    [[ $EXPOSURE_CONTROL == 0 ]] || { echo "$name: BRACKET and EXPOSURE_CONTROL=1 do not go together with the simulated camera: the exposure control would chase its bracket's levels" >&2; exit 2; }
    SOURCE="$SOURCE bracket=$BRACKET"
  elif [[ $SOURCE == aravissrc* || $name == genicam-live ]]; then
    bracket_by_autoexposure=1
  else
    echo "$name: BRACKET needs a camera whose exposure can be set: the simulated one (SOURCE=pyrocamsrc ...) or a GenICam camera (SOURCE=aravissrc ...), not '$SOURCE'" >&2
    exit 2
  fi
  bracket_frames=$(($(tr -cd , <<<"$BRACKET" | wc -c) + 1))
fi

set -f # SOURCE, CAPS and DARK split on spaces into the launcher's words
# The camera, ending in the tee `camera`; the watchdog ends the pipeline with an error when the
# camera sends nothing for WATCHDOG_MS.
# EXPOSURE_CONTROL=1 puts autoexposure after it (its dark level darksub's, when DARK gives one).
# A bracket of another camera than the simulated one is autoexposure's (above).
exposure_control=()
if [[ $EXPOSURE_CONTROL == 1 || $bracket_by_autoexposure == 1 ]]; then
  dark_level=$(sed -n 's/^dark-level=\([0-9.]*\)$/\1/p' <<<"$DARK")
  exposure_control=(autoexposure ${dark_level:+dark-level=$dark_level}
    ${EXPOSURE_LATENCY:+latency=$EXPOSURE_LATENCY})
  ((bracket_by_autoexposure == 0)) || exposure_control+=("bracket=$BRACKET")
  exposure_control+=(!)
fi
camera_chain=($SOURCE num-buffers="$NUM_BUFFERS" ! $CAPS ! "${exposure_control[@]}"
  watchdog name=camera-sent-no-frame timeout="$WATCHDOG_MS" ! tee name=camera)
if [[ $PROFILE == nir5x5-reference ]]; then
  # A 5x5 camera reads one temperature per 5x5 macro-pixel (width/5 x height/5). The view and
  # the overlay are both drawn at the sensor's size, each macro-pixel a 5x5 block, so that they
  # line up pixel for pixel: the temperatures scaled up by nearest neighbour (each code kept,
  # none interpolated), the camera view one band, the centre cell of each macro-pixel (the
  # nearest-neighbour scale-down by 5 takes pixel 5i+2), scaled back up the same way.
  width=$(sed -n 's/.*width=\(([a-z]*)\)\{0,1\} *\([0-9]*\).*/\2/p' <<<"$CAPS")
  height=$(sed -n 's/.*height=\(([a-z]*)\)\{0,1\} *\([0-9]*\).*/\2/p' <<<"$CAPS")
  if [[ -z $width || -z $height ]] || ((width % 5 || height % 5)); then
    echo "$name: the 5x5 view needs CAPS with a width and height that are multiples of 5, not '$CAPS'" >&2
    exit 2
  fi
  to_sensor_size=(videoscale method=nearest-neighbour ! "video/x-raw,width=$width,height=$height")
  camera_view=(videoscale method=nearest-neighbour !
    "video/x-raw,width=$((width / 5)),height=$((height / 5))" ! "${to_sensor_size[@]}" !
    videoconvert)
  colormap_scale=("${to_sensor_size[@]}" !)
  # A camera that does not say its band map in its caps (aravissrc) gets the profile's.
  demosaic=(demosaic25 "profile=$PROFILE")
else
  camera_view=(bayer2rgb)
  # Bayer carried as gray video (a 12-bit camera as GRAY16_LE, DARK with pattern=): bayer2rgb
  # takes 8-bit video/x-bayer only, so the overlay goes over the mosaic in gray.
  [[ $(grep -o 'video/x-[a-z]*' <<<"$CAPS" | tail -1) != video/x-raw ]] || camera_view=(videoconvert)
  colormap_scale=()
  demosaic=(demosaic25)
fi
# Camera frames to temperatures (0.1 K codes): `"${thermal_chain[@]}" ! ...`.
mosaic_fusion=()
((bracket_frames == 0)) || [[ $BRACKET_FUSION != mosaics ]] ||
  mosaic_fusion=(mosaicfuse "frames=$bracket_frames" !)
# BLUR_CORRECTION=1: ratiotemp blur-correction=true (colour camera: the steep sides of a pool
# read their mean temperature, not hotter); on by default with BRACKET_FUSION=mosaics, whose
# longest exposures read those sides.
if [[ -z $BLUR_CORRECTION ]]; then
  BLUR_CORRECTION=0
  ((bracket_frames == 0)) || [[ $BRACKET_FUSION != mosaics ]] || BLUR_CORRECTION=1
fi
blur_correction=()
[[ $BLUR_CORRECTION == 1 && $PROFILE != nir5x5-reference ]] && blur_correction=(blur-correction=true)
# BRIGHTNESS_RADIUS=r: ratiotemp brightness-radius=r (colour camera: each pixel read from its own
# sample, scaled over a (4r+1)-pixel window; 5x5: each cell from all its bands, scaled over
# (2r+1) x (2r+1) cells; for surfaces of one emissivity over the window).
brightness=()
[[ $BRIGHTNESS_RADIUS != 0 ]] && brightness=("brightness-radius=$BRIGHTNESS_RADIUS")
thermal_chain=(camera. ! queue ! darksub $DARK ! "${mosaic_fusion[@]}" "${demosaic[@]}" !
  ratiotemp "model=$MODEL" "${blur_correction[@]}" "${brightness[@]}")
# The temperature overlay (transparent where there is no reading) over the camera's image:
# link a colour-mapped branch to mix.overlay_sink, then `"${overlay_mix[@]}" ! ...` gives RGBA
# frames. thermaloverlay pairs each camera frame with the overlay of the same frame and waits for
# it, so no frame goes out under another frame's temperatures or without its own (unless the
# temperature branch drops it); LATENCY_MS is how long that wait is allowed before a live sink
# counts the frame late (it tells the sink; on a loaded machine raise it).
# The queue after it keeps its thread free: in a live pipeline the first sink to get a frame
# waits for the others.
overlay_mix=(camera. ! queue ! "${camera_view[@]}" ! video/x-raw,format=RGBA ! mix.video_sink
  thermaloverlay name=mix latency="$((LATENCY_MS * 1000000))" ! video/x-raw,format=RGBA ! queue)
peak_marker=()
[[ $PEAK_MARKER == 1 ]] && peak_marker=(peak-marker=true)
# The 5x5 camera's temperatures are scaled up 5 times first: the peak's windows of 5 x 5
# macro-pixels (not of 5 x 5 copies of one, which would mark the hottest single pixel).
[[ $PEAK_MARKER == 1 && $PROFILE == nir5x5-reference ]] && peak_marker+=(peak-window=25)
colormap_to_mix=("${colormap_scale[@]}" thermalcolormap scale-bar=true "${peak_marker[@]}" !
  video/x-raw,format=RGBA ! mix.overlay_sink)
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
# BRACKET: thermalfuse after ratiotemp (after the statistics' words, which are ratiotemp's), so
# that the alarm watches fused frames.
((bracket_frames == 0)) || [[ $BRACKET_FUSION != readings ]] ||
  thermal_chain+=(! thermalfuse "frames=$bracket_frames")
# ALARM_C: thermalalarm after ratiotemp, on the frame's peak for 5 frames (after the statistics'
# words above, which are ratiotemp's).
[[ -z $ALARM_C ]] || thermal_chain+=(! thermalalarm "threshold-c=$ALARM_C" statistic=peak)
# Last, after every setting was checked: a first calibration takes a minute or two.
if [[ ! -f $MODEL ]]; then
  if [[ -n $model_given ]]; then
    echo "$name: no model file $MODEL (set MODEL to a model from pyrocam-calib calibrate)" >&2
    exit 1
  fi
  "$here/lib/ensure-model.sh" "$PROFILE" "$MODEL" >&2 ||
    { echo "$name: could not calibrate the default model $MODEL of $PROFILE" >&2; exit 1; }
fi
