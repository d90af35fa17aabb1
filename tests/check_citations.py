#!/usr/bin/env python3
"""Every source citation in the repository resolves in the bibliography, and nothing points outside.

Scans include/ src/ python/ analysis/ tests/ bench/ fuzz/ plugins/ docs/ for citations written as
[Key] or [Key, eq. 21] (Key: CamelCase author or title and a two-digit year, Heitz14, or an undated
blog key ending in Blog) and fails, with file:line, on
  * a key that docs/theory/bibliography.md does not define (a "## Key" heading there);
  * a pointer to notes or documents outside the repository (the design notes' file name, the
    folder of working copies of the sources, a path of a build machine);
  * a citation in the old form that named a source by a three-digit number ("NNN eq. 1b").

Usage: check_citations.py [ROOT]   (ROOT defaults to the repository holding this script)
Python 3, standard library only. Exit 0 when clean, 1 with one line per problem otherwise.
"""
import os
import re
import sys

FOLDERS = ["include", "src", "python", "analysis", "tests", "bench", "fuzz", "plugins", "docs"]
SKIP_DIRS = {"_build", "__pycache__", ".git", "build"}
BINARY_EXT = {".png", ".jpg", ".jpeg", ".exr", ".gif", ".pdf", ".bsdf", ".binary", ".bin", ".npy",
              ".npz", ".gz", ".zip", ".pyc", ".so", ".a", ".o", ".ply", ".obj", ".stl", ".off"}
BIBLIOGRAPHY = os.path.join("docs", "theory", "bibliography.md")

KEY = r"[A-Z][A-Za-z]*(?:\d{2}[a-z]?|Blog)"
# "[Key]" or "[Key, ..." not glued to a name (a[Key] is an index, not a citation); the closing
# bracket may be on the next line of a comment, so only the key is required here.
CITATION = re.compile(r"(?<![\w\]\)])\[(" + KEY + r")(?=[,\]])")
DEFINITION = re.compile(r"^#{2,3}\s+(" + KEY + r")\s*$|^\((" + KEY + r")\)=\s*$")
OUTSIDE = re.compile(r"\.\./shared|shared[/]references|DESIGN\.md|[/]work[/]")
# (also right after a C escape such as a newline inside a string)
OLD_FORM = re.compile(r"(?:(?<![\w.,/-])|(?<=\\[nt]))00[0-4] (?:eq|Eq|sec|Sec|App|Appendix|Table|Fig|after)\b"
                      r"|(?:(?<![\w.,/-])|(?<=\\[nt]))00[0-4] [\"'][A-Z]")


def defined_keys(root):
    keys = set()
    path = os.path.join(root, BIBLIOGRAPHY)
    with open(path, encoding="utf-8") as f:
        for line in f:
            m = DEFINITION.match(line.rstrip("\n"))
            if m:
                keys.add(m.group(1) or m.group(2))
    return keys


def text_files(root):
    this = os.path.abspath(__file__)
    for folder in FOLDERS:
        for base, dirs, files in os.walk(os.path.join(root, folder)):
            dirs[:] = sorted(d for d in dirs if d not in SKIP_DIRS and not d.startswith("build"))
            for name in sorted(files):
                path = os.path.join(base, name)
                if os.path.splitext(name)[1].lower() in BINARY_EXT or os.path.abspath(path) == this:
                    continue
                try:
                    with open(path, encoding="utf-8") as f:
                        yield path, f.read().splitlines()
                except (UnicodeDecodeError, OSError):
                    continue


def problems(root):
    keys = defined_keys(root)
    if not keys:
        yield f"{BIBLIOGRAPHY}: defines no key (expected '## Key' headings)"
    for path, lines in text_files(root):
        rel = os.path.relpath(path, root)
        for number, line in enumerate(lines, 1):
            for m in CITATION.finditer(line):
                if m.group(1) not in keys:
                    yield f"{rel}:{number}: citation key [{m.group(1)}] is not defined in {BIBLIOGRAPHY}"
            m = OUTSIDE.search(line)
            if m:
                yield f"{rel}:{number}: points outside the repository ('{m.group(0)}')"
            m = OLD_FORM.search(line)
            if m:
                yield f"{rel}:{number}: old numeric citation '{m.group(0)}...': cite by a bibliography key"


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    found = list(problems(root))
    for p in found:
        print(p)
    if found:
        print(f"check_citations: {len(found)} problem(s)")
        return 1
    print("check_citations: every citation key resolves; no pointer outside the repository")
    return 0


if __name__ == "__main__":
    sys.exit(main())
