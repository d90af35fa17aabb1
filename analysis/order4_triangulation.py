#!/usr/bin/python3
"""Table of analysis/order4_triangulation.sh: per incidence and order, the mean over tiles (± the
between-tile standard error) of the mirror albedo with cells split along either diagonal, their paired
difference (same heights, same incidence), and the paths lost, unterminated or caught by the tracer's
counters.

usage: order4_triangulation.py OUTDIR TILES
"""
import json
import math
import sys

SLOTS = ["order_1", "order_2", "order_3", "order_4", "order_5", "order_6", "order_7", "order_8plus"]


def mean_se(x):
    n = len(x)
    m = sum(x) / n
    if n < 2:
        return m, float("nan")
    return m, math.sqrt(sum((v - m) ** 2 for v in x) / (n - 1) / n)


def albedos(inc):
    a = dict(inc["albedo"]["reflected"])
    a["order_4plus"] = sum(a[k] for k in SLOTS[3:])
    a["order_5plus"] = sum(a[k] for k in SLOTS[4:])
    return a


def main(out, tiles):
    runs = {v: [json.load(open(f"{out}/tile_{s}{suffix}.json")) for s in range(1, tiles + 1)]
            for v, suffix in (("as generated", ""), ("other diagonal", "_mirrored"))}
    print(f"{tiles} Beckmann alpha = 1 tiles, 16 cells per l, L/l = 32, "
          f"{runs['as generated'][0]['parameters']['rays']} rays per incidence and tile; mean over tiles ± "
          "between-tile standard error; difference paired (same tile), in % of the value as generated\n")
    print("| θi | order | as generated | other diagonal | difference |")
    print("|---|---|---|---|---|")
    n_inc = len(runs["as generated"][0]["incidences"])
    for i in range(n_inc):
        t = runs["as generated"][0]["incidences"][i]["theta_i_deg"]
        for k in ["order_1", "order_2", "order_3", "order_4plus", "order_4", "order_5plus", "total"]:
            a = [albedos(r["incidences"][i])[k] for r in runs["as generated"]]
            b = [albedos(r["incidences"][i])[k] for r in runs["other diagonal"]]
            ma, sa = mean_se(a)
            mb, sb = mean_se(b)
            md, sd = mean_se([y - x for x, y in zip(a, b)])
            rel = f"{100 * md / ma:+.2f} ± {100 * sd / ma:.2f}%" if ma > 0 else "-"
            print(f"| {t:.0f}° | {k} | {ma:.6f} ± {sa:.1e} | {mb:.6f} ± {sb:.1e} | {rel} |")
    print("\nLeaks, summed over tiles and both triangulations:\n")
    print("| θi | paths | lost | unterminated | lost below | back-face first hits | unresolved | lowest total albedo |")
    print("|---|---|---|---|---|---|---|---|")
    for i in range(n_inc):
        incs = [r["incidences"][i] for v in runs for r in runs[v]]
        c = lambda key: sum(x["trace_counters"][key] for x in incs)
        print(f"| {incs[0]['theta_i_deg']:.0f}° | {sum(x['paths'] for x in incs)} | {sum(x['lost_paths'] for x in incs)} | "
              f"{sum(x['unterminated_paths'] for x in incs)} | {c('lost_below')} | {c('backface_hits')} | {c('unresolved')} | "
              f"{min(x['albedo']['reflected']['total'] for x in incs):.7f} |")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], int(sys.argv[2]))
