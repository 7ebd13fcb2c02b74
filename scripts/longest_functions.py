#!/usr/bin/env python3
"""Lists the longest function bodies in the project's C++ sources.

How it measures: a brace-matching scan of each .cc/.h file (comments and
string/char literals blanked first, raw strings included). A function is a
top-level-in-its-namespace/class brace block whose opening brace follows a
`)` (optionally with const/override/noexcept/-> return type/initialiser
list); its length is the lines from the signature's first line to the
closing brace. Lambdas and blocks inside a function count toward it.
Data (brace initialisers after `=`) is not a function.

Usage (from the checkout root): scripts/longest_functions.py [-n 10] [folders...]
Without folders: every top-level folder but tests/, bench/, examples/, build/.
"""
import argparse
import os
import re
import sys

SKIP = {"build", ".git", "tests", "bench", "examples", "node_modules"}


def blank(text):
    """Replaces comments and literals by spaces, keeping newlines."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i)); i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j])); i = j
        elif c == "R" and text.startswith('R"', i) and (i == 0 or not (text[i-1].isalnum() or text[i-1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if not m:
                out.append(c); i += 1; continue
            end = ")" + m.group(1) + '"'
            j = text.find(end, i + m.end())
            j = n if j < 0 else j + len(end)
            out.append('""' + re.sub(r"[^\n]", " ", text[i + 2:j])); i = j
        elif c in "\"'":
            if c == "'" and i > 0 and text[i-1].isalnum():  # digit separator 1'000
                out.append(" "); i += 1; continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(c + " " * (j - i - 1) + c); i = j + 1
        else:
            out.append(c); i += 1
    return "".join(out)


def functions(path):
    text = blank(open(path, encoding="utf-8", errors="replace").read())
    results = []
    stack = []  # (kind, start line, name)
    line = 1
    for i, c in enumerate(text):
        if c == "\n":
            line += 1
        elif c == "{":
            if stack and stack[-1][0] == "func":
                stack.append(("inner", line, None)); continue
            head = text[max(0, i - 600):i]
            stmt = re.split(r"[;{}]", head)[-1]
            s = stmt.strip()
            is_func = False
            name = None
            if ")" in s and not re.search(r"=\s*$", s) and not re.match(r"^(namespace|class|struct|enum|union|extern)\b", s):
                # the name before the parameter list's opening parenthesis
                depth = 0
                k = len(s) - 1
                last_close = s.rfind(")")
                # find the first top-level '(' of the signature
                m = re.search(r"([~\w:<>]+(?:operator\W+)?)\s*\(", s)
                if m and m.group(1) not in ("if", "for", "while", "switch", "catch", "return"):
                    is_func = True
                    name = m.group(1)
            if is_func:
                first = line - stmt.count("\n") + (len(stmt) - len(stmt.lstrip()) and stmt[:len(stmt) - len(stmt.lstrip())].count("\n"))
                stack.append(("func", first, name))
            else:
                stack.append(("scope", line, None))
        elif c == "}":
            if not stack:
                continue
            kind, start, name = stack.pop()
            if kind == "func":
                results.append((line - start + 1, path, start, name))
    return results


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("-n", type=int, default=10)
    ap.add_argument("folders", nargs="*")
    a = ap.parse_args()
    folders = a.folders or sorted(d for d in os.listdir(".") if os.path.isdir(d) and d not in SKIP and not d.startswith("."))
    found = []
    for folder in folders:
        for dirpath, dirnames, filenames in os.walk(folder):
            dirnames[:] = [d for d in dirnames if d not in SKIP]
            for f in filenames:
                if f.endswith((".cc", ".h")):
                    found += functions(os.path.join(dirpath, f))
    found.sort(key=lambda r: (-r[0], r[1], r[2]))
    for length, path, start, name in found[:a.n]:
        print(f"{length:5d}  {path}:{start}  {name}")


if __name__ == "__main__":
    sys.exit(main())
