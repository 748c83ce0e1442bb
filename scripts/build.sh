#!/usr/bin/env bash
# Configures (once) and builds pyrocam in ./build. Extra arguments go to `meson setup`.
set -euo pipefail
cd "$(dirname "$0")/.."
if [[ ! -f build/build.ninja ]]; then
  meson setup build --buildtype=release "$@"
elif (($# > 0)); then
  meson configure build "$@"
fi
ninja -C build
