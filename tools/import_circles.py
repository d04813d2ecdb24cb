#!/usr/bin/env python3
"""Lists the import circles between the files of src/: sets of modules that import each other,
directly or through others (comments and test modules aside; a module's own children and
parent count as any other file). With --check the exit status is 1 when there is one, so the
test suite keeps src/ free of them.

    python3 tools/import_circles.py [--check]
"""
import argparse
import os
import re
import sys

PATH = re.compile(r"\b(crate|super|self|specmap)((?:::\w+)+)")


def modules(root="src"):
    """Module path (a tuple; the binary's under "bin") -> file."""
    found = {}
    for folder, _, names in os.walk(root):
        for name in names:
            if not name.endswith(".rs") or name == "main.rs":
                continue
            path = os.path.join(folder, name)
            parts = path[len(root) + 1:-3].split("/")
            if parts[-1] == "mod":
                parts = parts[:-1]
            if parts == ["lib"]:
                parts = []
            if parts and parts[0] == "cli":
                parts = ["bin"] + parts
            found[tuple(parts)] = path
    return found


def code_of(path):
    """The file's code: test modules and comments left out."""
    src = open(path, encoding="utf-8").read()
    cut = src.find("#[cfg(test)]\nmod tests")
    if cut >= 0:
        src = src[:cut]
    return re.sub(r"//.*", "", src)


def imports(mods):
    """Module -> the modules its paths name (the longest module each path starts with)."""
    def resolve(path):
        for n in range(len(path), 0, -1):
            if tuple(path[:n]) in mods:
                return tuple(path[:n])
        return None

    edges = {m: set() for m in mods}
    for m, path in mods.items():
        own = list(m) if not path.endswith("mod.rs") else list(m) + ["_"]
        for found in PATH.finditer(code_of(path)):
            head, rest = found.group(1), found.group(2).split("::")[1:]
            if head == "specmap" or (head == "crate" and (not m or m[0] != "bin")):
                target = rest
            elif head == "crate":
                target = ["bin"] + rest
            elif head == "super":
                target = own[:-2] + rest if path.endswith("mod.rs") else own[:-1] + rest
                while target and target[0] == "super":
                    target = target[1:]
            else:
                target = (own[:-1] if path.endswith("mod.rs") else own) + rest
            t = resolve(target)
            if t is not None and t != m:
                edges[m].add(t)
    return edges


def circles(edges):
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(comp)

    for v in edges:
        if v not in index:
            visit(v)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args()
    edges = imports(modules())
    found = circles(edges)
    for comp in found:
        names = sorted("::".join(m) for m in comp)
        print("circle:", ", ".join(names))
        members = set(comp)
        for a in comp:
            for b in sorted(edges[a] & members):
                print(f"    {'::'.join(a)} -> {'::'.join(b)}")
    print(f"{len(found)} import circles in src/", file=sys.stderr)
    return 1 if args.check and found else 0


if __name__ == "__main__":
    sys.exit(main())
