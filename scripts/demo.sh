#!/usr/bin/env bash
# Installs the Debian packages, builds, and runs the main job available today: a cold static solve
# of the B1 compact-tension specimen (bond-based and state-based), printing timings and the
# load-line opening as JSON lines. (The daemon + replay demo replaces this when the twin exists.)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j "$(nproc)"
for model in bb osb; do
  ./build/bin/peritwin-bench static --model "$model" --nodes "${NODES:-15000}"
done
