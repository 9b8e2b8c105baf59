#!/usr/bin/env bash
# Builds the whole project and its unit tests with AddressSanitizer + UndefinedBehaviorSanitizer
# (GCC 12, every finding fatal; build dir build-asan/) and runs the whole CTest suite under them.
#
#   bash scripts/sanitize.sh [CTEST_ARGS...]     e.g. -R fuzz_corpus, -E Integration
#
# GCC's UBSan leaves out its vptr check (PERITWIN_SANITIZE in CMakeLists.txt: it false-fires on
# LCM 1.3.1's subscription trampoline). PERITWIN_SANITIZE_CC=clang builds with clang 14 instead
# (installs it). PERITWIN_ASAN_BUILD_DIR overrides build-asan; PERITWIN_SANITIZE_JOBS the -j.
set -euo pipefail
cd "$(dirname "$0")/.."

compiler=${PERITWIN_SANITIZE_CC:-gcc}
case "$compiler" in
  gcc) cc=(-DCMAKE_C_COMPILER=gcc -DCMAKE_CXX_COMPILER=g++) ;;
  clang)
    export PERITWIN_SANITIZER_DEPS=1
    cc=(-DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++)
    ;;
  *)
    echo "sanitize.sh: PERITWIN_SANITIZE_CC must be gcc or clang, got '$compiler'" >&2
    exit 2
    ;;
esac
bash scripts/install-deps.sh
build=${PERITWIN_ASAN_BUILD_DIR:-build-asan}
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
# -O1 -g: usable stack traces at a bearable speed.
cmake -S . -B "$build" "${cc[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g" \
  -DPERITWIN_SANITIZE=ON -DPERITWIN_WERROR=ON "${launcher[@]}" >/dev/null
jobs=${PERITWIN_SANITIZE_JOBS:-$(nproc)}
cmake --build "$build" -j "$jobs"

# Leaks are findings too; suppressions for the libraries' own (tests/sanitize/lsan.supp).
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tests/sanitize/lsan.supp:print_suppressions=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
ctest --test-dir "$build" --output-on-failure -j "$jobs" "$@"
