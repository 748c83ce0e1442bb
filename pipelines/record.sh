#!/usr/bin/env bash
# Record: temperatures as 16-bit lossless video (FFV1 in Matroska segments) plus a colour-mapped snapshot PNG.
#
# The temperatures (GRAY16_LE, 0.1 K per step, 0 = no reading) go to OUT/temperature-NNNNN.mkv,
# a new segment every SEGMENT_SECONDS, so that a crash loses at most the segment being written.
# Ctrl-C (SIGINT) or SIGTERM sends EOS and finalises the last segment (a second one stops at
# once, leaving it unfinalised). A killed recording (SIGKILL, power cut) keeps every closed
# segment intact; the segment being written decodes up to its last whole frame, but has no
# index (no seeking) and no duration: players estimate one from its last frame.
# Each segment's title and comment tags (from ratiotemp) say the units, the model and its
# fingerprint, the profile, the method and the e-slope; see docs/recordings.md, which also
# covers `pyrocam-calib export` (TIFF, .npy, CSV) and STATS_CSV.
# The colour-mapped view (overlay over the camera's colour image) is written
# to OUT/view.png, refreshed SNAPSHOT_RATE times a second. A camera that sends nothing for
# WATCHDOG_MS ends the recording with an error: the segments already closed stay intact, and
# the one being written is finalised with its frames (an end of stream sent past the camera).
#
# Settings (environment variables, defaults in brackets):
#   PROFILE          camera: rgb-reference (colour) or nir5x5-reference (5x5 mosaic) [rgb-reference]
#   MODEL            calibrated model; the default is calibrated on first use [out/model-rgb.json,
#                    5x5: out/model-nir5x5.json]
#   OUT              folder for the segments and the snapshot            [out/recording]
#   SOURCE           camera element with its properties                  [pyrocamsrc is-live=true profile=PROFILE;
#                    5x5: scene=plate too; a typical unit, seed 1: add unit=… seed=N
#                    for the simulated unit a model was calibrated on, as simulate --unit-seed N]
#   CAPS             caps after the camera: format, size, frame rate     [video/x-bayer,width=320,height=240,framerate=30/1;
#                    5x5: video/x-raw,width=320,height=240,framerate=30/1]
#   DARK             darksub settings: dark-level=N or location=dark.pgm [dark-level=50]
#   NUM_BUFFERS      frames to record; -1 records until Ctrl-C           [-1]
#   WATCHDOG_MS      end with an error when the camera sends nothing this long; 0: never [5000]
#   LATENCY_MS       how long the picture waits for its temperature overlay, ms [100]
#   EXPOSURE_CONTROL autoexposure after the camera: the hottest region neither saturates nor goes dim (1) [0]
#   EXPOSURE_LATENCY frames from setting an exposure to the first frame taken with it, for autoexposure [3]
#   PEAK_MARKER      ring the frame's peak and write its temperature on the overlay (1) [0]
#   ALARM_C          thermalalarm: a pyrocam-alarm message when the peak stays above this, degC []
#   BRACKET          exposure factors the camera cycles through, fused by thermalfuse (high dynamic range), e.g. 9,3,1,0.333,0.111,0.037; a camera other than the simulated one is bracketed by autoexposure, one frame passing per EXPOSURE_LATENCY + 1 []
#   BRACKET_FUSION   readings: thermalfuse after ratiotemp, each pixel from one frame; mosaics: mosaicfuse before demosaic25, each sample from one frame, following a pool that moves (more of the pool reads; where its brightness changes over the bracket some read wild) [readings]
#   BLUR_CORRECTION ratiotemp blur-correction: steep sides read their footprint's mean temperature, not hotter (1; colour camera) [1 with BRACKET_FUSION=mosaics, else 0]
#   BRIGHTNESS_RADIUS ratiotemp brightness-radius: each pixel read from its own brightness, scaled over a window (colour: (4r+1) pixels; 5x5: (2r+1) cells); only for surfaces of one emissivity over the window (0 = off, 1-8) [0]
#   SEGMENT_SECONDS  length of one segment in seconds (decimals allowed) [10]
#   SNAPSHOT_RATE    snapshots per second (at most the frame rate)       [1]
#   STATS_CSV    write ratiotemp's statistics here as CSV, a row every STATS_INTERVAL_MS [none]
#   STATS_INTERVAL_MS  ms between statistics rows                   [1000]
#   ALARM_CSV    write alarm messages (thermalalarm) here as CSV    [none]
#   RAW              1: also the camera's raw mosaic, lossless, in OUT/raw-NNNNN.mkv; a Bayer
#                    camera other than the simulated one needs its layout in CAPS (format=) or DARK (pattern=) [0]
#
# Example: 300 frames of the simulated melt pool (10 s at 30 fps) into out/pool
#   OUT=out/pool NUM_BUFFERS=300 SOURCE="pyrocamsrc scene=melt-pool" pipelines/record.sh
#   pipelines/playback.sh out/pool
# From a GenICam camera, with its own model and dark:
#   MODEL=cam.json DARK=location=cam-dark.pgm SOURCE="aravissrc camera-name=192.168.1.42" \
#     CAPS=video/x-bayer,format=rggb,width=1024,height=768 OUT=out/run2 pipelines/record.sh
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
# The build tree's plugin and `launch` (pyrocam-launch, which never hangs after an error).
source "$here/lib/setup.sh"

