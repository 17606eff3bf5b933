#!/usr/bin/env bash
# The main job: installs what is needed (Debian packages), builds cairn and runs launch_specs/demo.yaml.
# Usage: ./scripts/demo.sh [seconds]   (default 20 s; 0 runs until Ctrl-C)
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install_deps.sh
./scripts/build.sh -DCAIRN_BUILD_BENCHMARKS=OFF   # the demo needs no benchmark drivers
source ./scripts/env.sh
echo "== cairn launch launch_specs/demo.yaml (DDS domain $CAIRN_DOMAIN_ID, loopback only)"
./build/bin/cairn launch launch_specs/demo.yaml --duration "${1:-20}"
