#!/usr/bin/python3
"""Every C++ source of a configured build, checked by its compiler with the build's own flags
(warnings and -Werror included) and -fsyntax-only: the compiler's diagnostics without code
generation, in a fraction of a build's time.

    check_warnings.py BUILD_DIR [JOBS]

BUILD_DIR must have been configured with -DCMAKE_EXPORT_COMPILE_COMMANDS=ON. Sources the build
generates (under BUILD_DIR: embedded web assets, ParaView's wrapping) are left out; they exist
only once the build has run. Prints each failing file with the compiler's messages and exits 1
when any fails, 0 when all pass.
"""
import concurrent.futures
import json
import os
import shlex
import subprocess
import sys
from pathlib import Path


def syntax_only(entry):
    """The entry's command line without its output, code generation or link-time options."""
    args = entry["arguments"] if "arguments" in entry else shlex.split(entry["command"])
    out, skip = [], False
    for a in args:
        if skip:
            skip = False
        elif a == "-o":
            skip = True
        elif a == "-c" or a.startswith("-flto") or a == "-fno-fat-lto-objects":
            continue
        else:
            out.append(a)
    return [out[0], "-fsyntax-only", *out[1:]]


def check(entry):
    r = subprocess.run(syntax_only(entry), cwd=entry["directory"], capture_output=True, text=True)
    return entry["file"], r.returncode, r.stdout + r.stderr


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    build = Path(sys.argv[1]).resolve()
    jobs = int(sys.argv[2]) if len(sys.argv) > 2 else (os.cpu_count() or 1)
    commands = build / "compile_commands.json"
    if not commands.is_file():
        sys.exit(f"{commands}: not found; configure with -DCMAKE_EXPORT_COMPILE_COMMANDS=ON")
    entries = [e for e in json.loads(commands.read_text())
               if not Path(e["directory"], e["file"]).resolve().is_relative_to(build)]
    failed = 0
    with concurrent.futures.ThreadPoolExecutor(jobs) as pool:
        for name, rc, messages in pool.map(check, entries):
            if rc != 0:
                failed += 1
                print(f"{name}:\n{messages}", flush=True)
    print(f"{len(entries) - failed} of {len(entries)} sources compile without a diagnostic")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
