#!/usr/bin/env python3
"""The library's layers point only down: every `#include "exabricks/LAYER/..."` in a layer's
public headers (include/exabricks/LAYER) and sources (src/LAYER) names that layer or one below
it, and no source reaches another folder by a relative path. The build enforces this for what it
compiles (each layer sees only the include folders of the layers it links); this also covers
headers that only upper layers include. Prints the graph it found.

    check_layers.py [ROOT] [--compiler CXX --layers BUILD/layers]

With a compiler and the build's layer include folders, it also compiles, for every layer, one
public header of each other layer against that layer's include folders (its own and those below
it, as the build gives them): a header from below must compile, one from above must not be found.
"""
import argparse
import re
import subprocess
import sys
import tempfile
from pathlib import Path

BELOW = {
    "core": set(),
    "amr": {"core"},
    "accel": {"core", "amr"},
    "render": {"core", "amr", "accel"},
    "io": {"core", "amr"},
    "documents": {"core", "amr", "accel", "render", "io"},
    "workflows": {"core", "amr", "accel", "render", "io", "documents"},
}
INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"', re.M)


def compile_check(root, compiler, layers, problems):
    """Includes across layers through the build's include folders, as the build compiles them."""
    for layer, below in BELOW.items():
        dirs = [f"-I{layers}/{l}" for l in sorted(below | {layer})]
        for other in BELOW:
            if other == layer:
                continue
            header = sorted((root / "include/exabricks" / other).glob("*.h"))[0].name
            with tempfile.NamedTemporaryFile("w", suffix=".cpp") as f:
                f.write(f'#include "exabricks/{other}/{header}"\n')
                f.flush()
                r = subprocess.run([compiler, "-std=c++20", "-fsyntax-only", *dirs, f.name], capture_output=True,
                                   text=True)
            if other in below and r.returncode != 0:
                problems.append(f"{layer} cannot include exabricks/{other}/{header} from below:\n{r.stderr[:800]}")
            if other not in below and (r.returncode == 0 or "No such file" not in r.stderr
                                       and "file not found" not in r.stderr):
                problems.append(f"{layer} can include exabricks/{other}/{header} from above (exit {r.returncode})")
        print(f"{layer:9}: compiles what is below, cannot find what is above")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("root", nargs="?", default=str(Path(__file__).resolve().parent.parent))
    ap.add_argument("--compiler")
    ap.add_argument("--layers")
    a = ap.parse_args()
    root = Path(a.root)
    problems, graph = [], {}
    for layer, allowed in BELOW.items():
        files = sorted((root / "include/exabricks" / layer).glob("*.h")) + sorted(p for p in (root / "src" / layer).rglob("*") if p.is_file())
        if not files:
            problems.append(f"layer {layer}: no files under include/exabricks/{layer} or src/{layer}")
        for f in files:
            for name in INCLUDE.findall(f.read_text(errors="replace")):
                rel = f.relative_to(root)
                if name.startswith("../") or "/../" in name:
                    problems.append(f"{rel}: #include \"{name}\" reaches another folder by a relative path")
                    continue
                m = re.match(r"exabricks/([a-z_]+)/", name)
                if not m:
                    continue
                target = m.group(1)
                if target == layer:
                    continue
                graph.setdefault(layer, {}).setdefault(target, 0)
                graph[layer][target] += 1
                if target not in allowed:
                    problems.append(f"{rel}: #include \"{name}\": {layer} may include only "
                                    f"{', '.join(sorted(allowed | {layer}))}")
    for layer in BELOW:
        edges = graph.get(layer, {})
        print(f"{layer:9} -> " + (", ".join(f"{t} ({n})" for t, n in sorted(edges.items())) or "nothing"))
    if a.compiler and a.layers:
        compile_check(root, a.compiler, a.layers, problems)
    for p in problems:
        print("error:", p, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
