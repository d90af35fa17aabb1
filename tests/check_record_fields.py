#!/usr/bin/env python3
"""Every field of the measurement records' rows is documented in docs/reference/records.md.

Runs small measurements (one surface, and an ensemble of two) with the built program and checks
that each field of their rows and bins (NAME, or NAME_stderr / NAME_stderr_rays of a documented
NAME) is named in the page's section of that command and table. A field a command starts
writing without a specification entry (measure/table.hpp TableSpec) fails here.
Python standard library only.
"""
import argparse
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path


def documented(page):
    """{(command, table): set of names} from the page's sections `## `command`: `table``."""
    sections, current = {}, None
    for line in page.read_text().splitlines():
        m = re.match(r"#{2,3} `([^`]+)`: `([^`]+)`", line)
        if m:
            current = (m.group(1), m.group(2))
            sections[current] = set()
        elif current:
            # Names in code spans, and named in the text (such as t_dof after `surfaces`).
            sections[current].update(re.findall(r"[A-Za-z0-9_]+", line.replace("\\", "")))
    return sections


def undocumented(rows, names, bin_names):
    def missing(obj, known):
        # NAME_stderr and NAME_stderr_rays of a documented NAME; z_..._rays of a documented z
        # (table.hpp one_surface_nominal_z).
        return {k for k in obj if k != "bins" and k not in known
                and re.sub(r"_stderr(_rays)?$", "", k) not in known
                and not (k.startswith("z_") and re.sub(r"_rays$", "", k) in known)}
    out = set()
    for row in rows:
        out |= missing(row, names)
        for b in row.get("bins", []):
            out |= {"bins." + k for k in missing(b, bin_names)}
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--microsim", required=True)
    ap.add_argument("--page", type=Path, required=True, help="docs/reference/records.md")
    args = ap.parse_args()
    sections = documented(args.page)
    microsim = str(Path(args.microsim).resolve())
    with tempfile.TemporaryDirectory(prefix="record-fields-") as folder:
        return check(microsim, Path(folder), sections, args.page.name)


def check(microsim, work, sections, page):
    def run(*words):
        subprocess.run([microsim, "-q", *words], cwd=work, check=True)

    for seed in ("1", "2"):
        run("generate", "gaussian", "--resolution", "32", "--alpha", "0.5", "--seed", seed, "-o", f"s{seed}.exr")
    small = ["--rays", "4000"]
    runs = [
        ("measure ndf", ["rows"], ["measure", "ndf", "s1.exr", "-o", "ndf.json"]),
        ("measure g1", ["rows"], ["measure", "g1", "s1.exr", "--theta", "0,60", *small, "-o", "g1.json"]),
        ("measure g1", ["rows"], ["measure", "g1", "s1.exr", "s2.exr", "--theta", "0,60", *small, "-o", "g1e.json"]),
        ("measure g2", ["rows"], ["measure", "g2", "s1.exr", "--theta-o", "40", "--theta-i", "60", *small, "-o", "g2.json"]),
        ("measure g2", ["rows"], ["measure", "g2", "s1.exr", "s2.exr", "--theta-o", "40", "--theta-i", "60", *small,
                                  "-o", "g2e.json"]),
        ("measure vndf", ["rows"], ["measure", "vndf", "s1.exr", "--theta", "40", *small, "-o", "vndf.json"]),
        ("measure vndf", ["rows"], ["measure", "vndf", "s1.exr", "s2.exr", "--theta", "40", *small, "-o", "vndfe.json"]),
        ("measure bsdf", ["rows", "in_plane"], ["measure", "bsdf", "s1.exr", "--material", "dielectric", "--eta", "1.5",
                                                "--theta-i", "30", *small, "-o", "bsdf.json"]),
        ("measure albedo", ["rows", "averages"], ["measure", "albedo", "s1.exr", "s2.exr", "--material", "dielectric",
                                                  "--eta", "1.5", "--mu-nodes", "3", *small, "-o", "albedo.json"]),
    ]
    failures = 0
    for command, tables, words in runs:
        run(*words)
        record = json.loads((work / words[-1]).read_text())
        for table in tables:
            names = sections.get((command, table))
            if names is None:
                print(f"{page}: no section for {command} {table}")
                failures += 1
                continue
            extra = undocumented(record[table], names, sections.get((command, "bins"), set()))
            if extra:
                print(f"{words[-1]}: {command} {table}: not in {page}: {', '.join(sorted(extra))}")
                failures += 1
    print("every field documented" if not failures else f"{failures} table(s) with undocumented fields")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
