"""Tables of analysis/objects_grooves_tables.sh from its measure bsdf records."""
import json
import math
import os
import sys


def summary(path):
    with open(path) as f:
        j = json.load(f)
    return j.get("summary", j)


def main(out):
    print("## Mirror box H/W = 0.5: total albedo per unit macro area vs 1 + (H/W) tan(theta_i)")
    for th in (0, 30, 60):
        s = summary(os.path.join(out, f"box_{th}.json"))
        a, e = s["albedo"]["reflected"]["total"], s["reflected_stderr"]["total"]
        r = 1 + 0.5 * math.tan(math.radians(th))
        print(f"theta_i {th:2d}: {a:.5f} +- {e:.5f}  ratio {r:.5f}  z {(a - r) / e:+.2f}  "
              f"below base plane {s['normalization']['reflected_below_base_plane']:.4f}")
    print("\n## Tiled mirror boxes (H/W = 0.5), theta_i = 60: albedo vs N, model 1 + (H/(N W)) tan(theta_i)")
    for n in (1, 2, 4, 8, 16):
        s = summary(os.path.join(out, f"tiled_{n}_60.json"))
        a, e = s["albedo"]["reflected"]["total"], s["reflected_stderr"]["total"]
        r = 1 + 0.5 / n * math.tan(math.radians(60))
        print(f"N {n:2d}: {a:.5f} +- {e:.5f}  model {r:.5f}  z {(a - r) / e:+.2f}")
    print("\n## Periodic mirror V-grooves: per-order albedo vs the closed form (vgroove_multiple)")
    zmax, n = 0.0, 0
    for tf in (45, 60, 70):
        for th in (0, 20, 45, 70):
            for ph in (0, 30, 60):
                s = summary(os.path.join(out, f"vgroove_{tf}_{th}_{ph}.json"))
                cells = []
                for row in s["rows"]:
                    if row["side"] != "reflected" or row["order"] == "total":
                        continue
                    z = row.get("z_vgroove_multiple")
                    if row["albedo"] > 0 or row["vgroove_multiple"] > 0:
                        cells.append(f"{row['order']} {row['albedo']:.4f}+-{row['albedo_stderr']:.4f} "
                                     f"({row['vgroove_multiple']:.4f})")
                    if z is not None and row["albedo_stderr"] > 1e-6:
                        zmax, n = max(zmax, abs(z)), n + 1
                print(f"facet {tf} theta_i {th:2d} phi_i {ph:2d}: " + "; ".join(cells))
    print(f"max |z| over {n} per-order comparisons with an error: {zmax:.2f}")
    print("\n## V-cavity ensemble, Beckmann alpha 0.5, mirror: traced vs V-cavity model vs Smith walk")
    for th in (0, 30, 60, 80):
        s = summary(os.path.join(out, f"vcavity_{th}.json"))
        own = s["albedo_models"]["vcavity_multiple_grooves"]["reflected"]
        for row in s["rows"]:
            if row["side"] != "reflected" or row["order"] == "total":
                continue
            print(f"theta_i {th:2d} {row['order']:>11}: traced {row['albedo']:.5f}+-{row['albedo_stderr']:.5f}"
                  f"  vcavity_multiple {row['vcavity_multiple']:.5f} (z {row.get('z_vcavity_multiple') or 0:+.2f})"
                  f"  own grooves {own[row['order']]:.5f}"
                  f"  smith walk {row.get('smith_multiple', float('nan')):.5f}")


if __name__ == "__main__":
    main(sys.argv[1])
