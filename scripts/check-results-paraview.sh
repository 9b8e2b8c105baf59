#!/usr/bin/env bash
# Checks that ParaView 5.11's DEFAULT XDMF reader opens peritwin's results and shows the
# displacement, strain and damage (scripts/check-results-paraview.py, run with pvbatch).
#
#   bash scripts/check-results-paraview.sh                 install ParaView, build, run the check
#   bash scripts/check-results-paraview.sh FILE.xdmf       check an existing results file
#   bash scripts/check-results-paraview.sh --replay BIN_DIR OUT_DIR
#                                                          what the CTest test runs: B1 for 12
#                                                          batches by peritwin-replay --in-process
#                                                          --results OUT_DIR, then the check
#
# Not in the default suite (scripts/test.sh): ParaView is about 545 MB installed (paraview +
# python3-paraview, 90 s to install here), so it is its own CTest label, `paraview`, registered
# when the build is configured with -DPERITWIN_PARAVIEW_CHECK=ON (docs/testing.md).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"

check() {
  pvbatch "$root/scripts/check-results-paraview.py" "$1"
}

case "${1:-}" in
  "")
    cd "$root"
    PERITWIN_PARAVIEW_DEPS=1 bash scripts/install-deps.sh
    cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPERITWIN_WERROR=ON -DPERITWIN_PARAVIEW_CHECK=ON
    cmake --build build -j "$(nproc)" --target peritwin-replay
    ctest --test-dir build --output-on-failure -L paraview
    ;;
  --replay)
    bin="$2" out="$3"
    rm -rf "$out"
    mkdir -p "$out"
    # The first 12 batches of the demo history (1000 cycles each): snapshots at states 0 and 10
    # and the last state, 12; the crack has grown by then.
    head -n 17 "$root/examples/b1-cycles.csv" > "$out/b1-12-batches.csv"
    "$bin/peritwin-replay" --config "$root/examples/b1-ct-al6061.toml" \
      --history "$out/b1-12-batches.csv" --in-process --results "$out/b1-ct" > "$out/replay.log"
    check "$out/b1-ct/b1-ct.xdmf"
    ;;
  *)
    check "$1"
    ;;
esac
