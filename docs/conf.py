# The documentation site (scripts/docs.sh builds it into build-docs/html): Markdown pages through
# MyST, the C++ API through Breathe on Doxygen's XML, the Python API by autodoc from the built
# package. scripts/docs.sh copies docs/ into build-docs/src, adds the pages generated from the
# program itself (one per command, from its --help) and runs sphinx-build -W: a warning fails.
import os
import pathlib
import re


def _project_version() -> str:
    """The version in CMakeLists.txt's project(kccd VERSION x.y.z): KCCD_SOURCE_DIR (scripts/docs.sh
    sets it), else the first folder above this file that holds a CMakeLists.txt naming the project."""
    here = pathlib.Path(__file__).resolve().parent
    folders = [pathlib.Path(os.environ["KCCD_SOURCE_DIR"])] if os.environ.get("KCCD_SOURCE_DIR") else []
    for folder in folders + [here, *here.parents]:
        lists = folder / "CMakeLists.txt"
        if lists.is_file():
            m = re.search(r"project\(\s*kccd\s+VERSION\s+([0-9][0-9.]*)", lists.read_text(encoding="utf-8"))
            if m:
                return m.group(1)
    raise RuntimeError("docs/conf.py: no CMakeLists.txt with project(kccd VERSION ...) found (set KCCD_SOURCE_DIR)")


project = "KCCD"
author = "KCCD"
copyright = "KCCD"
release = version = _project_version()
extensions = ["myst_parser", "breathe", "sphinx.ext.autodoc"]
source_suffix = {".md": "markdown"}
exclude_patterns = ["_build"]
myst_heading_anchors = 4  # links such as formats.md#14-robot-logs-... resolve as on GitHub
myst_enable_extensions = ["colon_fence", "substitution"]
myst_substitutions = {"version": release}  # {{ version }} in a page
html_theme = "furo"
html_title = f"KCCD {release}"  # the sidebar's and the mobile header's name: the version is always in view
html_static_path = ["_static"]
html_css_files = ["kccd.css"]
html_js_files = ["copybutton.js"]  # a Copy button on every code block (_static/copybutton.js)
# One Doxygen project per public header (scripts/docs_cpp.py writes them into KCCD_DOXYGEN_DIR).
_doxygen = pathlib.Path(os.environ.get("KCCD_DOXYGEN_DIR", "../doxygen"))
breathe_projects = {p.parent.name: str(p) for p in sorted(_doxygen.glob("*/xml"))}
breathe_default_project = next(iter(breathe_projects), "kccd")
breathe_default_members = ("members",)
autodoc_member_order = "bysource"
autodoc_typehints = "none"  # the signatures pybind11 writes already name the types


def _public_name(text):
    """pybind11 writes the compiled module's name into signatures and docstrings
    (kccd._kccd.Model); the package exports every one of them as kccd.Model."""
    return text.replace("kccd._kccd.", "kccd.") if text else text


def _public_signature(app, what, name, obj, options, signature, return_annotation):
    return _public_name(signature), _public_name(return_annotation)


def _public_docstring(app, what, name, obj, options, lines):
    lines[:] = [_public_name(line) for line in lines]


def setup(app):
    app.connect("autodoc-process-signature", _public_signature)
    app.connect("autodoc-process-docstring", _public_docstring)
