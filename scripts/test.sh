#!/usr/bin/env bash
# Installs the Debian packages, builds (Release) and runs the whole test suite with CTest, then
# fuzzes every fuzz target for a few seconds (scripts/fuzz.sh; docs/testing.md).
#   PERITWIN_FUZZ_SECONDS   seconds per fuzz target, default 6 (a minute in all); 0 skips
#   PERITWIN_TEST_SANITIZE  1 also runs the whole suite under ASan + UBSan (scripts/sanitize.sh,
#                           about 20 min more on 2 cores); 0 (default) leaves that to its script
set -euo pipefail
cd "$(dirname "$0")/.."
fuzz_seconds=${PERITWIN_FUZZ_SECONDS:-6}
sanitize=${PERITWIN_TEST_SANITIZE:-0}
if ! [[ "$fuzz_seconds" =~ ^[0-9]+$ ]]; then
  echo "test.sh: PERITWIN_FUZZ_SECONDS must be a whole number of seconds, got '$fuzz_seconds'" >&2
  exit 2
fi
if [ "$sanitize" != 0 ] && [ "$sanitize" != 1 ]; then
  echo "test.sh: PERITWIN_TEST_SANITIZE must be 0 or 1, got '$sanitize'" >&2
  exit 2
fi
bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPERITWIN_WERROR=ON
cmake --build build -j "$(nproc)"
ctest --test-dir build --output-on-failure -j "$(nproc)"
if [ "$fuzz_seconds" -gt 0 ]; then
  bash scripts/fuzz.sh "$fuzz_seconds"
fi
if [ "$sanitize" = 1 ]; then
  bash scripts/sanitize.sh
fi
