#!/usr/bin/env bash
# Installs the Debian packages of build-package/ (scripts/package.sh) on this machine, uses them
# as a user would with only the installed files, then removes them. As root or through sudo;
# it changes the system (CI runs it on its own machine: scripts/test.sh --packages). Checks:
#   /usr/bin/kccd --version is the project's version, and starts without the whole program;
#   the demo's main job (synth, calib from tags, overlay) from /usr/bin/kccd on the installed
#   sample data, its colliding frames equal to the recording's truth;
#   the examples built against the installed libkccd-dev (find_package(kccd ...)) and run;
#   `import kccd` in Debian's python3 with nothing on PYTHONPATH, and a query through it;
#   the shell blocks of the Quickstart and of every guide that needs nothing of the repository,
#   as written, on the installed files (tests/docs/run_guides.py);
#   after removal no kccd file is left.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
debs=("$root"/build-package/*.deb)
[ -e "${debs[0]}" ] || { echo "package_test.sh: no packages in build-package/ (run scripts/package.sh)" >&2; exit 2; }
version=$(sed -n 's/^project(kccd VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)
work=$(mktemp -d)
remove() {
  "${sudo_cmd[@]}" dpkg -r python3-kccd libkccd-dev kccd >/dev/null 2>&1 || true
  rm -rf "$work"
}
trap remove EXIT
step() { printf '== %s\n' "$*"; }
# Only what a user's shell has: no PYTHONPATH, no build tree on PATH, a fresh folder.
clean() { env -i HOME="$work" PATH=/usr/bin:/bin LANG=C.UTF-8 "$@"; }

step "dpkg -i, then apt-get -f install for what they depend on"
"${sudo_cmd[@]}" dpkg -i "${debs[@]}" >/dev/null || "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get -f install -y -qq >/dev/null
dpkg-query -W kccd libkccd-dev python3-kccd

step "kccd --version"
got=$(clean kccd --version)
[ "$got" = "kccd $version" ] || { echo "expected 'kccd $version', got '$got'" >&2; exit 1; }
[ "$(command -v kccd)" = /usr/bin/kccd ] || { echo "kccd is not /usr/bin/kccd" >&2; exit 1; }
# The launcher loads the checker's few libraries only (the whole program is /usr/libexec/kccd/kccd-all).
n=$(ldd /usr/bin/kccd | wc -l)
[ "$n" -le 12 ] || { echo "/usr/bin/kccd loads $n shared libraries (expected 12 at most)" >&2; exit 1; }

step "the main job from /usr/bin/kccd on the installed sample data"
data=/usr/share/kccd/data
cd "$work"
clean kccd synth $data/humanoid.yaml -o rec --seconds 1 --width 640 --height 360 -q
clean kccd calib --intrinsics rec/intrinsics.yaml --video rec/video.mkv --frame 0 --tags rec/tags.yaml \
  --model $data/humanoid.yaml --states rec/states.csv --time 0.137 -o camera.yaml --truth rec/camera_true.yaml
clean kccd overlay $data/humanoid.yaml --camera camera.yaml --video rec/video.mkv --states rec/states.csv \
  --time-offset 0.137 -o overlay.mp4 --report report.json -q
clean python3 - <<'PY'
import json
truth = json.load(open("rec/synth.json"))["collision"]["frames"]
seen = [f["index"] for f in json.load(open("report.json"))["frames"] if f["status"] == "colliding"]
print(f"colliding frames: overlay {seen}, the recording's truth {truth}")
assert seen == truth, "the overlay's colliding frames differ from the truth"
PY

step "the examples built against libkccd-dev"
cp -r /usr/share/doc/libkccd-dev/examples ex
for example in query overlay; do
  clean cmake -S ex/$example -B ex/build-$example -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  clean cmake --build ex/build-$example -j "${KCCD_JOBS:-2}" >/dev/null
done
clean ex/build-query/kccd_example_query $data/demo_arm.yaml
rc=0
mkdir -p ex/out
clean ex/build-overlay/kccd_example_overlay $data/humanoid.yaml camera.yaml rec/video.mkv rec/states.csv 0.137 ex/out || rc=$?
[ $rc -eq 0 ] && [ -s ex/out/overlay.mkv ] && [ -s ex/out/report.json ] || { echo "kccd_example_overlay: exit $rc" >&2; exit 1; }

step "import kccd with Debian's python3, nothing on PYTHONPATH"
clean /usr/bin/python3 - <<PY
import kccd
assert kccd.__version__ == "$version", kccd.__version__
assert kccd.__file__.startswith("/usr/lib/python3/dist-packages/"), kccd.__file__
r = kccd.Checker(kccd.Model.load("$data/demo_arm.yaml")).query([-0.5, 0, 0], [0.5, 0, 0], type="distances")
assert r.collision, "the demo arm's swing must hit the pole"
print("kccd", kccd.__version__, "from", kccd.__file__, "- the swing collides:", r.collision)
PY

step "the Quickstart's and the guides' commands with only the installed files"
cd "$root"
# Every page whose commands need nothing of the repository (not its tests/ folder) runs as written
# with /usr/bin/kccd, the installed sample data and Debian's python3 with nothing on PYTHONPATH.
pages=$(grep -L 'KCCD_DATA/\.\./tests' docs/getting-started.md docs/guides/*.md)
mkdir -p "$work/empty"
clean /usr/bin/python3 tests/docs/run_guides.py /usr/bin/kccd /usr/share/kccd/data "$work/empty" $pages

step "dpkg -r leaves no kccd file"
"${sudo_cmd[@]}" dpkg -r python3-kccd libkccd-dev kccd >/dev/null
left=$(ls -d /usr/bin/kccd /usr/libexec/kccd /usr/include/kccd /usr/lib/*/cmake/kccd /usr/lib/*/libkccd*.a \
  /usr/share/kccd /usr/share/doc/libkccd-dev /usr/share/man/man1/kccd.1.gz /usr/lib/python3/dist-packages/kccd \
  2>/dev/null || true)
[ -z "$left" ] || { echo "left after removal: $left" >&2; exit 1; }
echo "package_test.sh: installed, used and removed"
