#!/usr/bin/env bash
# Builds pyrocam with AddressSanitizer and UndefinedBehaviorSanitizer (g++, into ./build-sanitized,
# configured once) and runs the `lib` and `elements` test suites there. Undefined behaviour fails
# the test (-fno-sanitize-recover), so does any leak in pyrocam's own code; only what GStreamer,
# GLib and TBB keep for the life of the process is suppressed (tests/sanitizers/lsan.supp).
# Usage: scripts/test-sanitized.sh [extra `meson test` arguments, e.g. a test name]
# On a busy 2-core machine: about 40 min to build the first time, about 15 min of tests.
set -euo pipefail
cd "$(dirname "$0")/.."
src=$PWD
dir=build-sanitized
begun=$(date +%s)
if [[ ! -f $dir/build.ninja ]]; then
  # -O1 and line tables only: the sanitizers' usual setting, and a much quicker build than -O2 -g.
  # No -DNDEBUG: assertions stay on.
  flags="-O1 -g1 -fno-sanitize-recover=undefined"
  meson setup "$dir" --buildtype=plain -Dwerror=true -Db_sanitize=address,undefined \
    -Db_lundef=false -Dcpp_args="$flags" -Dc_args="$flags"
fi
# Only what the two suites run and need (not the benchmarks or the pipeline tests).
mapfile -t needed < <(python3 - "$dir" <<'PY'
import json, subprocess, sys
d = sys.argv[1]
intro = lambda what: json.loads(subprocess.check_output(["meson", "introspect", d, what]))
files = {t["id"]: t["filename"] for t in intro("--targets")}
for t in intro("--tests"):
    if {"pyrocam:lib", "pyrocam:elements"} & set(t["suite"]):
        for dep in t["depends"]:
            for f in files.get(dep, []):
                print(f.split(d + "/", 1)[-1] if "/" + d + "/" in f else f)
PY
)
ninja -C "$dir" -j "${JOBS:-2}" "${needed[@]}"

# The plugin is an ASan-built module dlopen()ed by the test programs (themselves ASan-built):
# scan it in-process, not in gst-plugin-scanner (a plain program that would refuse it).
export GST_REGISTRY_FORK=no
# Full stacks for every allocation (the suppressions match frames deep inside GStreamer).
export ASAN_OPTIONS=detect_leaks=1:fast_unwind_on_malloc=0:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1
export LSAN_OPTIONS=suppressions=$src/tests/sanitizers/lsan.supp:print_suppressions=0
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# The element tests' pipelines wait up to this many times as long for their end (element_support.h).
export PYROCAM_TEST_TIME_FACTOR=${PYROCAM_TEST_TIME_FACTOR:-10}
started=$(date +%s)
set +e
meson test -C "$dir" --no-rebuild --suite lib --suite elements --print-errorlogs --num-processes 2 \
  --timeout-multiplier 10 "$@" 2>&1 | tee "$dir/test-output.txt"
rc=${PIPESTATUS[0]}
set -e
echo "test-sanitized: $(($(date +%s) - begun)) s in all, $(($(date +%s) - started)) s of tests;" \
  "log: $dir/meson-logs/testlog.txt"
exit "$rc"
