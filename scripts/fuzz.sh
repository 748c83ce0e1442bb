#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz; clang with AddressSanitizer and UBSan, into
# ./build-fuzz, configured once) and runs each for SECONDS, then prints per target the inputs
# run, the coverage reached and the findings (crashes, sanitizer reports, leaks, out-of-memory
# above 2 GB, inputs taking over 25 s). Exits 1 if any target has a finding.
#
# Usage: scripts/fuzz.sh SECONDS [TARGET...]
#   targets: image (PGM/PNG/TIFF), manifest (dataset), profile, model, imec (IMEC XML),
#            curve (spectrum CSV); all of them by default.
# Settings (environment variables, defaults in brackets):
#   KEEP_GOING  1: go on after a finding (libFuzzer's -fork=1 with -ignore_crashes, -ignore_ooms,
#               -ignore_timeouts) and collect every failing input; 0: stop at the first    [1]
#   STRICT      1: an exception other than pyrocam::InputError is a finding too             [0]
#   JOBS        build jobs                                                                    [2]
# The corpus of each target grows across runs in build-fuzz/corpus/TARGET (seeded from
# tests/fuzz/seeds/TARGET and the shipped profiles and curves); the failing inputs of a run go to
# build-fuzz/findings/DATE/TARGET/ (reproduce one with build-fuzz/tests/fuzz/fuzz_TARGET FILE).
# Needs clang and libFuzzer (apt-get install clang libfuzzer-14-dev; installed here if missing).
set -euo pipefail
cd "$(dirname "$0")/.."
if (($# < 1)) || ! [[ $1 =~ ^[0-9]+$ ]]; then
  sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//' >&2
  exit 2
fi
seconds=$1
shift
all=(image manifest profile model imec curve)
targets=("$@")
((${#targets[@]})) || targets=("${all[@]}")
for t in "${targets[@]}"; do
  [[ " ${all[*]} " == *" $t "* ]] || { echo "fuzz: unknown target $t (${all[*]})" >&2; exit 2; }
done

if ! command -v clang++ >/dev/null || ! compgen -G "/usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a" >/dev/null; then
  echo "fuzz: installing clang and libFuzzer" >&2
  sudo=""
  [[ $(id -u) -eq 0 ]] || sudo=sudo
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends clang libfuzzer-14-dev
fi

dir=build-fuzz
if [[ ! -f $dir/build.ninja ]]; then
  CC=clang CXX=clang++ meson setup "$dir" --buildtype=debugoptimized -Dfuzzing=true \
    -Db_sanitize=address,undefined -Db_lundef=false \
    -Dcpp_args=-fno-sanitize-recover=undefined -Dc_args=-fno-sanitize-recover=undefined
fi
ninja -C "$dir" -j "${JOBS:-2}" "${targets[@]/#/tests/fuzz/fuzz_}"

# Seeds: the committed ones and the shipped files each reader reads.
for t in "${targets[@]}"; do
  mkdir -p "$dir/corpus/$t"
  cp -n tests/fuzz/seeds/"$t"/* "$dir/corpus/$t/" 2>/dev/null || true
done
[[ -d $dir/corpus/profile ]] && cp -n profiles/*.json "$dir/corpus/profile/"
[[ -d $dir/corpus/curve ]] && cp -n profiles/curves/*.csv "$dir/corpus/curve/"

declare -A max_len=([image]=8192 [manifest]=2048 [profile]=8192 [model]=32768 [imec]=8192
                    [curve]=8192)
export ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=0
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export PYROCAM_FUZZ_STRICT=${STRICT:-0}
keep_going=()
[[ ${KEEP_GOING:-1} == 1 ]] && keep_going=(-fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1)
findings_root=$dir/findings/$(date -u +%Y%m%dT%H%M%S)
summary=()
failed=0
for t in "${targets[@]}"; do
  out=$findings_root/$t
  mkdir -p "$out"
  echo "fuzz: $t for $seconds s (log: $out/fuzz.log)"
  set +e
  "$dir/tests/fuzz/fuzz_$t" "$dir/corpus/$t" -max_total_time="$seconds" -rss_limit_mb=2048 \
    -malloc_limit_mb=2048 -timeout=25 -max_len="${max_len[$t]}" -artifact_prefix="$out/" \
    -print_final_stats=1 "${keep_going[@]}" >"$out/fuzz.log" 2>&1
  rc=$?
  set -e
  # Fork mode: "#RUNS: cov: C ft: F corp: N ..."; otherwise "#RUNS <WHAT> cov: C ft: F corp: N/..".
  last=$(grep -aE '^#[0-9]+[: ]' "$out/fuzz.log" | grep -a 'cov:' | tail -1 || true)
  runs=$(sed -nE 's/^#([0-9]+).*/\1/p' <<<"$last")
  cov=$(sed -nE 's/.* cov: ([0-9]+).*/\1/p' <<<"$last")
  ft=$(sed -nE 's/.* ft: ([0-9]+).*/\1/p' <<<"$last")
  corp=$(sed -nE 's/.* corp: ([0-9]+).*/\1/p' <<<"$last")
  found=$(find "$out" -maxdepth 1 -type f \( -name 'crash-*' -o -name 'leak-*' -o -name 'oom-*' \
    -o -name 'timeout-*' \) | wc -l)
  if ((found == 0)) && ((rc != 0)); then found="?"; fi  # stopped without leaving an input
  line=$(printf '%-9s %10s runs  cov %6s  ft %6s  corpus %5s  findings %s' "$t" "${runs:-?}" \
    "${cov:-?}" "${ft:-?}" "${corp:-?}" "$found")
  [[ $found != 0 ]] && { line+="  ($out)"; failed=1; }
  summary+=("$line")
done
echo
printf '%s\n' "${summary[@]}"
exit "$failed"
