#!/usr/bin/env python3
"""Lengths of the functions of the C++ sources: the N longest, and whether any exceeds a limit.

A function's length is the number of lines from the first line of its signature to its closing
brace, as a reader sees it on the page (comments and blank lines inside count). Functions are
found by reading the code with comments, string and character literals blanked out and tracking
the braces: a brace opens a function body when it ends a declaration with a parameter list at
namespace or class scope (constructors' member initializers `m{...}` are skipped). Lambdas and
local classes count as part of the function that holds them.

Usage: function_lengths.py [N] [--limit L] [--fail] [--root DIR] [DIR ...]
  N        how many of the longest functions to list (default 10)
  --limit  the length counted as too long (default 80): the summary counts the functions over it
  --fail   exit 1 when a function is longer than --limit (the default only reports)
  DIR      folders to read, under --root (default: src include)
"""
import argparse
import pathlib
import re
import sys

SUFFIXES = {".cpp", ".hpp", ".h", ".cc", ".cxx", ".hh"}


def blank_comments_and_literals(text):
    """The text with comments and string/char literals replaced by spaces (newlines kept)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "R" and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]{0,16})\(', text[i:])
            if not m:
                out.append(c)
                i += 1
                continue
            end = text.find(")" + m.group(1) + '"', i)
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            # a digit separator (1'000'000) is not a character literal
            if c == "'" and i > 0 and text[i - 1].isalnum() and i + 1 < n and text[i + 1].isalnum() \
                    and re.match(r"[0-9a-fA-FxXbB']", text[i - 1]):
                out.append(" ")
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(c + " " * (j - i - 2) + c if j - i >= 2 else c)
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def blank_preprocessor(text):
    """Preprocessor lines (with their continuations) blanked: they are not declarations."""
    lines = text.split("\n")
    continued = False
    for k, line in enumerate(lines):
        if continued or line.lstrip().startswith("#"):
            continued = line.rstrip().endswith("\\")
            lines[k] = ""
    return "\n".join(lines)


def outside_parens(s):
    """The parts of s at parenthesis depth 0."""
    depth, out = 0, []
    for c in s:
        if c == "(":
            depth += 1
        elif c == ")":
            depth = max(0, depth - 1)
        elif depth == 0:
            out.append(c)
    return "".join(out)


def function_name(declaration):
    """The name before the parameter list of a declaration ("Tracer::Tracer", "operator()")."""
    m = re.search(r"(~?[A-Za-z_][\w:]*::)?operator\s*(\(\)|[^\s(]+)\s*\(", declaration)
    if m:
        return (m.group(1) or "") + "operator" + m.group(2)
    m = re.search(r"(~?[A-Za-z_][\w:<>,]*)\s*\(", declaration)
    return m.group(1) if m else declaration.strip()[:40]


def brace_kind(declaration):
    """What a brace at namespace or class scope opens, from the declaration before it."""
    d = " ".join(declaration.split())
    d = re.sub(r"^template\s*<.*?>\s*", "", d)
    if re.match(r"^(inline\s+)?namespace\b", d) or re.match(r"^extern\b", d):
        return "namespace"
    top = outside_parens(d)
    if re.match(r"^(class|struct|union|enum)\b", d) and "(" not in d.split("{")[0].split(":")[0]:
        return "class"
    if "(" in d and "=" not in top.replace("==", "").replace("operator=", ""):
        return "function"
    return "other"


def member_initializer_brace(declaration):
    """A `m{...}` of a constructor's initializer list (the declaration runs `...) : a(x), m`)."""
    d = declaration.rstrip()
    close = d.rfind(")")
    tail = d[close + 1:] if close >= 0 else ""
    return bool(re.search(r"(^|\W):[^:]", tail)) and bool(re.search(r"[\w>]$", d))


def functions_of(text):
    """(first line, last line, name) of every function body in the text (1-based lines)."""
    code = blank_preprocessor(blank_comments_and_literals(text))
    found, stack = [], []  # stack of (kind, start line, name)
    decl_start, decl = None, []
    line = 1
    for c in code:
        if c == "\n":
            line += 1
        inside_function = any(k == "function" for k, _, _ in stack)
        if c == "{":
            if inside_function:
                stack.append(("other", line, ""))
                continue
            declaration = "".join(decl)
            if member_initializer_brace(declaration) and brace_kind(declaration) == "function":
                stack.append(("initializer", line, ""))
                decl.append("{")
                continue
            kind = brace_kind(declaration)
            stack.append((kind, decl_start or line, function_name(declaration) if kind == "function" else ""))
            decl_start, decl = None, []
        elif c == "}":
            if not stack:
                continue
            kind, start, name = stack.pop()
            if kind == "initializer":
                decl.append("}")
                continue
            if kind == "function":
                found.append((start, line, name))
            if not any(k == "function" for k, _, _ in stack):
                decl_start, decl = None, []
        elif c == ";" and not inside_function:
            if stack and stack[-1][0] == "initializer":
                continue
            decl_start, decl = None, []
        elif not inside_function:
            if stack and stack[-1][0] == "initializer":
                continue
            if decl_start is None and not c.isspace():
                decl_start = line
            decl.append(c)
            if re.search(r"\b(public|private|protected)\s*:$", "".join(decl[-12:])):
                decl_start, decl = None, []
    return found


def lengths(root, folders):
    """(length, path, first line, name) of every function under the folders."""
    rows = []
    for folder in folders:
        for path in sorted((root / folder).rglob("*")):
            if path.suffix not in SUFFIXES or not path.is_file():
                continue
            text = path.read_text(errors="replace")
            for first, last, name in functions_of(text):
                rows.append((last - first + 1, str(path.relative_to(root)), first, name))
    rows.sort(key=lambda r: (-r[0], r[1], r[2]))
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("count", nargs="?", type=int, default=10)
    parser.add_argument("folders", nargs="*", default=["src", "include"])
    parser.add_argument("--limit", type=int, default=80)
    parser.add_argument("--fail", action="store_true")
    parser.add_argument("--root", default=".")
    args = parser.parse_args()
    rows = lengths(pathlib.Path(args.root), args.folders)
    for n, path, first, name in rows[:args.count]:
        print(f"{n:5d} {path}:{first} {name}")
    over = [r for r in rows if r[0] > args.limit]
    print(f"{len(rows)} functions, {len(over)} longer than {args.limit} lines")
    return 1 if args.fail and over else 0


if __name__ == "__main__":
    sys.exit(main())
