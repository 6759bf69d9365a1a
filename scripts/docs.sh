#!/usr/bin/env bash
# Builds the documentation site into build-docs/html (open build-docs/html/index.html): the pages
# of docs/ (Markdown, through Sphinx and MyST), a page per command generated from the command's
# own --help (so it cannot drift), the C++ API from the headers (Doxygen XML, Breathe; a page per
# group of headers, scripts/docs_cpp.py) and the Python API from the built package (autodoc).
# Warnings are errors. Installs what it needs (scripts/install-deps.sh --docs) and builds the
# command and the Python package first.
# Usage: scripts/docs.sh [BUILD_DIR (default build)]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
out=build-docs
bash scripts/install-deps.sh --docs
if [ ! -x "$build/overlay/kccd" ] || [ ! -d "$build/python/kccd" ]; then
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
cmake --build "$build" -j "${KCCD_JOBS:-2}" --target kccd_cli kccd_python kccd_python_files
rm -rf "$out/src" "$out/html" "$out/doxygen"
mkdir -p "$out/src" "$out/doxygen"
cp -r docs/. "$out/src/"
# The command reference: every command's and subcommand's --help, verbatim.
python3 scripts/docs_cli.py "$build/overlay/kccd" "$out/src/reference"
# The C++ API: a page per group of public headers, found in the tree, each header Doxygen's XML
# of its own (scripts/docs_cpp.py).
python3 scripts/docs_cpp.py . "$out/src/reference" "$PWD/$out/doxygen"
export KCCD_DOXYGEN_DIR="$PWD/$out/doxygen"
export KCCD_SOURCE_DIR="$PWD"  # conf.py reads the version from CMakeLists.txt here
PYTHONPATH="$PWD/$build/python" /usr/bin/python3 -m sphinx -W --keep-going -q -b html "$out/src" "$out/html"
echo "docs: $out/html/index.html"
