#!/usr/bin/env bash
# Builds the documentation site into build-docs/html (open build-docs/html/index.html): the pages
# of docs/ (Markdown, through Sphinx and MyST), a page per command generated from the command's
# own --help (so it cannot drift), the C++ API from the headers (Doxygen XML, Breathe) and the
# Python API from the built package (autodoc). Warnings are errors. Installs what it needs
# (scripts/install-deps.sh --docs) and builds the command and the Python package first.
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
# The C++ API: Doxygen's XML of the public headers.
headers=$(ls -d libkccd/include logs/include calib/include render/include overlay/include 2>/dev/null | tr '\n' ' ')
cat > "$out/doxygen/Doxyfile" <<DOXY
PROJECT_NAME = KCCD
INPUT = $headers
RECURSIVE = YES
FILE_PATTERNS = *.hpp
EXCLUDE_SYMBOLS = detail::* *::detail::*
GENERATE_XML = YES
GENERATE_HTML = NO
GENERATE_LATEX = NO
XML_OUTPUT = $PWD/$out/doxygen/xml
QUIET = YES
WARNINGS = NO
WARN_IF_UNDOCUMENTED = NO
EXTRACT_ALL = YES
MAX_INITIALIZER_LINES = 0
ENABLE_PREPROCESSING = YES
MACRO_EXPANSION = YES
DOXY
doxygen "$out/doxygen/Doxyfile"
# The command reference: every command's and subcommand's --help, verbatim.
python3 scripts/docs_cli.py "$build/overlay/kccd" "$out/src/reference"
export KCCD_DOXYGEN_XML="$PWD/$out/doxygen/xml"
PYTHONPATH="$PWD/$build/python" /usr/bin/python3 -m sphinx -W --keep-going -q -b html "$out/src" "$out/html"
echo "docs: $out/html/index.html"
