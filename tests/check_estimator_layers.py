#!/usr/bin/env python3
"""The G2 and VNDF estimators are layered: result types (measure/g2_result, measure/vndf_result)
below the one estimator of each (measure/g2_estimator, measure/vndf_estimator), below their entry
points (measure/g2_measure, measure/vndf_measure, the ensemble's measure/ensemble_g2_vndf), with
the ensemble's shared steps (measure/estimator_steps) including none of them. Fails when one of
these components is in an include cycle (tools/include_cycles.py's components) or an estimator
or result type includes an entry point. A synthetic tree with the cycle estimator_steps <->
g2_measure must be caught, or the check itself is wrong."""
import pathlib
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
import include_cycles  # noqa: E402

LAYERED = ["measure/g2_result", "measure/vndf_result", "measure/g2_estimator", "measure/vndf_estimator",
           "measure/g2_measure", "measure/vndf_measure", "measure/ensemble_g2_vndf", "measure/estimator_steps"]
BELOW = {  # component -> entry points it must not include
    "measure/g2_result": ["measure/g2_measure", "measure/g2_estimator"],
    "measure/vndf_result": ["measure/vndf_measure", "measure/vndf_estimator"],
    "measure/g2_estimator": ["measure/g2_measure", "measure/ensemble_estimators"],
    "measure/vndf_estimator": ["measure/vndf_measure", "measure/ensemble_estimators"],
    "measure/estimator_steps": ["measure/g2_measure", "measure/vndf_measure"],
}


def problems(root):
    graph = include_cycles.component_graph(root)
    found = []
    for group in include_cycles.strongly_connected(graph):
        touched = [c for c in group if c in LAYERED]
        if touched:
            found.append("include cycle through %s: %s" % (", ".join(touched), " <-> ".join(group)))
    for low, highs in BELOW.items():
        for high in highs:
            if high in graph.get(low, set()):
                found.append("%s includes %s" % (low, high))
    return found


def synthetic_cycle_is_caught():
    with tempfile.TemporaryDirectory() as d:
        root = pathlib.Path(d)
        (root / "include/microsim/measure").mkdir(parents=True)
        (root / "src/measure").mkdir(parents=True)
        (root / "include/microsim/measure/g2_measure.hpp").write_text("#pragma once\n")
        (root / "src/measure/g2_measure.cpp").write_text('#include "estimator_steps.hpp"\n')
        (root / "src/measure/estimator_steps.hpp").write_text('#include "microsim/measure/g2_measure.hpp"\n')
        found = problems(root)
        return any("include cycle" in p for p in found) and any("estimator_steps includes" in p for p in found)


def main():
    if not synthetic_cycle_is_caught():
        print("the check misses a synthetic cycle estimator_steps <-> g2_measure")
        return 1
    found = problems(ROOT)
    for p in found:
        print(p)
    print("%d problems" % len(found))
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
