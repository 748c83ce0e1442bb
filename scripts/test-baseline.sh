#!/usr/bin/env bash
# Every test with the baseline code paths forced, as on an x86-64 machine without AVX2 or FMA:
# the library built without its x86-64-v3 clones (build-baseline/, -Dvector_clones=false) and
# glibc told to hide AVX2, FMA and AVX-512 from its per-CPU libm variants. The results must be
# the same as command 2's (scripts/test-all.sh). Extra arguments go to `meson test`.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
if [[ ! -f build-baseline/build.ninja ]]; then
  meson setup build-baseline --buildtype=release -Dwerror=true -Dvector_clones=false
fi
export GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA,-AVX512F,-AVX512VL,-AVX512BW,-AVX512DQ,-AVX
# OpenCV dispatches on the CPU too.
export OPENCV_CPU_DISABLE=AVX,AVX2,FMA3,FP16,POPCNT
# The test models are made at build time: make them under the same tunables.
ninja -C build-baseline
set +e
meson test -C build-baseline --print-errorlogs --num-processes 2 "$@" 2>&1 |
  tee build-baseline/test-output.txt
rc=${PIPESTATUS[0]}
set -e
ok=$(sed -n 's/^Ok: *\([0-9]*\).*/\1/p' build-baseline/test-output.txt | tail -1)
fail=$(sed -n 's/^Fail: *\([0-9]*\).*/\1/p' build-baseline/test-output.txt | tail -1)
timeout=$(sed -n 's/^Timeout: *\([0-9]*\).*/\1/p' build-baseline/test-output.txt | tail -1)
echo "baseline tests: ${ok:-0} passed, $(( ${fail:-0} + ${timeout:-0} )) failed"
exit "$rc"
