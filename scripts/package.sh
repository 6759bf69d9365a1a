#!/usr/bin/env bash
# Builds the Debian packages (cmake/packaging.cmake) into build-package/:
#   kccd_<version>_amd64.deb          the command (/usr/bin/kccd) and the sample data (/usr/share/kccd/data)
#   libkccd-dev_<version>_amd64.deb   the C++ libraries, headers, find_package(kccd) and the examples
#   python3-kccd_<version>_amd64.deb  `import kccd` for Debian's python3
# Install them with `sudo apt install ./build-package/*.deb`. The build directory (default build)
# is configured for the prefix /usr while the packages are made, then given back its own prefix;
# what is already built there is reused. Needs dpkg-shlibdeps (dpkg-dev); counts lintian's
# findings when lintian is installed.
# Usage: scripts/package.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
out=build-package
bash scripts/install-deps.sh --package
cache() {  # the build directory's cached value of $1 (empty when unset)
  [ -f "$build/CMakeCache.txt" ] && sed -n "s/^$1:[A-Z]*=//p" "$build/CMakeCache.txt" || true
}
prefix=$(cache CMAKE_INSTALL_PREFIX)
python_dir=$(cache KCCD_PYTHON_INSTALL_DIR)
restore() {  # the build directory's own install prefix and Python directory
  [ -f "$build/CMakeCache.txt" ] || return 0
  local args=(-DCMAKE_INSTALL_PREFIX="${prefix:-/usr/local}")
  if [ -n "$python_dir" ]; then args+=(-DKCCD_PYTHON_INSTALL_DIR="$python_dir"); else args+=(-UKCCD_PYTHON_INSTALL_DIR); fi
  cmake -S . -B "$build" "${args[@]}" >/dev/null
}
trap restore EXIT
extra=()
[ -f "$build/CMakeCache.txt" ] || extra=(-G Ninja -DCMAKE_BUILD_TYPE=Release -DKCCD_BUILD_TESTS=OFF -DKCCD_BUILD_BENCHMARKS=OFF)
# Debian's python3 looks in /usr/lib/python3/dist-packages.
cmake -S . -B "$build" "${extra[@]}" -DCMAKE_INSTALL_PREFIX=/usr -DKCCD_PYTHON_INSTALL_DIR=lib/python3/dist-packages >/dev/null
if [ "$(cache CMAKE_BUILD_TYPE)" != Release ]; then
  echo "package.sh: $build is a $(cache CMAKE_BUILD_TYPE) build; packages are made from a Release build" >&2
  exit 2
fi
cmake --build "$build" -j "${KCCD_JOBS:-2}" --target kccd_cli kccd_python kccd_python_files \
  kccd kccd_hull kccd_modelling kccd_calib kccd_logs kccd_render kccd_overlay
help2man --no-info --version-string="$("$build/overlay/kccd" --version | cut -d' ' -f2)" \
  --name="strictly conservative continuous collision detection for robots" "$build/overlay/kccd" |
  gzip -9n >"$build/debian/kccd.1.gz"
rm -rf "$build/packages"
(cd "$build" && cpack -G DEB >/dev/null)
rm -rf "$out"
mkdir -p "$out"
mv "$build"/packages/*.deb "$out/"
for deb in "$out"/*.deb; do
  printf '%s  %s\n' "$(du -h "$deb" | cut -f1)" "$deb"
  dpkg-deb -f "$deb" Depends | fold -s -w 100 | sed 's/^/    Depends: /'
done
if command -v lintian >/dev/null; then
  lintian --tag-display-limit 0 "$out"/*.deb >"$out/lintian.txt" 2>&1 || true
  echo "lintian: $(grep -c '^E:' "$out/lintian.txt" || true) errors, $(grep -c '^W:' "$out/lintian.txt" || true) warnings ($out/lintian.txt)"
fi
