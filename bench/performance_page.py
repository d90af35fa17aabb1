#!/usr/bin/env python3
"""Writes docs/performance.md: the benchmark table of this build on this machine.

    cmake --build build --target performance_page

runs, on one tile (Beckmann alpha = 0.5, 4 cells per correlation length, default 1024^2):
microsim_bench (G1 estimators (a) and (b) against a bare Embree loop over the same rays, the
mirror and dielectric walks against a replay of their own Embree queries and against a plain walk
tracer, the Smith random-walk model) and bench/peak_memory.sh (peak memory of each command, on
1024^2 and 4096^2 tiles), then
writes the page: the machine (cores, processor model, load average), the date, the commands, the
tables. Rates are per processor second (user + system time of all threads), the best of --repeat
runs; on a shared machine the ratios to the bare loop are the robust numbers.

    bench/performance_page.py --build BUILD --out docs/performance.md [--resolution N]
                              [--rays N] [--walks N] [--repeat K] [--threads T]
                              [--memory-resolutions N,M]
"""
import argparse
import datetime
import os
import platform
import re
import shlex
import subprocess
import sys
import time


def run(cmd):
    """stdout of cmd (which must succeed), and its wall seconds."""
    t0 = time.monotonic()
    out = subprocess.run(cmd, check=True, stdout=subprocess.PIPE, text=True).stdout
    return out, time.monotonic() - t0


def machine():
    model = "unknown processor"
    with open("/proc/cpuinfo") as f:
        for line in f:
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    mem_gib = 0.0
    with open("/proc/meminfo") as f:
        for line in f:
            if line.startswith("MemTotal"):
                mem_gib = int(line.split()[1]) / 2**20
    return model, os.cpu_count(), mem_gib


def load_average():
    with open("/proc/loadavg") as f:
        return " / ".join(f.read().split()[:3])


def number(s):
    return float(s)


def parse_bench(out):
    """G1 rows per view, walk rows per (material, view), Smith walks per view, peak per tile."""
    g1, walks, smith, peak = {}, {}, {}, {}
    for line in out.splitlines():
        t = line.split()
        if len(t) == 3 and t[0].endswith("^2"):  # the closing table: tile, peak MiB, B/facet
            peak = dict(mib=number(t[1]), bytes_per_facet=number(t[2]))
        elif len(t) == 16 and t[0].endswith("^2") and t[1].endswith("deg"):
            v = list(map(number, t[2:]))
            g1[int(t[1][:-3])] = dict(a=v[3], b=v[4], bare=v[5], ratio=v[6], lean=v[7],
                                      lean_ratio=v[8], peak=v[10], bytes_per_facet=v[11],
                                      wall_a=v[12], wall_bare=v[13], build_s=v[1])
        elif len(t) == 17 and t[0] in ("mirror", "dielectric"):
            v = list(map(number, t[1:]))
            walks[(t[0], int(v[0]))] = dict(paths=v[1], segs=v[2], msegs=v[3], queries=v[4],
                                            bare=v[5], ratio=v[6], plain=v[7], vs_plain=v[10])
        elif t[:1] == ["smith-walk"]:
            smith[int(float(t[1]))] = number(t[2])
    return g1, walks, smith, peak


def parse_peak_memory(out):
    rows = []
    for line in out.splitlines():
        t = line.split()
        if len(t) == 6 and t[0].endswith("^2"):
            rows.append(dict(tile=t[0].replace("^2", "²"), command=t[1], peak=number(t[2]), bytes_per_facet=number(t[3]),
                             cpu=number(t[4]), wall=t[5]))
    return rows


def shown(path, source):
    """A path as the page shows it: relative to the source tree, never this machine's."""
    rel = os.path.relpath(path, source)
    if not rel.startswith(".."):
        return rel
    return os.path.join(os.path.basename(os.path.dirname(os.path.abspath(path))), os.path.basename(path))


