#!/usr/bin/env python3
"""The include graph of src/ by folder, checked against the layers of
docs/development.md: a folder may include its own headers and those of the
layers below it, never one above. Prints the graph (folder -> folders it
includes, with counts) and every upward edge with its file and line; exits
1 if there is one.

    python3 scripts/include_layers.py [SRC_DIR]
"""
import pathlib
import re
import sys

# Lowest first. cl/ (the kernels' shared headers) sits below them all.
LAYERS = [["core"], ["compute"], ["sim", "grind", "life"], ["io"], ["viewer"], ["app"]]
LEVEL = {folder: k for k, group in enumerate(LAYERS) for folder in group}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def main() -> int:
    src = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parent.parent / "src")
    edges = {}
    upward = []
    for path in sorted(src.rglob("*")):
        if path.suffix not in (".h", ".hpp", ".cpp") or not path.is_file():
            continue
        folder = path.relative_to(src).parts[0]
        if folder not in LEVEL:
            upward.append(f"{path}: folder {folder} is in no layer (add it to scripts/include_layers.py and docs)")
            continue
        for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            m = INCLUDE.match(line)
            if not m:
                continue
            target = m.group(1)
            head = target.split("/")[0]
            if head not in LEVEL:  # cl/ headers, generated headers, same-folder names
                continue
            edges[(folder, head)] = edges.get((folder, head), 0) + 1
            if LEVEL[head] > LEVEL[folder] or (LEVEL[head] == LEVEL[folder] and head != folder):
                upward.append(f"{path}:{n}: {folder} includes {target} ({head} is not below {folder})")
    for group in LAYERS:
        for folder in group:
            outs = sorted(((h, c) for (f, h), c in edges.items() if f == folder and h != folder),
                          key=lambda x: LEVEL[x[0]])
            print(f"{folder:8s} -> " + (", ".join(f"{h} ({c})" for h, c in outs) or "(nothing outside itself)"))
    if upward:
        print(f"{len(upward)} upward include(s):")
        for u in upward:
            print("  " + u)
        return 1
    print("no upward include")
    return 0


if __name__ == "__main__":
    sys.exit(main())
