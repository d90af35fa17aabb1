#!/usr/bin/env python3
"""Report #include cycles among microsim's components.

A component is a header include/microsim/<dir>/<name>.hpp together with its
source src/<dir>/<name>.cpp (and src-local headers, named by their path under
src/). Component A depends on B when A's header or source includes B's header.
A cycle means neither can be understood, tested or linked without the other,
so the script lists every strongly connected group of two or more components
(Tarjan's algorithm) and, optionally, the directory-level cycles
(io -> measure -> io), which is how layering rules ("io may depend on result
types, not the reverse") are stated. A layer rule names lower directories whose
headers and sources must include nothing of the upper ones (measure knows no
request of api, no command of cli).

Usage: include_cycles.py [--root DIR] [--dirs] [--fail] [--fail-touching DIR ...]
                         [--forbid-includes LOWER UPPER ...]
  --dirs             also report cycles between top-level directories (io, measure, ...)
  --fail             exit 1 when a component cycle exists (the default only reports)
  --fail-touching    exit 1 when a component cycle has a member in one of these top-level
                     directories (a guard for the directories already free of cycles)
  --forbid-includes  LOWER UPPER, each a comma-separated list of top-level directories:
                     exit 1 when a header or source in LOWER includes one in UPPER
                     (repeatable: one rule each)
"""
import argparse
import os
import pathlib
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"', re.M)


def component_of(path, root):
    """Component name of a file: its path under include/microsim or src, without suffix."""
    rel = path.relative_to(root)
    parts = rel.parts
    if parts[:2] == ("include", "microsim"):
        parts = parts[2:]
    elif parts[0] == "src":
        parts = parts[1:]
    return str(pathlib.PurePosixPath(*parts).with_suffix(""))


def resolve(target, including, root):
    """File an #include "target" names: include/ first, then relative to the includer ("../"
    folded, so that the file has one component name however it is reached)."""
    for candidate in (root / "include" / target, including.parent / target, root / "src" / target):
        if candidate.is_file():
            return pathlib.Path(os.path.normpath(candidate))
    return None


def component_graph(root):
    """Edges component -> set of components it includes (self-edges dropped)."""
    files = sorted(list((root / "include").rglob("*.hpp")) + list((root / "src").rglob("*.hpp"))
                   + list((root / "src").rglob("*.cpp")))
    graph = {}
    for f in files:
        src = component_of(f, root)
        deps = graph.setdefault(src, set())
        for target in INCLUDE.findall(f.read_text(errors="replace")):
            hit = resolve(target, f, root)
            if hit is None:
                continue
            dst = component_of(hit, root)
            if dst != src:
                deps.add(dst)
                graph.setdefault(dst, set())
    return graph


def top_directory(path, root):
    """Top-level directory of a file under include/microsim or src ("measure", ...), or None."""
    parts = path.relative_to(root).parts
    if parts[:2] == ("include", "microsim") and len(parts) > 3:
        return parts[2]
    if parts[0] == "src" and len(parts) > 2:
        return parts[1]
    return None


def layer_violations(root, lower, upper):
    """Lines "file includes target" for every #include from a file in a `lower` directory of a
    file in an `upper` one (includes resolved as component_graph resolves them)."""
    files = sorted(list((root / "include").rglob("*.hpp")) + list((root / "src").rglob("*.hpp"))
                   + list((root / "src").rglob("*.cpp")))
    found = []
    for f in files:
        if top_directory(f, root) not in lower:
            continue
        for target in INCLUDE.findall(f.read_text(errors="replace")):
            hit = resolve(target, f, root)
            if hit is not None and top_directory(pathlib.Path(os.path.normpath(hit)), root) in upper:
                found.append(f"{f.relative_to(root)} includes {target}")
    return found


def strongly_connected(graph):
    """Tarjan's strongly connected components, iterative (no recursion limit)."""
    index, low, on_stack, stack, groups = {}, {}, set(), [], []
    counter = 0
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            advanced = False
            for child in children:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                    advanced = True
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                group = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    group.append(member)
                    if member == node:
                        break
                if len(group) > 1:
                    groups.append(sorted(group))
    return sorted(groups)


def directory_graph(graph):
    """Collapse components to their top-level directory (io, measure, ...)."""
    top = lambda c: c.split("/")[0] if "/" in c else "(root)"
    dirs = {}
    for src, deps in graph.items():
        d = dirs.setdefault(top(src), {})
        for dst in deps:
            if top(dst) != top(src):
                d.setdefault(top(dst), []).append((src, dst))
    return dirs


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--root", default=".")
    parser.add_argument("--dirs", action="store_true")
    parser.add_argument("--fail", action="store_true")
    parser.add_argument("--fail-touching", nargs="+", default=[], metavar="DIR")
    parser.add_argument("--forbid-includes", nargs=2, action="append", default=[], metavar=("LOWER", "UPPER"))
    args = parser.parse_args()
    root = pathlib.Path(args.root).resolve()
    graph = component_graph(root)
    cycles = strongly_connected(graph)
    for group in cycles:
        print("component cycle:", " <-> ".join(group))
        for a in group:
            for b in sorted(graph[a] & set(group)):
                print(f"    {a} includes {b}")
    print(f"component cycles: {len(cycles)} ({len(graph)} components)")
    if args.dirs:
        dirs = directory_graph(graph)
        dir_cycles = strongly_connected({d: set(e) for d, e in dirs.items()})
        for group in dir_cycles:
            print("directory cycle:", " <-> ".join(group))
            for a in group:
                for b in sorted(set(dirs[a]) & set(group)):
                    for src, dst in sorted(dirs[a][b]):
                        print(f"    {src} includes {dst}")
        print(f"directory cycles: {len(dir_cycles)}")
    touching = [g for g in cycles if any(c.split("/")[0] in args.fail_touching for c in g)]
    for group in touching:
        print("cycle in a guarded directory:", " <-> ".join(group))
    violations = []
    for lower, upper in args.forbid_includes:
        lower_dirs, upper_dirs = set(lower.split(",")), set(upper.split(","))
        for line in layer_violations(root, lower_dirs, upper_dirs):
            violations.append(line)
            print(f"layer rule ({lower} below {upper}) broken: {line}")
    if args.forbid_includes:
        print(f"layer rule violations: {len(violations)}")
    return 1 if (args.fail and cycles) or touching or violations else 0


if __name__ == "__main__":
    sys.exit(main())
