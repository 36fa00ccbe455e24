#!/usr/bin/env bash
# Installs the dependencies, builds the `strata` CLI (Release, in build/) and runs the demo: the
# paper's bent-cylinder cases rebuilt by displacement volumes and by displacement vectors, written
# to out/ with a comparison table on stdout. Extra arguments go to `strata demo` (e.g. --triangles 4000).
# Works from any directory; out/ is created in the repository root.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
JOBS=${STRATA_JOBS:-2}

bash tools/setup.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$JOBS" --target strata
exec build/tools/strata demo --out-dir out "$@"