OUT=${OUT:-out/recording}
SEGMENT_SECONDS=${SEGMENT_SECONDS:-10}
SNAPSHOT_RATE=${SNAPSHOT_RATE:-1}
RAW=${RAW:-0}
# Before camera.sh, which may calibrate a model first.
[[ $SNAPSHOT_RATE =~ ^[1-9][0-9]*$ ]] ||
  { echo "record: SNAPSHOT_RATE must be a whole number of snapshots a second, 1 or more, not '$SNAPSHOT_RATE'" >&2; exit 2; }
source "$here/lib/camera.sh"

# 0 would be one segment for the whole recording, and splitmuxsink takes at most 2^64 ns.
[[ $SEGMENT_SECONDS =~ ^[0-9]*[.]?[0-9]+$ ]] &&
  segment_ns=$(awk -v s="$SEGMENT_SECONDS" 'BEGIN { if (!(s >= 0.1 && s <= 86400)) exit 1; printf "%.0f", s * 1e9 }') ||
  { echo "record: SEGMENT_SECONDS must be a number of seconds from 0.1 to 86400, not '$SEGMENT_SECONDS'" >&2; exit 2; }
if compgen -G "$OUT/temperature-*.mkv" >/dev/null; then
  echo "record: $OUT already holds a recording; choose another OUT" >&2
  exit 1
fi

# Every FFV1 frame is a key frame (gop-size=1): a segment can start on any frame and decodes
# alone. A segment cut short by SIGKILL or a power cut has no index and no duration, and players
# estimate its duration from the time of its last cluster: so each frame is its own Matroska
# cluster (min-cluster-duration=0, about 1 % more bytes) and each segment starts at time 0
# (offset-to-zero=true; splitmuxsrc and playback.sh join them). Measured on killed segments:
# 7 frames (0.233 s) estimated 0.233 s; with the defaults 9 frames estimated 2.734 s (the
# recording's time at the last 0.5 s cluster) and, in a first segment, 2.0 s estimated 1.0 s.
# splitmuxsink sets muxer properties only with async-finalize=true. The snapshot branch keeps
# SNAPSHOT_RATE frames a second, so PNG encoding costs little.
segments=(avenc_ffv1 gop-size=1 ! splitmuxsink async-finalize=true muxer-factory=matroskamux
  "muxer-properties=properties,min-cluster-duration=(guint64)0,offset-to-zero=true"
  max-size-time="$segment_ns")
# RAW=1: the camera's frames as they came (8-bit Bayer as GRAY8, FFV1 has no Bayer format) in
# segments beside the temperatures, frame for frame, for `pyrocam-calib measure --recording`;
# their comment tag gives DARK and the mosaic: 5x5, or the Bayer layout.
# identity keeps the encoder's allocation query from the camera, which then allocates from its
# own pool whatever the encoder would propose.
raw_branch=()
if [[ $RAW == 1 && -n $BRACKET ]]; then
  # measure --recording reads frame by frame: it would not fuse the bracket, and its readings
  # would not be the recorded ones.
  echo "record: RAW=1 and BRACKET do not go together yet (pyrocam-calib measure --recording does not fuse a bracket)" >&2
  exit 2
fi
if [[ $RAW == 1 ]]; then
  # A raw Bayer frame does not say its layout, and read as another one it gives about half the
  # temperature: the layout comes from CAPS, DARK or the simulated camera's profile, or RAW=1 is
  # refused.
  if [[ $PROFILE == nir5x5-reference ]]; then raw_pattern=5x5
  elif [[ $CAPS =~ format=(rggb|bggr|grbg|gbrg) ]]; then raw_pattern=${BASH_REMATCH[1]}
  elif [[ " $DARK " =~ \ pattern=(rggb|bggr|grbg|gbrg)\  ]]; then raw_pattern=${BASH_REMATCH[1]}
  elif [[ -z $camera_given ]]; then raw_pattern=rggb  # the rgb-reference profile's
  else
    echo "record: RAW=1 needs the camera's Bayer layout, which raw frames do not say: name it in CAPS (video/x-bayer,format=rggb, bggr, grbg or gbrg) or DARK (pattern=...)" >&2
    exit 2
  fi
  raw_tags="pyrocam-raw; dark=$DARK; pattern=$raw_pattern"
  raw_branch=(camera. ! queue ! identity drop-allocation=true !)
  [[ $CAPS != video/x-bayer* ]] || raw_branch+=(capssetter join=false caps=video/x-raw,format=GRAY8 !)
  raw_branch+=(taginject "tags=\"comment=\\\"$raw_tags\\\"\"" ! "${segments[@]}" "location=$OUT/raw-%05d.mkv")
elif [[ $RAW != 0 ]]; then
  echo "record: RAW must be 0 or 1, not '$RAW'" >&2
  exit 2
fi
# Only now, so that a refused setting leaves no empty folder behind.
mkdir -p "$OUT" || { echo "record: cannot create the folder OUT=$OUT" >&2; exit 1; }
exec "$launch" -e "${launch_options[@]}" "${camera_chain[@]}" \
  "${thermal_chain[@]}" ! tee name=temperature \
  temperature. ! queue ! "${segments[@]}" "location=$OUT/temperature-%05d.mkv" \
  "${raw_branch[@]}" \
  temperature. ! queue ! "${colormap_to_mix[@]}" \
  "${overlay_mix[@]}" ! \
    videorate drop-only=true max-rate="$SNAPSHOT_RATE" ! videoconvert ! video/x-raw,format=RGB ! \
    pngenc ! multifilesink "location=$OUT/view.png"
