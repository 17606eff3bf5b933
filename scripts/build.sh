#!/usr/bin/env bash
# Configures and builds the superbuild into ./build (Ninja, ccache, Release). Extra args go to cmake.
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=${CAIRN_JOBS:-$(nproc)}
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DCAIRN_WERROR=${CAIRN_WERROR:-ON} "$@" >/dev/null
cmake --build build -j "$JOBS"
