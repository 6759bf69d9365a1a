#!/usr/bin/env bash
# Installs the Debian packages KCCD builds and tests with (skips apt when all are present).
set -euo pipefail
packages=(
  g++ cmake ninja-build pkg-config
  libeigen3-dev libccd-dev libyaml-cpp-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  nlohmann-json3-dev libcpp-httplib-dev libssl-dev
  libfcl-dev libqhull-dev
  libcoin-dev inventor-data liburdfdom-dev libassimp-dev
  libosmesa6-dev libgl-dev libegl-dev libopengl-dev libegl-mesa0
  libopencv-dev libavformat-dev libavcodec-dev libavutil-dev libswscale-dev libpng-dev libjpeg62-turbo-dev libtinyxml2-dev libapriltag-dev
  zlib1g-dev libzstd-dev liblz4-dev libbz2-dev libsqlite3-dev libsnappy-dev
  python3-dev pybind11-dev python3-numpy
  python3-yaml python3-distributed python3-dask
)
# Options (any of them, in any order):
#   --fuzz   also the compiler and runtime of the libFuzzer targets (scripts/fuzz.sh)
#   --tests  also what the labelling page's tests run: Debian's chromium, node and npm (below),
#            and npm's playwright-core in tests/e2e (scripts/test.sh); and the Python package's:
#            pytest, mypy and typeshed's stubs (PyYAML's, for mypy --strict on kccd.batch); and the
#            robot-log tests' fixture writers: ROS 1's rosbag with its sensor_msgs and lz4
#            (python3-rosbag, python3-sensor-msgs, python3-roslz4), npm's @mcap/core (tests/bags);
#            the dataset tests' writers: npm's parquet-wasm, apache-arrow and hyparquet-writer
#            (tests/datasets) and Debian's FFmpeg (AV1, h264 and mpeg4 videos);
#            and clang-format and clang-tidy (scripts/lint.sh).
#   --package  also what scripts/package.sh makes Debian packages with: dpkg-shlibdeps (dpkg-dev),
#            help2man (the manual page) and lintian to check them
#   --docs   also what scripts/docs.sh builds the site with: Sphinx, MyST (Markdown pages), Breathe
#            on Doxygen's XML (the C++ API), the Furo theme
tests=0
for arg in "$@"; do
  case "$arg" in
    --fuzz) packages+=(clang-14 libclang-rt-14-dev) ;;
    --package) packages+=(dpkg-dev lintian help2man) ;;
    --docs) packages+=(python3-sphinx python3-myst-parser python3-breathe doxygen furo) ;;
    --tests) tests=1; packages+=(chromium python3-pytest python3-matplotlib mypy python3-typeshed python3-rosbag python3-sensor-msgs python3-roslz4 clang-format clang-tidy ffmpeg) ;;
    *) echo "install-deps.sh: unknown option $arg" >&2; exit 2 ;;
  esac
done
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# Node and npm for the labelling page's tests (node --test, and playwright-core from npm): Debian's
# packages unless a node with npm is already installed.
if [ $tests = 1 ]; then
  command -v node >/dev/null 2>&1 || missing+=(nodejs)
  command -v npm >/dev/null 2>&1 || missing+=(npm)
fi
root=$(cd "$(dirname "$0")/.." && pwd)
e2e() {  # from npm: the browser test's driver (the browser itself is Debian's chromium), the log fixtures' writers
  [ $tests = 1 ] || return 0
  if [ ! -d "$root/tests/e2e/node_modules/playwright-core" ]; then
    echo "install-deps: npm ci in tests/e2e (playwright-core)"
    (cd "$root/tests/e2e" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
  fi
  # The robot-log tests' fixture writers (other projects' MCAP and ROS 2 serialisation).
  if [ ! -d "$root/tests/bags/node_modules/@mcap/core" ]; then
    echo "install-deps: npm ci in tests/bags (@mcap/core, @foxglove/rosmsg2-serialization)"
    (cd "$root/tests/bags" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
  fi
  # The dataset tests' Parquet writers (arrow-rs compiled to wasm, hyparquet-writer).
  if [ ! -d "$root/tests/datasets/node_modules/parquet-wasm" ]; then
    echo "install-deps: npm ci in tests/datasets (parquet-wasm, apache-arrow, hyparquet-writer)"
    (cd "$root/tests/datasets" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
  fi
}
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  e2e
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
e2e
