#!/usr/bin/env bash
# Installs the Debian packages KCCD builds and tests with (skips apt when all are present).
set -euo pipefail
packages=(
  g++ cmake ninja-build pkg-config
  libeigen3-dev libccd-dev libyaml-cpp-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  nlohmann-json3-dev
  libfcl-dev libqhull-dev
  libcoin-dev inventor-data liburdfdom-dev libassimp-dev
  libosmesa6-dev libgl-dev libegl-dev libopengl-dev libegl-mesa0
  libopencv-dev libpng-dev libtinyxml2-dev libapriltag-dev
)
# --fuzz: also the compiler and runtime of the libFuzzer targets (scripts/fuzz.sh).
[ "${1:-}" = "--fuzz" ] && packages+=(clang-14 libclang-rt-14-dev)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
