#!/usr/bin/env bash
# Compares `gst-inspect-1.0 <element>` with a committed file, after dropping the lines that
# change with the build or the machine (file name, version, release date, origin). With
# PYROCAM_UPDATE_INSPECT=1 it rewrites the committed file instead.
# Usage: check-inspect.sh <gst-inspect-1.0> <element> <expected.txt>
set -euo pipefail
inspect=$1 element=$2 expected=$3
actual=$(GST_INSPECT_NO_COLORS=1 PAGER=cat "$inspect" --no-colors "$element" 2>&1 |
  sed -e 's/[[:space:]]*$//' |
  grep -Ev '^[[:space:]]*(Filename|Version|Release date|Source module|Binary package|Origin URL|Source release date)[[:space:]]' || true)
if [[ -n "${PYROCAM_UPDATE_INSPECT:-}" ]]; then
  printf '%s\n' "$actual" > "$expected"
  echo "updated $expected"
  exit 0
fi
if [[ ! -f "$expected" ]]; then
  echo "missing $expected: run PYROCAM_UPDATE_INSPECT=1 meson test -C build --suite inspect" >&2
  exit 1
fi
if ! diff -u "$expected" <(printf '%s\n' "$actual"); then
  echo "gst-inspect-1.0 $element differs from $expected (regenerate with" \
       "PYROCAM_UPDATE_INSPECT=1 meson test -C build --suite inspect if intended)" >&2
  exit 1
fi
