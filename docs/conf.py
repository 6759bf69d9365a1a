# The documentation site (scripts/docs.sh builds it into build-docs/html): Markdown pages through
# MyST, the C++ API through Breathe on Doxygen's XML, the Python API by autodoc from the built
# package. scripts/docs.sh copies docs/ into build-docs/src, adds the pages generated from the
# program itself (one per command, from its --help) and runs sphinx-build -W: a warning fails.
import os

project = "KCCD"
author = "KCCD"
copyright = "KCCD"
extensions = ["myst_parser", "breathe", "sphinx.ext.autodoc"]
source_suffix = {".md": "markdown"}
exclude_patterns = ["_build"]
myst_heading_anchors = 4  # links such as formats.md#14-robot-logs-... resolve as on GitHub
myst_enable_extensions = ["colon_fence"]
html_theme = "furo"
html_title = "KCCD"
html_static_path = []
breathe_projects = {"kccd": os.environ.get("KCCD_DOXYGEN_XML", "../doxygen/xml")}
breathe_default_project = "kccd"
breathe_default_members = ("members",)
autodoc_member_order = "bysource"
autodoc_typehints = "none"  # the signatures pybind11 writes already name the types
