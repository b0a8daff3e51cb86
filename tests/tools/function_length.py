#!/usr/bin/env python3
"""Lists C++ function bodies longer than a limit (no function in server/, client/, common/ or
tests/ is longer than 80 lines).

    function_length.py [--limit N] [--list] [--exclude DIR]... DIR...

A function body is an outermost '{' ... '}' whose header (the text since the previous ';', '{'
or '}') ends in ')' with optional qualifiers, or is a constructor's initializer list; control
statements and lambdas inside a function count towards it. Comments, strings and preprocessor
lines are ignored. Files under an --exclude directory are skipped. Exits 1 if a body is longer
than the limit (lines from '{' to '}').
"""
import argparse
import pathlib
import re
import sys

CONTROL = re.compile(r"^\s*(if|for|while|switch|catch|else|do|return|case)\b")
TAIL = re.compile(
    r"\)\s*(const)?\s*(noexcept(\([^)]*\))?)?\s*(override)?\s*(final)?\s*(->\s*[\w:<>,\s*&]+)?\s*$")


def strip(text):
    """Comments, string and character literals and preprocessor lines blanked (newlines kept)."""
    out = []
    i, n = 0, len(text)
    at_line_start = True
    while i < n:
        c = text[i]
        if at_line_start and c == "#":
            while i < n and text[i] != "\n":
                # a continued preprocessor line goes on
                if text[i] == "\\" and i + 1 < n and text[i + 1] == "\n":
                    out.append("\n")
                    i += 2
                    continue
                i += 1
            continue
        if c == "/" and text.startswith("//", i):
            while i < n and text[i] != "\n":
                i += 1
            continue
        if c == "/" and text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * text.count("\n", i, j))
            i = j
            continue
        if c == 'R' and text.startswith('R"', i):
            m = re.match(r'R"([^(]*)\(', text[i:])
            if m:
                end = text.find(")" + m.group(1) + '"', i)
                end = n if end < 0 else end + len(m.group(1)) + 2
                out.append('""' + "\n" * text.count("\n", i, end))
                i = end
                continue
        if c in "\"'":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
            continue
        out.append(c)
        if c == "\n":
            at_line_start = True
        elif not c.isspace():
            at_line_start = False
        i += 1
    return "".join(out)


def functions(path):
    """(name, first line, length in lines) of every outermost function body in the file."""
    text = strip(path.read_text(encoding="utf-8", errors="replace"))
    found = []
    depth = 0
    func_depth = None  # depth at which the current function's body opened
    start_line = 0
    name = ""
    header_start = 0
    line = 1
    for i, c in enumerate(text):
        if c == "\n":
            line += 1
        elif c == "{":
            header = text[header_start:i]
            if func_depth is None:
                flat = " ".join(header.split())
                is_init_list = re.search(r"\)\s*:\s*[\w:]+[({]", flat) is not None
                if flat and not CONTROL.match(flat) and "](" not in flat.replace(" ", "") and (
                        TAIL.search(flat) or is_init_list) and not flat.endswith("= "):
                    func_depth = depth
                    start_line = line
                    m = re.search(r"([~\w:]+)\s*\(", flat)
                    name = m.group(1) if m else flat[:40]
            depth += 1
            header_start = i + 1
        elif c == "}":
            depth -= 1
            if func_depth is not None and depth == func_depth:
                found.append((name, start_line, line - start_line + 1))
                func_depth = None
            header_start = i + 1
        elif c == ";":
            header_start = i + 1
    return found


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--limit", type=int, default=120)
    ap.add_argument("--list", action="store_true", help="print every function over 60 lines")
    ap.add_argument("--exclude", action="append", default=[], metavar="DIR",
                    help="skip the files under DIR (may be given several times)")
    ap.add_argument("dirs", nargs="+")
    a = ap.parse_args()
    excluded = [pathlib.Path(e).resolve() for e in a.exclude]
    over = []
    for d in a.dirs:
        for p in sorted(pathlib.Path(d).rglob("*")):
            if p.suffix not in (".cpp", ".hpp", ".h", ".cc") or "vendor" in p.parts:
                continue
            if any(p.resolve().is_relative_to(e) for e in excluded):
                continue
            for name, start, length in functions(p):
                if length > a.limit or (a.list and length > 60):
                    print(f"{p}:{start}: {name}: {length} lines")
                if length > a.limit:
                    over.append(name)
    if over:
        print(f"function_length: {len(over)} function(s) longer than {a.limit} lines")
        return 1
    skipped = "".join(f" (except {e})" for e in a.exclude)
    print(f"function_length: every function in {' '.join(a.dirs)}{skipped} is at most {a.limit} lines")
    return 0


if __name__ == "__main__":
    sys.exit(main())
