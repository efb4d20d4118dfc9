#!/usr/bin/env python3
"""Checks the source tree's layout, as the product card and lib/CMakeLists.txt state it.

  - every #include "visproxy/..." in lib/, apps/ and tests/ names a real file under lib/;
  - every folder of lib/visproxy depends (through its files' includes) only on folders
    that lib/CMakeLists.txt lists before it: the order is its "Layers:" comment, one
    folder per line ("  render/world  ..."), lowest first; a folder and its subfolder are
    two folders;
  - no file in lib/ is longer than 1000 lines.
Prints one line per problem and exits 1 if there is any.
usage: check_layout.py SOURCE_DIR
"""
import os
import re
import sys

root = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
lib = os.path.join(root, "lib")
problems = []

# The layers, from the comment at the top of lib/CMakeLists.txt.
layers = []
in_layers = False
for line in open(os.path.join(lib, "CMakeLists.txt"), encoding="utf-8"):
    if line.startswith("# Layers"):
        in_layers = True
        continue
    if in_layers:
        m = re.match(r"#   ([a-z_/]+)\s", line)
        if m:
            layers.append(m.group(1))
        elif not line.startswith("#     "):
            break
rank = {folder: i for i, folder in enumerate(layers)}
if not layers:
    problems.append("lib/CMakeLists.txt: no '# Layers' comment listing the folders, lowest first")

include = re.compile(r'#include\s+[<"](visproxy/[^">]+)[">]')
edges = {}
for top in ("lib", "apps", "tests"):
    for dirpath, _, files in os.walk(os.path.join(root, top)):
        for name in files:
            if not name.endswith((".h", ".cpp")):
                continue
            path = os.path.join(dirpath, name)
            rel = os.path.relpath(path, root)
            lines = open(path, encoding="utf-8").read().split("\n")
            if top == "lib" and len(lines) > 1001:
                problems.append(f"{rel}: {len(lines) - 1} lines (at most 1000 in lib/)")
            own = os.path.relpath(dirpath, os.path.join(lib, "visproxy")) if rel.startswith("lib/visproxy/") else None
            for number, text in enumerate(lines, 1):
                m = include.search(text)
                if not m:
                    continue
                target = m.group(1)
                if not os.path.isfile(os.path.join(lib, target)):
                    problems.append(f"{rel}:{number}: includes {target}, which is no file under lib/")
                    continue
                if own is None:
                    continue
                folder = os.path.dirname(target)[len("visproxy/"):]
                if folder != own:
                    edges.setdefault(own, set()).add((folder, f"{rel}:{number}"))

for folder in sorted(edges):
    if folder not in rank:
        problems.append(f"lib/visproxy/{folder}: not listed in the layers of lib/CMakeLists.txt")
        continue
    for target, where in sorted(edges[folder]):
        if target not in rank:
            problems.append(f"{where}: includes from lib/visproxy/{target}, not listed in the layers")
        elif rank[target] >= rank[folder]:
            problems.append(f"{where}: lib/visproxy/{folder} includes from lib/visproxy/{target}, which is not below it")
for folder in layers:
    if not os.path.isdir(os.path.join(lib, "visproxy", folder)):
        problems.append(f"lib/CMakeLists.txt: layer {folder} is no folder under lib/visproxy")

for p in problems:
    print(p)
print(f"check_layout: {len(layers)} layers, {sum(len(v) for v in edges.values())} folder dependencies, {len(problems)} problems")
sys.exit(1 if problems else 0)
