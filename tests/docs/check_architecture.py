#!/usr/bin/env python3
"""docs/architecture.md names every public header and every source folder of the tree, so a
newcomer finds where each idea lives: a header by its file name (the map may group siblings as
`golden_{manifest,render}.hpp`), a folder by its path with a trailing slash.

Usage: check_architecture.py ROOT
Exit 0 when nothing is missing; otherwise the missing names, one per line, and exit 1."""

import pathlib
import re
import subprocess
import sys


def named(text: str) -> set[str]:
    """The file names the page mentions, with `a_{b,c}.hpp` expanded to a_b.hpp and a_c.hpp."""
    names = set(re.findall(r"[\w.-]+\.(?:hpp|cpp|h)", text))
    for stem, options, ext in re.findall(r"([\w-]*)\{([\w,]+)\}([\w-]*\.(?:hpp|cpp))", text):
        names |= {stem + o + ext for o in options.split(",")}
    return names


def main() -> int:
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    root = pathlib.Path(sys.argv[1])
    text = (root / "docs" / "architecture.md").read_text(encoding="utf-8")
    files = subprocess.run(["git", "-C", str(root), "ls-files", "*.hpp", "*.cpp", "*.h"], check=True, capture_output=True,
                           text=True).stdout.split()
    if not files:  # not a git checkout: the tree as it is
        files = [str(p.relative_to(root)) for p in root.rglob("*") if p.suffix in (".hpp", ".cpp", ".h")
                 and "build" not in p.parts]
    names = named(text)
    missing = []
    for f in sorted(files):
        p = pathlib.PurePosixPath(f)
        if "/include/" in f and p.suffix == ".hpp" and p.name not in names:
            missing.append(f"header {f}")
    for folder in sorted({str(pathlib.PurePosixPath(f).parent) for f in files}):
        if folder.startswith(("tests/", "third_party/")) or "/include/" in folder + "/" or folder == ".":
            continue
        if folder + "/" not in text:
            missing.append(f"folder {folder}/")
    for m in missing:
        print(f"docs/architecture.md does not name the {m}")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
