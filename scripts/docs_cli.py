#!/usr/bin/env python3
"""Writes the command reference of the documentation site: reference/cli.md (a table of the
commands) and reference/cli/<command>.md per command and subcommand, each the command's own
--help verbatim, so the reference cannot drift from the program.

Usage: docs_cli.py KCCD_BINARY OUT_DIR"""

import os
import re
import subprocess
import sys
import textwrap


def help_of(kccd: str, words: list[str]) -> str:
    run = subprocess.run([kccd, *words, "--help"], capture_output=True, text=True, check=True)
    # The binary's path as the user types it.
    return run.stdout.replace(kccd, "kccd")


def wrapped(text: str, width: int = 82) -> str:
    """The help text with long lines wrapped, each continuation under its description's column
    (the words are the program's own, only the line breaks differ)."""
    out: list[str] = []
    for line in text.splitlines():
        if len(line) <= width:
            out.append(line)
            continue
        m = re.match(r"^(\s*\S.*?\s{2,})(\S.*)$", line)
        column = len(m.group(1)) if m and len(m.group(1)) < width // 2 else len(line) - len(line.lstrip())
        head, rest = line[:column], line[column:]
        out.extend(textwrap.wrap(rest, width=width, initial_indent=head, subsequent_indent=" " * column,
                                 break_long_words=False, break_on_hyphens=False) or [line])
    return "\n".join(out)


def subcommands(text: str) -> list[tuple[str, str]]:
    """(name, summary) of the 'Subcommands:' block of a --help text."""
    out: list[tuple[str, str]] = []
    block = text.split("Subcommands:", 1)
    if len(block) < 2:
        return out
    for line in block[1].splitlines():
        m = re.match(r"^  ([a-z][a-z0-9-]*)\s+(.*)$", line)
        if m:
            out.append((m.group(1), m.group(2).strip()))
        elif line.strip() and not line.startswith("  "):
            break
    return out


def main() -> int:
    kccd, out = sys.argv[1], sys.argv[2]
    os.makedirs(os.path.join(out, "cli"), exist_ok=True)
    pages: list[tuple[str, str]] = []

    def write(words: list[str], summary: str) -> None:
        text = help_of(kccd, words)
        name = "-".join(words)
        title = "kccd " + " ".join(words)
        with open(os.path.join(out, "cli", name + ".md"), "w", encoding="utf-8") as f:
            f.write(f"# `{title}`\n\n{summary}\n\n```text\n{wrapped(text.rstrip())}\n```\n")
        pages.append((name, title))
        for sub, sub_summary in subcommands(text):
            write(words + [sub], sub_summary)

    for command, summary in subcommands(help_of(kccd, [])):
        write([command], summary)
    with open(os.path.join(out, "cli.md"), "w", encoding="utf-8") as f:
        f.write("# Command reference\n\nEvery page is the command's own `--help`, as this build prints it.\n\n")
        f.write("```{toctree}\n:maxdepth: 1\n\n" + "\n".join(f"cli/{name}" for name, _ in pages) + "\n```\n")
    print(f"docs_cli: {len(pages)} command pages")
    return 0


if __name__ == "__main__":
    sys.exit(main())
