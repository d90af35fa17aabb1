#!/usr/bin/env python3
"""The source tools measure what they claim: tools/function_lengths.py finds a function's first
and last line (a multi-line signature, a constructor with brace initializers, braces in strings
and comments) and tools/include_cycles.py finds a two-header cycle and nothing in a chain, and a
lower layer's header or source including an upper layer's (and not the reverse)."""
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
import function_lengths  # noqa: E402
import include_cycles  # noqa: E402

SAMPLE = '''namespace a {
struct S {
  int x{1};
  int get() const {
    return x;
  }
};
S::S(int v)
    : x{v}, y(2) {
  const char* s = "}{";  // }
}
int long_one(int a,
             int b) {
  auto f = [&](int c) {
    return c;
  };
  /* { */
  return f(a) + b;
}
}  // namespace a
'''


def check(condition, what):
    if not condition:
        print("FAIL:", what)
        sys.exit(1)


def main():
    found = {name: (first, last) for first, last, name in function_lengths.functions_of(SAMPLE)}
    check(found.get("get") == (4, 6), f"inline member function lines: {found}")
    check(found.get("S::S") == (8, 11), f"constructor with brace initializer: {found}")
    check(found.get("long_one") == (12, 19), f"multi-line signature with a lambda: {found}")
    check(len(found) == 3, f"exactly three functions: {found}")

    with tempfile.TemporaryDirectory() as d:
        root = pathlib.Path(d)
        inc = root / "include" / "microsim" / "x"
        inc.mkdir(parents=True)
        (root / "src" / "x").mkdir(parents=True)
        (inc / "a.hpp").write_text('#include "microsim/x/b.hpp"\n')
        (inc / "b.hpp").write_text("\n")
        (inc / "c.hpp").write_text('#include "microsim/x/a.hpp"\n')
        check(include_cycles.strongly_connected(include_cycles.component_graph(root)) == [],
              "a chain c -> a -> b is no cycle")
        (root / "src" / "x" / "b.cpp").write_text('#include "microsim/x/b.hpp"\n#include "microsim/x/a.hpp"\n')
        cycles = include_cycles.strongly_connected(include_cycles.component_graph(root))
        check(cycles == [["x/a", "x/b"]], f"b's source including a closes a cycle: {cycles}")
        failing = subprocess.run([sys.executable, str(ROOT / "tools" / "include_cycles.py"), "--root", d, "--fail"],
                                 capture_output=True, text=True)
        check(failing.returncode == 1, "--fail exits 1 on a cycle")
        guarded = [sys.executable, str(ROOT / "tools" / "include_cycles.py"), "--root", d, "--fail-touching"]
        check(subprocess.run(guarded + ["x"], capture_output=True).returncode == 1,
              "--fail-touching x exits 1 on a cycle in x")
        check(subprocess.run(guarded + ["y"], capture_output=True).returncode == 0,
              "--fail-touching y ignores a cycle in x")
        # A layer rule: a lower directory's header or source including an upper one's fails,
        # the upper including the lower does not.
        for d_ in ("include/microsim/low", "include/microsim/up", "src/low", "src/up"):
            (root / d_).mkdir(parents=True)
        (root / "include/microsim/up/req.hpp").write_text('#include "microsim/low/est.hpp"\n')
        (root / "include/microsim/low/est.hpp").write_text("\n")
        (root / "src/up/local.hpp").write_text("\n")
        layered = [sys.executable, str(ROOT / "tools" / "include_cycles.py"), "--root", d,
                   "--forbid-includes", "low,other", "up"]
        check(subprocess.run(layered, capture_output=True).returncode == 0, "an upper layer may include a lower one")
        (root / "src/low/est.cpp").write_text('#include "microsim/low/est.hpp"\n#include "../up/local.hpp"\n')
        broken = subprocess.run(layered, capture_output=True, text=True)
        check(broken.returncode == 1 and "src/low/est.cpp includes ../up/local.hpp" in broken.stdout,
              f"a lower source including an upper src-local header fails: {broken.stdout}")
        (root / "src/low/est.cpp").write_text('#include "microsim/low/est.hpp"\n')
        (root / "include/microsim/low/est.hpp").write_text('#include "microsim/up/req.hpp"\n')
        broken = subprocess.run(layered, capture_output=True, text=True)
        check(broken.returncode == 1 and "include/microsim/low/est.hpp includes microsim/up/req.hpp" in broken.stdout,
              f"a lower header including an upper one fails: {broken.stdout}")
        # Includes through "../" name the file they reach: a cycle through them is found.
        for d_ in ("src/z", "src/z2"):
            (root / d_).mkdir(parents=True)
        (root / "src/z/p.hpp").write_text('#include "../z2/q.hpp"\n')
        (root / "src/z2/q.hpp").write_text('#include "../z/p.hpp"\n')
        cycles = include_cycles.strongly_connected(include_cycles.component_graph(root))
        check(["z/p", "z2/q"] in cycles, f"a cycle through ../ includes is found: {cycles}")
        long_file = root / "src" / "x" / "long.cpp"
        long_file.write_text("int f() {\n" + "  ;\n" * 90 + "}\n")
        over = subprocess.run([sys.executable, str(ROOT / "tools" / "function_lengths.py"), "3", "--root", d,
                               "--limit", "80", "--fail"], capture_output=True, text=True)
        check(over.returncode == 1 and "92 src/x/long.cpp:1 f" in over.stdout,
              f"--fail exits 1 on a 92-line function: {over.stdout}")
    print("source tools: ok")


if __name__ == "__main__":
    main()