def page(a, g1, walks, smith, peak, memory, info):
    n = a.resolution
    L = []
    L.append("# Performance\n")
    L.append("The benchmark table of the current code, written by `cmake --build build --target "
             "performance_page` (`bench/performance_page.py`); it replaces this page. "
             "Tile: Beckmann α = 0.5, 4 cells per correlation length, "
             f"{n}² cells ({2 * n * n:,} facets).\n")
    L.append("| | |\n|---|---|")
    L.append(f"| date | {info['date']} |")
    L.append(f"| machine | {info['cores']} cores, {info['model']}, {info['mem']:.0f} GiB |")
    L.append(f"| load average (1 / 5 / 15 min) | before {info['load_before']}; after {info['load_after']} |")
    L.append(f"| threads | {a.threads} |")
    L.append(f"| run time | {info['seconds']:.0f} s |")
    L.append("")
    L.append("Commands (from the source folder):\n")
    L.append("```text")
    for c in info["commands"]:
        L.append(c)
    L.append("```\n")
    L.append("Rates are per processor second (user + system time of all threads), the best of "
             f"{a.repeat} run{'s' if a.repeat > 1 else ''} with the estimator and its bare loop interleaved in one process. "
             "When other work shares the cores (a load average above the core count) the absolute "
             "rates drop and scatter; the ratios to the bare loop, which lose the same share, are "
             "the numbers to compare between machines.\n")

    L.append("## Masking G1: rays per second\n")
    L.append("Estimator (a) is ray casting from above (`measure g1`, the primary rays); (b) is area "
             "sampling (occlusion rays leaving sampled facets). The bare loop is `rtcIntersect1` "
             "over the very same rays as (a) with nothing else (no wrap-around, facet lookup or "
             "binning).\n")
    L.append("| view θ | (a) Mrays/s | (b) Mrays/s | bare loop Mrays/s | (a) / bare | (a) wall Mrays/s |")
    L.append("|---|---|---|---|---|---|")
    for th in sorted(g1):
        r = g1[th]
        L.append(f"| {th}° | {r['a']:.2f} | {r['b']:.2f} | {r['bare']:.2f} | {r['ratio']:.2f} | {r['wall_a']:.2f} |")
    L.append("")

    L.append("## Random walks (`measure bsdf`): paths per second\n")
    L.append(f"{a.walks:,} paths per row. *Queries / bare*: the walks' Embree queries per second "
             "against a bare loop replaying the same queries in order; *vs plain tracer*: paths per "
             "second against a plain Embree walk tracer on the same heights "
             "(`bench/plain_walk.hpp`).\n")
    L.append("| material | incidence θ | paths/s | segments/path | queries / bare | vs plain tracer |")
    L.append("|---|---|---|---|---|---|")
    for (m, th) in sorted(walks, key=lambda k: (k[0] != "mirror", k[1])):
        r = walks[(m, th)]
        L.append(f"| {m} | {th}° | {r['paths'] / 1e3:.0f} k | {r['segs']:.3f} | {r['ratio']:.2f} | {r['vs_plain']:.2f} |")
    L.append("")
    if smith:
        L.append("The Smith random-walk model (analytic, no surface), mirror: " + ", ".join(
            f"{smith[th] / 1e6:.2f} M walks/s at {th}°" for th in sorted(smith)) + ".\n")

    L.append("## Memory\n")
    if peak:
        L.append(f"The benchmark process (generation, Embree scene, facet table, G1 in both "
                 f"estimators): peak resident memory {peak['mib']:.0f} MiB, "
                 f"{peak['bytes_per_facet']:.0f} bytes per facet; Embree scene build "
                 f"{g1[min(g1)]['build_s']:.2f} s.\n")
    L.append("Each command on its own (`bench/peak_memory.sh`, `/usr/bin/time -v`, whole process; "
             "bytes per facet include the program and its libraries, about 30 MiB, which dominate on small tiles):\n")
    L.append("| tile | command | peak MiB | bytes/facet | processor s |")
    L.append("|---|---|---|---|---|")
    for r in memory:
        L.append(f"| {r['tile']} | {r['command']} | {r['peak']:.0f} | {r['bytes_per_facet']:.1f} | {r['cpu']:.1f} |")
    L.append("")
    return "\n".join(L)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--build", required=True, help="build folder (microsim, microsim_bench)")
    p.add_argument("--out", required=True)
    p.add_argument("--resolution", type=int, default=1024)
    p.add_argument("--rays", type=int, default=1000000)
    p.add_argument("--walks", type=int, default=200000)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--memory-resolutions", default="1024,4096",
                   help="tiles of bench/peak_memory.sh (comma-separated)")
    p.add_argument("--threads", type=int, default=2)
    a = p.parse_args()
    source = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    bench = os.path.join(a.build, "microsim_bench")
    program = os.path.join(a.build, "microsim")
    peak = os.path.join(source, "bench", "peak_memory.sh")
    # microsim_bench uses all cores TBB sees; --threads limits the commands of peak_memory.sh.
    bench_cmd = [bench, "--rays", str(a.rays), "--repeat", str(a.repeat), "--walks", str(a.walks),
                 str(a.resolution)]
    peak_cmd = [peak, "-b", program, "-t", str(a.threads)] + a.memory_resolutions.split(",")
    model, cores, mem = machine()
    info = dict(model=model, cores=cores, mem=mem, load_before=load_average(),
                date=datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"))
    t0 = time.monotonic()
    print("running", " ".join(bench_cmd), flush=True)
    bench_out, _ = run(bench_cmd)
    print(bench_out, flush=True)
    print("running", " ".join(peak_cmd), flush=True)
    peak_out, _ = run(peak_cmd)
    print(peak_out, flush=True)
    info["seconds"] = time.monotonic() - t0
    info["load_after"] = load_average()
    paths = (bench, program, peak)
    info["commands"] = [" ".join(shlex.quote(shown(c, source) if c in paths else c) for c in cmd)
                        for cmd in (bench_cmd, peak_cmd)]
    g1, walks, smith, peak = parse_bench(bench_out)
    memory = parse_peak_memory(peak_out)
    if not g1 or not walks or not peak or not memory:
        sys.exit("performance_page: could not read the benchmark's output (format changed?)")
    text = page(a, g1, walks, smith, peak, memory, info)
    with open(a.out, "w") as f:
        f.write(text)
    print(f"wrote {a.out} ({info['seconds']:.0f} s)")


if __name__ == "__main__":
    main()
