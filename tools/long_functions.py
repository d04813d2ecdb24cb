#!/usr/bin/env python3
"""Lists the functions in src/ longer than a limit (80 lines by default), outside test modules.

A function may stay longer when a line of its doc comment starts with `One piece:` and says why
it must be one (a shader-like loop, a table). With --check the exit status is 1 when any other
function is over the limit, so the test suite keeps the rule.

    python3 tools/long_functions.py [--limit 80] [--check] [PATH...]
"""
import argparse
import os
import re
import sys

FN = re.compile(r"\s*(pub(\([^)]*\))?\s+)?(const\s+)?(async\s+)?(unsafe\s+)?fn\s+(\w+)")
TESTS = re.compile(r"\s*#\[cfg\(test\)\]")


def code_of(line):
    """The line without its comment and the contents of its string and char literals."""
    line = re.sub(r'"(\\.|[^"\\])*"', '""', line)
    line = re.sub(r"'(\\.|[^'\\])'", "''", line)
    return re.sub(r"//.*", "", line)


def body_end(lines, start):
    """The index of the line closing the function opened at `start`, or None (a declaration)."""
    depth, opened = 0, False
    for j in range(start, len(lines)):
        code = code_of(lines[j])
        if not opened and ";" in code and "{" not in code:
            return None
        for ch in code:
            if ch == "{":
                depth, opened = depth + 1, True
            elif ch == "}":
                depth -= 1
        if opened and depth == 0:
            return j
    return None


def exempt(lines, start):
    """Whether the doc comment above line `start` says why the function is one piece."""
    k = start - 1
    while k >= 0 and re.match(r"\s*(///|#\[)", lines[k]):
        if re.match(r"\s*///\s*One piece:", lines[k]):
            return True
        k -= 1
    return False


def long_functions(path, limit):
    lines = open(path, encoding="utf-8").read().split("\n")
    found = []
    for i, line in enumerate(lines):
        if TESTS.match(line) and i + 1 < len(lines) and re.match(r"\s*(pub )?mod tests", lines[i + 1]):
            break
        m = FN.match(line)
        if not m:
            continue
        end = body_end(lines, i)
        if end is not None and end - i + 1 > limit:
            found.append((end - i + 1, path, i + 1, m.group(6), exempt(lines, i)))
    return found


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--limit", type=int, default=80)
    ap.add_argument("--check", action="store_true")
    ap.add_argument("paths", nargs="*", default=["src"])
    args = ap.parse_args()
    files = []
    for p in args.paths:
        if os.path.isfile(p):
            files.append(p)
        for root, _, names in os.walk(p):
            files += [os.path.join(root, n) for n in names if n.endswith(".rs")]
    found = sorted((f for p in files for f in long_functions(p, args.limit)), reverse=True)
    for n, path, line, name, ok in found:
        print(f"{n:4d} {path}:{line} {name}{'  (one piece, said why)' if ok else ''}")
    over = [f for f in found if not f[4]]
    print(f"{len(over)} functions over {args.limit} lines without a reason", file=sys.stderr)
    return 1 if args.check and over else 0


if __name__ == "__main__":
    sys.exit(main())
