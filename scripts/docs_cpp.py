#!/usr/bin/env python3
"""Writes the C++ API pages of the documentation site: reference/cpp/<group>.md, one page per group
of public headers (the collision core, inputs, modelling, calibration, rendering, robot logs and
the overlay's subsystems), each header under its own heading, and reference/cpp-api.md's list of
them. Each header is its own Doxygen project (DOXYGEN_DIR/<project>/xml, one Doxygen run per
header, a fraction of a second each), shown by Breathe's doxygennamespace: so every entity is
declared once, on its header's page, whatever namespaces the headers share. conf.py registers
every project it finds in DOXYGEN_DIR. The headers are found in the tree, so a new header appears
on its folder's page without an edit here; a header no group claims goes to a page of its own and
is named on standard error.

Usage: docs_cpp.py SOURCE_DIR OUT_DIR DOXYGEN_DIR (OUT_DIR: the site's reference/ folder)"""

import fnmatch
import os
import pathlib
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

# (page, title, what the page holds, find_package component and target, header patterns under
# the include roots). The first group whose pattern matches a header takes it.
GROUPS = [
    ("core", "The collision core: models and queries",
     "The model, the checker and its queries, braking intervals, explanations of flagged pairs, and "
     "the geometry under them: what goes on a robot controller.",
     "always there: `kccd::kccd`",
     ["kccd/model.hpp", "kccd/checker.hpp", "kccd/query.hpp", "kccd/braking.hpp", "kccd/safety_status.hpp",
      "kccd/explain.hpp", "kccd/types.hpp", "kccd/ssch.hpp", "kccd/distance.hpp", "kccd/kinematics.hpp",
      "kccd/rotation.hpp"]),
    ("inputs", "Inputs: state logs, errors and readers",
     "Joint logs and the state at a time, and the input foundation every reader shares: errors that "
     "name the file and place, the bounded file and YAML readers, the number formatter.",
     "always there: `kccd::kccd`",
     ["kccd/*.hpp"]),
    ("modelling", "Modelling: parts, fits, URDF import and pair proofs",
     "Reading CAD parts and meshes, fitting SSCHs to a part or to a tolerance, convex pieces, URDF "
     "import, pair proofs and surveys, in-place model edits; and the hull geometry they share.",
     "`find_package(kccd COMPONENTS modelling)`: `kccd::modelling` (with `kccd::hull`)",
     ["kccd/modelling/*.hpp", "kccd/hull/*.hpp"]),
    ("calib", "Calibration: cameras, tags and poses",
     "The camera model and its file, tag layouts, labels, AprilTag detection, intrinsics from a board, "
     "the pose solve, and the refinements to masks, edges and a recording's background. No GL.",
     "`find_package(kccd COMPONENTS calib)`: `kccd::calib`",
     ["kccd/calib/*.hpp"]),
    ("render", "Rendering",
     "Off-screen rendering of the volumes through a calibrated camera (EGL or OSMesa): GL contexts, "
     "projections, meshes and outlines, the renderer, a model's visuals and the model as a camera sees it.",
     "`find_package(kccd COMPONENTS render)`: `kccd::render`",
     ["kccd/render/*.hpp"]),
    ("logs", "Robot logs and datasets: readers",
     "MCAP, rosbag2 sqlite3 and ROS 1 readers, ROS message definitions and decoding, Parquet and "
     "LeRobot datasets. No GL, no OpenCV.",
     "`find_package(kccd COMPONENTS logs)`: `kccd::logs`",
     ["kccd/logs/*.hpp"]),
    ("overlay-recording", "The overlay: recordings, jobs and outputs",
     "The main job as library calls: recordings in (videos, frame times, the time offset), the "
     "per-frame annotator, overlayRecording and its report, the overlay and check jobs, contact "
     "sheets, timelines and staged outputs.",
     "`find_package(kccd COMPONENTS overlay)`: `kccd::overlay`",
     ["kccd/overlay/recording/*.hpp", "kccd/overlay/jobs/*.hpp", "kccd/overlay/common/*.hpp"]),
    ("overlay-calibration", "The overlay: calibration and labelling",
     "What `kccd calib`, `kccd calib sheet` and `kccd calib label` do, as calls: gathering "
     "correspondences from pictures and recordings, the solve, refinements, the check image, the "
     "report, labelling candidates and the labelling page's session and server.",
     "`find_package(kccd COMPONENTS overlay)`: `kccd::overlay`",
     ["kccd/overlay/calibration/*.hpp", "kccd/overlay/labelling/*.hpp"]),
    ("overlay-logs", "The overlay: robot logs and datasets as recordings",
     "`kccd bag info` and `bag export`, a robot log or a LeRobot episode read as a recording, and the "
     "joint map.",
     "`find_package(kccd COMPONENTS overlay)`: `kccd::overlay`",
     ["kccd/overlay/bags/*.hpp", "kccd/overlay/datasets/*.hpp"]),
    ("overlay-golden-synth", "The overlay: golden images and synthetic recordings",
     "`kccd golden` (manifests, rendering, comparison, reports) and `kccd synth` (trajectory, scene, "
     "sensor, truth) as calls.",
     "`find_package(kccd COMPONENTS overlay)`: `kccd::overlay`",
     ["kccd/overlay/golden/*.hpp", "kccd/overlay/synth/*.hpp"]),
]
OTHER = ("other", "Other headers", "Public headers no other page claims yet.", "", ["*"])
ROOTS = ["libkccd/include", "libkccd/hull/include", "libkccd/modelling/include", "logs/include", "calib/include",
         "render/include", "overlay/include"]


