#!/usr/bin/env bash
# Installs the Debian 12 packages pyrocam needs, only those missing (quick when all are there).
# With --tests also those only the tests need (scripts/test-all.sh passes it).
set -euo pipefail

packages=(
  meson ninja-build pkg-config g++ clang-format
  libgstreamer1.0-dev libgstreamer-plugins-base1.0-dev libgstrtspserver-1.0-dev
  gstreamer1.0-tools gstreamer1.0-plugins-base gstreamer1.0-plugins-good
  gstreamer1.0-plugins-bad gstreamer1.0-plugins-ugly gstreamer1.0-libav
  gstreamer1.0-x
  libaravis-dev aravis-tools aravis-tools-cli libusb-1.0-0-dev
  libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev libtiff-dev
  libeigen3-dev libgtest-dev nlohmann-json3-dev libcli11-dev libpugixml-dev
  libsoup-3.0-dev libjs-chart.js
)

# Only for the tests.
test_packages=(
  xvfb
  # examples/read_recording.py (run by the pipelines tests)
  python3-gi gir1.2-gstreamer-1.0 gir1.2-gst-plugins-base-1.0 python3-numpy
  chromium
  # the serve-lossless test reads /temperature with ffmpeg's RTSP client too
  ffmpeg
)
if [[ ${1:-} == --tests ]]; then
  packages+=("${test_packages[@]}")
elif (($# > 0)); then
  echo "install-deps: unknown argument '$1' (the only one is --tests)" >&2
  exit 2
fi

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
sudo=""
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "install-deps: need root or sudo to install packages" >&2; exit 1; }
  sudo="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
