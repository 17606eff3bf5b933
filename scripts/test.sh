#!/usr/bin/env bash
# Installs what is needed (Debian packages), builds everything and runs all tests (ctest).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install_deps.sh
./scripts/build.sh -DCAIRN_BUILD_BENCHMARKS=OFF
ctest --test-dir build --output-on-failure -j "${CAIRN_TEST_JOBS:-2}" --timeout 600 "$@"
