#!/usr/bin/env python3
"""Runs one reproduce executable for `make reproduce` and records how it ended, so that one
failure does not stop the others (issue #35).

Usage: run_one.py OUT_DIR EXECUTABLE [ARGS...]

The executable runs as `EXECUTABLE --out OUT_DIR ARGS...` with its output passed through. Its
outcome goes to OUT_DIR/.runs/<name>.json: {"executable", "exit_code" (negative: the signal),
"seconds", "message"}, the message being the run's "FAILED" lines (reproduce::Run::finish), or
else the last lines of its error output. report.py reads these files: it lists every failure in
REPORT.md's "Failed" section and then exits non-zero. This script itself exits 0 unless it
cannot run or record, so that make goes on to the next executable.
"""
import json
import os
import subprocess
import sys
import time
from pathlib import Path


def main():
    if len(sys.argv) < 3:
        sys.exit("usage: run_one.py OUT_DIR EXECUTABLE [ARGS...]")
    out, exe = Path(sys.argv[1]), sys.argv[2]
    name = Path(exe).name
    runs = out / ".runs"
    runs.mkdir(parents=True, exist_ok=True)
    start = time.monotonic()
    proc = subprocess.Popen([exe, "--out", str(out), *sys.argv[3:]], stderr=subprocess.PIPE, text=True,
                            errors="replace")
    errors = []
    for line in proc.stderr:  # passed through as it comes, kept for the message
        sys.stderr.write(line)
        errors.append(line.rstrip("\n"))
    code = proc.wait()
    seconds = time.monotonic() - start
    failed = [line for line in errors if "FAILED" in line]
    if code == 0:
        message = ""
    elif failed:
        message = " | ".join(failed)
    else:
        tail = " | ".join(errors[-5:]) if errors else "no error output"
        message = (f"killed by signal {-code}" if code < 0 else f"exit code {code}") + ": " + tail
    record = {"executable": name, "exit_code": code, "seconds": round(seconds, 3), "message": message}
    tmp = runs / f".{name}.json.tmp"
    tmp.write_text(json.dumps(record, indent=2) + "\n")
    os.replace(tmp, runs / f"{name}.json")
    if code != 0:
        print(f"run_one.py: {name} FAILED after {seconds:.1f} s ({message}); the other runs go on", file=sys.stderr)


if __name__ == "__main__":
    main()
