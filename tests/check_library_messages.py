#!/usr/bin/env python3
"""The library's messages name its parameters, never a front end's options.

Scans the library (include/ and src/, without src/cli, the command line's own layer) for the
string literals of every error it constructs (UsageError, ParameterError, RuntimeFailure) and of
the checks that put a caller's name into one (io/checks.hpp and the like), and fails, with
file:line, on a literal that names a command-line option: "--theta-i" or "-o ". The library
writes "{theta_i}" (a ParameterError placeholder, include/microsim/common.hpp); the command
line spells it --theta-i, Python theta_i.

Usage: check_library_messages.py [ROOT]   (ROOT defaults to the repository holding this script)
Python 3, standard library only. Exit 0 when clean, 1 with one line per problem otherwise.
"""
import os
import re
import sys

FOLDERS = ["include", "src"]
SKIP = [os.path.join("src", "cli")]
# Calls whose string literals become an error's message.
CALLS = ["UsageError", "ParameterError", "RuntimeFailure", "require_in_range", "parse_number_in",
         "parse_integer_in", "parse_seed", "split_items", "require_regular_input", "require_memory",
         "parse_json_input", "apply_guard_band", "require_positive", "require_alpha",
         "require_finite_positive", "parse_numbers"]
CALL = re.compile(r"\b(?:" + "|".join(CALLS) + r")\b\s*(?:\w+\s*)?\(")
LITERAL = re.compile(r'"(?:[^"\\\n]|\\.)*"')
# A long option ("--rays"), or the short output option at a word's start ("-o x.exr").
OPTION = re.compile(r"(?<![\w-])--[a-z]|(?<![\w-])-o(?![\w-])")


def strip_comments(text):
    """The text with // and /* */ comments blanked (string literals kept, line numbers kept)."""
    out, k, n = [], 0, len(text)
    while k < n:
        c = text[k]
        if c == '"':
            m = LITERAL.match(text, k)
            end = m.end() if m else k + 1
            out.append(text[k:end])
            k = end
        elif c == "'" and k + 2 < n:
            end = text.find("'", k + 2 if text[k + 1] == "\\" else k + 1)
            end = k + 1 if end < 0 else end + 1
            out.append(text[k:end])
            k = end
        elif text.startswith("//", k):
            end = text.find("\n", k)
            end = n if end < 0 else end
            k = end
        elif text.startswith("/*", k):
            end = text.find("*/", k)
            end = n if end < 0 else end + 2
            out.append("\n" * text.count("\n", k, end))
            k = end
        else:
            out.append(c)
            k += 1
    return "".join(out)


def call_extent(text, open_paren):
    """Index just past the parenthesis closing the one at open_paren (string literals skipped)."""
    depth, k = 0, open_paren
    while k < len(text):
        c = text[k]
        if c == '"':
            m = LITERAL.match(text, k)
            k = m.end() if m else k + 1
            continue
        if c == "(":
            depth += 1
        elif c == ")":
            depth -= 1
            if depth == 0:
                return k + 1
        k += 1
    return len(text)


def problems_in(path, rel):
    with open(path, encoding="utf-8") as f:
        text = strip_comments(f.read())
    found = []
    for call in CALL.finditer(text):
        end = call_extent(text, call.end() - 1)
        for lit in LITERAL.finditer(text, call.end(), end):
            if OPTION.search(lit.group(0)):
                line = text.count("\n", 0, lit.start()) + 1
                found.append(f"{rel}:{line}: a library message names a command-line option: {lit.group(0)}"
                             " (name the parameter: \"{name}\")")
    return found


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    problems = []
    for folder in FOLDERS:
        for dirpath, dirnames, filenames in os.walk(os.path.join(root, folder)):
            rel_dir = os.path.relpath(dirpath, root)
            if any(rel_dir == s or rel_dir.startswith(s + os.sep) for s in SKIP):
                dirnames[:] = []
                continue
            for name in sorted(filenames):
                if name.endswith((".cpp", ".hpp", ".h")):
                    problems += problems_in(os.path.join(dirpath, name), os.path.join(rel_dir, name))
    for p in sorted(set(problems)):
        print(p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
