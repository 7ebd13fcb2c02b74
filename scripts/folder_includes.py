#!/usr/bin/env python3
"""Prints which folders each folder's sources include ("a -> b c"), from the
#include "x/..." lines of its .cc and .h files (robot/trajectory counted as
its own library). Run from the checkout root; tests/ and bench/ are left out
unless named.

Usage: scripts/folder_includes.py [folders...]
"""
import os
import re
import sys

INCLUDE = re.compile(r'^\s*#include "([^"]+)"', re.M)
LIBS = ["robot/trajectory"]  # sub-folders that are libraries of their own


def library_of(path):
    for lib in LIBS:
        if path.startswith(lib + "/"):
            return lib
    return path.split("/", 1)[0]


def main():
    skip = {"build", "tests", "bench", "docs", "examples", "scripts", "tools", "cmake"}
    folders = sys.argv[1:] or sorted(
        d for d in os.listdir(".") if os.path.isdir(d) and not d.startswith(".") and d not in skip)
    edges = {}
    for folder in folders:
        for dirpath, _, files in os.walk(folder):
            for f in files:
                if not f.endswith((".cc", ".h")):
                    continue
                path = os.path.join(dirpath, f)
                src = library_of(path)
                for inc in INCLUDE.findall(open(path, encoding="utf-8", errors="replace").read()):
                    if "/" not in inc:
                        continue
                    dst = library_of(inc)
                    if dst != src and os.path.isdir(inc.split("/", 1)[0]):
                        edges.setdefault(src, set()).add(dst)
    for src in sorted(edges):
        print(f"{src} -> {' '.join(sorted(edges[src]))}")


if __name__ == "__main__":
    sys.exit(main())
