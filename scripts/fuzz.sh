#!/usr/bin/env bash
# Builds the libFuzzer targets of tests/fuzz with clang, ASan and UBSan (build dir build-fuzz/)
# and fuzzes each for a bounded time, starting from its committed corpus (tests/fuzz/corpus/<t>/).
# Fails when any target finds a crash, a sanitizer error, a leak, a timeout or an out-of-memory;
# the input that did it is left in build-fuzz/fuzz/<target>/ (crash-*, leak-*, timeout-*, oom-*).
#
#   bash scripts/fuzz.sh [SECONDS_PER_TARGET [TARGET...]]    default: 60 s, every target
#
# Targets: batch state reject mesh key_file config series cycles spectrum observations
# observation_msg lcm_log checkpoint (docs/testing.md). What libFuzzer
# finds beyond the committed corpus stays in build-fuzz/fuzz/<target>/corpus/ and seeds the next
# run. PERITWIN_FUZZ_BUILD_DIR overrides build-fuzz; PERITWIN_FUZZ_JOBS the build's -j.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:-60}
shift || true
all=(batch state reject mesh key_file config series cycles spectrum observations observation_msg lcm_log
  checkpoint)
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=("${all[@]}")
if ! [[ "$seconds" =~ ^[0-9]+$ ]] || [ "$seconds" -lt 1 ]; then
  echo "fuzz.sh: SECONDS_PER_TARGET must be a positive integer, got '$seconds'" >&2
  exit 2
fi
for t in "${targets[@]}"; do
  if [[ " ${all[*]} " != *" $t "* ]]; then
    echo "fuzz.sh: unknown target '$t' (known: ${all[*]})" >&2
    exit 2
  fi
done

PERITWIN_SANITIZER_DEPS=1 bash scripts/install-deps.sh
build=${PERITWIN_FUZZ_BUILD_DIR:-build-fuzz}
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
cmake -S . -B "$build" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPERITWIN_FUZZ=ON -DPERITWIN_BUILD_TESTS=OFF \
  -DPERITWIN_WERROR=ON "${launcher[@]}" >/dev/null
cmake --build "$build" -j "${PERITWIN_FUZZ_JOBS:-$(nproc)}" --target peritwin_fuzz_targets

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tests/sanitize/lsan.supp:print_suppressions=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
failed=()
summary=()
for t in "${targets[@]}"; do
  work="$build/fuzz/$t"
  mkdir -p "$work/corpus"
  rm -f "$work"/crash-* "$work"/leak-* "$work"/timeout-* "$work"/oom-* "$work"/slow-unit-*
  # New inputs go to the first corpus directory (the work dir), never to the committed one.
  # -timeout: one input running 10 s is a finding; -malloc_limit_mb: so is one allocation of
  # more than 1 GB from inputs of a few kB.
  set +e
  "$build/bin/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -malloc_limit_mb=1024 -print_final_stats=1 -artifact_prefix="$work/" \
    "$work/corpus" "tests/fuzz/corpus/$t" >"$work/log" 2>&1
  rc=$?
  set -e
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$work/log" | tail -1 || true)
  cov=$( (grep -o 'cov: [0-9]*' "$work/log" || true) | tail -1 | sed 's/cov: //')
  speed=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$work/log" | tail -1 || true)
  line=$(printf '%-11s %10s runs  %7s exec/s  cov %6s' "$t" "${runs:-?}" "${speed:-?}" "${cov:-?}")
  if [ "$rc" -ne 0 ]; then
    failed+=("$t")
    line="$line  FAILED (exit $rc, log $work/log)"
    echo "fuzz.sh: $t failed; the end of its log:" >&2
    tail -n 40 "$work/log" >&2
    ls "$work"/crash-* "$work"/leak-* "$work"/timeout-* "$work"/oom-* 2>/dev/null >&2 || true
  fi
  summary+=("$line")
  echo "fuzz: $line"
done
echo "fuzz.sh: ${#targets[@]} targets x ${seconds} s:"
printf '  %s\n' "${summary[@]}"
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz.sh: FAILED: ${failed[*]} (reproduce: $build/bin/fuzz_<target> <artifact>)" >&2
  exit 1
fi
