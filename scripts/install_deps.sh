#!/usr/bin/env bash
# Installs every Debian package cairn needs to build, test and run. Idempotent: packages that are
# already installed are skipped, so a second run does no apt work at all. (libpcl-dev is not listed: no code
# uses PCL yet, and it pulls in VTK and Qt on a fresh machine; add it with the first find_package(PCL).)
set -euo pipefail
PKGS=(
  build-essential cmake ninja-build pkg-config ccache git python3
  cyclonedds-dev cyclonedds-tools
  libeigen3-dev libsuitesparse-dev libceres-dev libopencv-dev
  libyaml-cpp-dev libtinyxml2-dev liburdfdom-dev liburdfdom-headers-dev libbz2-dev libpng-dev zlib1g-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  colcon python3-colcon-cmake python3-colcon-test-result python3-colcon-package-selection
  python3-colcon-output python3-colcon-parallel-executor python3-colcon-library-path
  python3-colcon-recursive-crawl python3-colcon-defaults python3-colcon-package-information
)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#PKGS[@]} packages present"
  exit 0
fi
echo "install_deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install_deps: done"