def headers(source: pathlib.Path) -> dict[str, pathlib.Path]:
    """Every public header as it is included (kccd/...) and its file."""
    found = {}
    for root in ROOTS:
        base = source / root
        for p in base.rglob("*.hpp") if base.is_dir() else []:
            found[str(p.relative_to(base))] = p.resolve()
    return dict(sorted(found.items()))


DOXYFILE = """PROJECT_NAME = KCCD
INPUT = {input}
FILE_PATTERNS = *.hpp
EXCLUDE_SYMBOLS = detail::* *::detail::*
GENERATE_XML = YES
GENERATE_HTML = NO
GENERATE_LATEX = NO
XML_OUTPUT = {xml}
QUIET = YES
WARNINGS = NO
WARN_LOGFILE = {log}
EXTRACT_ALL = YES
MAX_INITIALIZER_LINES = 0
ENABLE_PREPROCESSING = YES
MACRO_EXPANSION = YES
FULL_PATH_NAMES = YES
STRIP_FROM_PATH = {root}
STRIP_FROM_INC_PATH = {root}
"""


def project_name(header: str) -> str:
    return re.sub(r"[^A-Za-z0-9]+", "_", header.removesuffix(".hpp"))


def namespaces(xml: pathlib.Path) -> list[str]:
    """The kccd namespaces that hold something of this project (members or classes), outer first."""
    out = []
    for compound in ET.parse(xml / "index.xml").getroot().findall("compound[@kind='namespace']"):
        name = compound.findtext("name")
        if not name.startswith("kccd") or "detail" in name.split("::"):
            continue
        root = ET.parse(xml / (compound.get("refid") + ".xml")).getroot()
        if root.find(".//innerclass") is not None or root.find(".//memberdef") is not None:
            out.append(name)
    return sorted(out, key=lambda n: (n.count("::"), n))


def doxygen(header: str, path: pathlib.Path, doxygen_dir: pathlib.Path) -> pathlib.Path:
    """Runs Doxygen on one header; returns its XML folder."""
    folder = doxygen_dir / project_name(header)
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    root = str(path)[: -len(header)]  # the include root: #include <kccd/...> as a program writes it
    (folder / "Doxyfile").write_text(DOXYFILE.format(input=path, xml=folder / "xml", log=folder / "warnings.txt",
                                                     root=root))
    subprocess.run(["doxygen", str(folder / "Doxyfile")], check=True, stdout=subprocess.DEVNULL)
    return folder / "xml"


def main() -> int:
    if len(sys.argv) != 4:
        print(__doc__, file=sys.stderr)
        return 2
    source, out, doxygen_dir = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2]), pathlib.Path(sys.argv[3])
    found = headers(source)
    pages: dict[str, list[str]] = {}
    for h in found:
        for group in GROUPS + [OTHER]:
            if any(fnmatch.fnmatchcase(h, p) and (p != "kccd/*.hpp" or h.count("/") == 1) for p in group[4]):
                pages.setdefault(group[0], []).append(h)
                break
    if pages.get("other"):
        print("docs_cpp: headers on the 'Other headers' page: " + ", ".join(pages["other"]), file=sys.stderr)
    os.makedirs(out / "cpp", exist_ok=True)
    listed = []
    for name, title, what, component, _ in GROUPS + [OTHER]:
        if not pages.get(name):
            continue
        text = f"# {title}\n\n{what}\n\n"
        if component:
            text += f"Link: {component}.\n\n"
        text += "Headers on this page: " + ", ".join(f"`{h}`" for h in pages[name]) + ".\n\n"
        for h in pages[name]:
            xml = doxygen(h, found[h], doxygen_dir)
            text += f"## `{h}`\n\n"
            spaces = namespaces(xml)
            for ns in spaces:
                if len(spaces) > 1:
                    text += f"### `{ns}`\n\n"
                text += (f"```{{doxygennamespace}} {ns}\n:project: {project_name(h)}\n:content-only:\n"
                         ":members:\n```\n\n")
            if not spaces:
                text += "Nothing but macros or forward declarations.\n\n"
        (out / "cpp" / f"{name}.md").write_text(text, encoding="utf-8")
        listed.append((name, title, len(pages[name])))
    with open(out / "cpp-api.md", "a", encoding="utf-8") as f:
        f.write("\n## The pages\n\n" + "".join(f"- [{title}](cpp/{name}.md): {n} headers\n" for name, title, n in listed))
        f.write("\n```{toctree}\n:hidden:\n\n" + "\n".join(f"cpp/{name}" for name, _, _ in listed) + "\n```\n")
    print(f"docs_cpp: {sum(n for *_, n in listed)} headers on {len(listed)} pages")
    return 0


if __name__ == "__main__":
    sys.exit(main())
