#!/usr/bin/env python3
"""Runs the shell blocks of the documentation's guides, so they cannot drift from the program:
every fenced block whose language is `sh` in a page, in order, with `bash -e`, in a fresh empty
folder, with the built `kccd` first on PATH and `python3` the interpreter running this script, KCCD_DATA the sample data folder (also linked as `data/` in
the folder, as in the repository) and the built Python package on PYTHONPATH. Other blocks (```console, ```text, ```bash, ...) are shown, not run.

Usage: run_guides.py KCCD_BINARY DATA_DIR PYTHONPATH PAGE.md [PAGE.md ...]
Exit 0 when every block of every page ran with status 0; otherwise the failing page, block (its
line in the page) and the output, and exit 1."""

import os
import re
import subprocess
import sys
import tempfile
import time


def blocks(page: str) -> list[tuple[int, str]]:
    """(line, text) of each ```sh block of a Markdown page."""
    out: list[tuple[int, str]] = []
    lines = open(page, encoding="utf-8").read().splitlines()
    i = 0
    while i < len(lines):
        m = re.match(r"^(\s*)(`{3,})sh\s*$", lines[i])
        if m:
            fence, start, body = m.group(2), i + 1, []
            i += 1
            while i < len(lines) and not lines[i].strip().startswith(fence):
                body.append(lines[i][len(m.group(1)):] if lines[i].startswith(m.group(1)) else lines[i])
                i += 1
            out.append((start, "\n".join(body) + "\n"))
        i += 1
    return out


def main() -> int:
    if len(sys.argv) < 5:
        print(__doc__, file=sys.stderr)
        return 2
    kccd, data, pythonpath, pages = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
    env = dict(os.environ)
    # `python3` in a block is this interpreter (the one the package was built for), whatever else
    # comes first on PATH.
    shim = tempfile.mkdtemp(prefix="kccd_guide_bin_")
    os.symlink(sys.executable, os.path.join(shim, "python3"))
    env["PATH"] = os.pathsep.join([os.path.dirname(os.path.abspath(kccd)), shim, env.get("PATH", "")])
    env["KCCD_DATA"] = os.path.abspath(data)
    env["PYTHONPATH"] = os.path.abspath(pythonpath)
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    failed = 0
    for page in pages:
        found = blocks(page)
        if not found:
            print(f"{page}: no ```sh block: a guide shows at least one command run on sample data")
            failed += 1
            continue
        t0 = time.monotonic()
        with tempfile.TemporaryDirectory(prefix="kccd_guide_") as work:
            # `data/` as in the repository, where a reader runs the commands from.
            os.symlink(env["KCCD_DATA"], os.path.join(work, "data"))
            for line, text in found:
                run = subprocess.run(["bash", "-e", "-c", text], cwd=work, env=env, capture_output=True, text=True)
                if run.returncode != 0:
                    print(f"{page}:{line}: the block exits {run.returncode}:\n{text}--- output:\n{run.stdout}{run.stderr}")
                    failed += 1
                    break
        print(f"{page}: {len(found)} block(s) in {time.monotonic() - t0:.1f} s")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
