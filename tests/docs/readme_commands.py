"""Runs the README's command lines as a newcomer would copy them (issue #40, item 9).

Usage: readme_commands.py SOURCE_DIR BUILD_DIR. Every line of every ```sh block of README.md runs
with /bin/sh from SOURCE_DIR and must exit 0, except the `make ...` lines (they are CI's own
steps, and make test cannot run make reproduce inside itself). `build/` is replaced by BUILD_DIR
and `/tmp/` by a fresh temporary folder, removed at the end, so that nothing is written into the
source tree or shared folders. Prints each command and its exit status; exit 1 if any failed.
"""
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path


def commands(readme):
    """The command lines of the ```sh blocks: comments stripped, continuation lines skipped."""
    lines, inside = [], False
    for line in readme.splitlines():
        if line.startswith("```"):
            inside = line.strip() == "```sh" if not inside else False
            continue
        if inside:
            command = re.sub(r"\s+#.*$", "", line).strip()
            if command and not command.startswith("#"):
                lines.append(command)
    return lines


def main(argv):
    source, build = Path(argv[1]).resolve(), Path(argv[2]).resolve()
    scratch = Path(tempfile.mkdtemp(prefix="wbm_readme_"))
    failed = 0
    try:
        found = commands((source / "README.md").read_text())
        assert found, "README.md has no ```sh block"
        for command in found:
            if command.startswith("make "):
                print(f"skipped (a CI step): {command}")
                continue
            # /tmp/ first: a build folder under /tmp/ must not be moved into the scratch folder.
            run = re.sub(r"(?<![\w/])build/", f"{build}/", command.replace("/tmp/", f"{scratch}/"))
            r = subprocess.run(run, shell=True, cwd=source, capture_output=True, text=True, timeout=600)
            print(f"exit {r.returncode}: {command}")
            if r.returncode != 0:
                failed += 1
                print(r.stdout[-2000:], r.stderr[-2000:], sep="\n")
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
