#!/usr/bin/env bash
# Live view: the camera's own image (colour, or a 5x5 camera's centre band) with the calibrated temperature overlay and scale bar.
#
# Settings (environment variables, defaults in brackets):
#   PROFILE      camera: rgb-reference (colour) or nir5x5-reference (5x5 mosaic) [rgb-reference]
#   MODEL        calibrated model; the default is calibrated on first use [out/model-rgb.json,
#                5x5: out/model-nir5x5.json]
#   SOURCE       camera element with its properties                   [pyrocamsrc is-live=true profile=PROFILE;
#                    5x5: scene=plate too; a typical unit, seed 1: add unit=… seed=N
#                    for the simulated unit a model was calibrated on, as simulate --unit-seed N]
#   CAPS         caps after the camera: format, size, frame rate      [video/x-bayer,width=320,height=240,framerate=30/1;
#                5x5: video/x-raw,width=320,height=240,framerate=30/1]
#   DARK         darksub settings: dark-level=N or location=dark.pgm  [dark-level=50]
#   NUM_BUFFERS  frames before the view ends; -1 runs until Ctrl-C    [-1]
#   WATCHDOG_MS  end with an error when the camera sends nothing this long; 0: never [5000]
#   LATENCY_MS   how long the picture waits for its temperature overlay, ms [100]
#   EXPOSURE_CONTROL autoexposure after the camera: the hottest region neither saturates nor goes dim (1) [0]
#   EXPOSURE_LATENCY frames from setting an exposure to the first frame taken with it, for autoexposure [3]
#   PEAK_MARKER  ring the frame's peak and write its temperature on the overlay (1) [0]
#   ALARM_C      thermalalarm: a pyrocam-alarm message when the peak stays above this, degC []
#   BRACKET      exposure factors the camera cycles through, fused by thermalfuse (high dynamic range), e.g. 9,3,1,0.333,0.111,0.037; a camera other than the simulated one is bracketed by autoexposure, one frame passing per EXPOSURE_LATENCY + 1 []
#   BRACKET_FUSION readings: thermalfuse after ratiotemp, each pixel from one frame; mosaics: mosaicfuse before demosaic25, each sample from one frame, following a pool that moves (more of the pool reads; where its brightness changes over the bracket some read wild) [readings]
#   BLUR_CORRECTION ratiotemp blur-correction: steep sides read their footprint's mean temperature, not hotter (1; colour camera) [1 with BRACKET_FUSION=mosaics, else 0]
#   BRIGHTNESS_RADIUS ratiotemp brightness-radius: each pixel read from its own brightness, scaled over a window (colour: (4r+1) pixels; 5x5: (2r+1) cells); only for surfaces of one emissivity over the window (0 = off, 1-8) [0]
#   SINK         where the view goes                                  [autovideosink]
#   STATS_CSV    write ratiotemp's statistics here as CSV, a row every STATS_INTERVAL_MS [none]
#   STATS_INTERVAL_MS  ms between statistics rows                   [1000]
#   ALARM_CSV    write alarm messages (thermalalarm) here as CSV    [none]
#
# Several monitors, window placement and full screen: docs/live-view.md.
#
# Example (the simulated melt pool; the first run calibrates the simulated camera, once):
#   pipelines/live-view.sh
#   PROFILE=nir5x5-reference pipelines/live-view.sh
#   SOURCE="pyrocamsrc is-live=true scene=filament temperature=1800" pipelines/live-view.sh
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
# The build tree's plugin and `launch` (pyrocam-launch, which never hangs after an error).
source "$here/lib/setup.sh"

SINK=${SINK:-autovideosink}
require_display "$SINK"
source "$here/lib/camera.sh"

set -f # SINK splits on spaces into the launcher's words
exec "$launch" -e "${launch_options[@]}" "${camera_chain[@]}" \
  "${thermal_chain[@]}" ! "${colormap_to_mix[@]}" \
  "${overlay_mix[@]}" ! videoconvert ! $SINK
