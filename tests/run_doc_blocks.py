#!/usr/bin/env python3
"""Runs the commands the documentation shows: every fenced code block whose language is `sh`
in README.md and docs/**/*.md.

Each page runs in a fresh temporary folder, its blocks in order in one bash process (so that a
block may use the files and variables of the blocks above it) under `set -euo pipefail`, with
the build's `microsim` first on PATH, then `python3` (the interpreter running this script), the
build's Python module on PYTHONPATH and the repository's surfaces/ folder reachable as
`surfaces/`. A page stops at its first failing block.

Skipped: blocks containing `apt-get` (installing packages is not the documentation's to test)
and blocks whose first line is `# long example`; with --long, the pages holding long examples
run instead, each whole (its earlier blocks set the long example up) and nothing else.

Prints per page the blocks run, skipped and failed (with the failing command and its stderr),
and last `N passed, M failed`; exits 1 when a block failed or a page ran out of time.
Python standard library only.
"""
import argparse
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

LONG_MARK = "# long example"
FENCE = re.compile(r"^(?P<indent>\s*)(?P<fence>`{3,}|~{3,})\s*(?P<info>[^`]*?)\s*$")


class Block:
    def __init__(self, line, text):
        self.line = line  # line number of the opening fence (1-based)
        self.text = text

    @property
    def long(self):
        lines = self.text.strip().splitlines()
        return bool(lines) and lines[0].strip() == LONG_MARK

    @property
    def installs(self):
        return "apt-get" in self.text


def sh_blocks(markdown):
    """The fenced blocks of language `sh`, in page order (fences nested in longer fences and
    indented blocks in list items are handled; the fence's indentation is removed)."""
    blocks, lines, k = [], markdown.splitlines(), 0
    while k < len(lines):
        m = FENCE.match(lines[k])
        if not m:
            k += 1
            continue
        fence, indent = m.group("fence"), len(m.group("indent"))
        language = m.group("info").split()[0] if m.group("info").split() else ""
        start, body, k = k + 1, [], k + 1
        while k < len(lines):
            close = lines[k].strip()
            if close and set(close) == {fence[0]} and len(close) >= len(fence):
                break
            body.append(lines[k][indent:] if lines[k][:indent].strip() == "" else lines[k].lstrip())
            k += 1
        k += 1
        if language == "sh":
            blocks.append(Block(start, "\n".join(body) + "\n"))
    return blocks


def pages(root):
    found = [root / "README.md"] if (root / "README.md").is_file() else []
    docs = root / "docs"
    if docs.is_dir():
        for p in sorted(docs.rglob("*.md")):
            # Build output and hidden folders are not pages.
            if any(part.startswith(("_", ".")) for part in p.relative_to(docs).parts[:-1]):
                continue
            found.append(p)
    return found


def page_script(blocks, state):
    """One bash script running the blocks in order; before each block, its number and a fresh
    stdout/stderr file in `state`, so that the failing block and its output are known. Also
    returns, for each line of the script, the line of the page it comes from (or None)."""
    parts = [
        "set -euo pipefail",
        f"trap 'echo \"$BASH_COMMAND\" > \"{state}/failed_command\"' ERR",
    ]
    page_line = [None, None]
    for n, b in enumerate(blocks):
        parts.append(f'echo {n} > "{state}/block"; exec > "{state}/out.{n}" 2> "{state}/err.{n}"')
        page_line.append(None)
        parts.append(b.text.rstrip("\n"))
        page_line += [b.line + 1 + k for k in range(len(b.text.rstrip("\n").splitlines()))]
    parts.append(f'echo done > "{state}/block"')
    return "\n".join(parts) + "\n", page_line


def page_lines(text, script, page_line, page):
    """bash's `SCRIPT: line N:` in messages as the page's file and line."""
    def to_page(m):
        n = int(m.group(1))
        line = page_line[n - 1] if 0 < n <= len(page_line) else None
        return f"{page}: line {line}:" if line else m.group(0)
    return re.sub(re.escape(str(script)) + r": line (\d+):", to_page, text)


def read(path):
    try:
        return Path(path).read_text(errors="replace")
    except OSError:
        return ""


def indented(text, limit=40):
    lines = text.rstrip().splitlines()
    if len(lines) > limit:
        lines = [f"... ({len(lines) - limit} lines above)"] + lines[-limit:]
    return "\n".join("    " + line for line in lines)


def run_page(page, blocks, args, env):
    """Runs `blocks` of one page; returns (passed, failed, messages)."""
    work = Path(tempfile.mkdtemp(prefix="doc-blocks-"))
    state = Path(tempfile.mkdtemp(prefix="doc-blocks-state-"))
    try:
        (work / "surfaces").symlink_to(args.root / "surfaces")
        script = state / "page.sh"
        text, page_line = page_script(blocks, state)
        script.write_text(text)
        proc = subprocess.Popen(["bash", str(script)], cwd=work, env=env, process_group=0,
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        timed_out = False
        try:
            _, bash_err = proc.communicate(timeout=args.timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            _, bash_err = proc.communicate()
            timed_out = True
        reached = read(state / "block").strip()
        if reached == "done" and proc.returncode == 0:
            return len(blocks), 0, []
        n = int(reached) if reached.isdigit() else 0
        b = blocks[n]
        why = f"timed out after {args.timeout} s" if timed_out else f"exit {proc.returncode}"
        command = read(state / "failed_command").strip() or b.text.strip().splitlines()[-1]
        msg = [f"  block {n + 1} (line {b.line}) failed ({why}): {command}"]
        err = page_lines(read(state / f"err.{n}") + bash_err.decode(errors="replace"), script, page_line, page.name)
        if err.strip():
            msg.append("  stderr:\n" + indented(err))
        if n + 1 < len(blocks):
            msg.append(f"  {len(blocks) - n - 1} later block(s) of the page not run")
        return n, 1, msg
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)
            shutil.rmtree(state, ignore_errors=True)
        else:
            print(f"  kept {work} and {state}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", type=Path, default=Path(__file__).resolve().parent.parent,
                    help="repository root (README.md, docs/, surfaces/)")
    ap.add_argument("--bin-dir", type=Path, required=True, help="folder holding the built microsim")
    ap.add_argument("--pythonpath", default="", help="folder of the built Python module")
    ap.add_argument("--long", action="store_true", help="run the pages holding long examples instead")
    ap.add_argument("--timeout", type=float, default=300, help="seconds per page")
    ap.add_argument("--keep", action="store_true", help="keep each page's folder")
    ap.add_argument("pages", nargs="*", type=Path, help="pages to run (default: README.md and docs/**/*.md)")
    args = ap.parse_args()
    args.root = args.root.resolve()
    if not (args.bin_dir / "microsim").exists():
        sys.exit(f"run_doc_blocks: no microsim in {args.bin_dir}")
    # `python3` in a block is this interpreter (the one the build's module is made for).
    python_dir = Path(tempfile.mkdtemp(prefix="doc-blocks-python-"))
    (python_dir / "python3").symlink_to(sys.executable)
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join([str(args.bin_dir.resolve()), str(python_dir), env.get("PATH", "")])
    if args.pythonpath:
        env["PYTHONPATH"] = os.pathsep.join(p for p in (args.pythonpath, env.get("PYTHONPATH", "")) if p)

    passed = failed = skipped = 0
    for page in [p.resolve() for p in args.pages] or pages(args.root):
        blocks = sh_blocks(page.read_text())
        if not blocks:
            continue
        installs = [b for b in blocks if b.installs]
        runnable = [b for b in blocks if not b.installs]
        long_blocks = [b for b in runnable if b.long]
        if args.long and not long_blocks:
            skipped += len(blocks)
            continue
        run = runnable if args.long else [b for b in runnable if not b.long]
        reason = ", ".join(s for s in (f"{len(long_blocks)} long example(s)" if long_blocks and not args.long else "",
                                       f"{len(installs)} with apt-get" if installs else "") if s)
        n_skipped = len(blocks) - len(run)
        name = page.relative_to(args.root) if page.is_relative_to(args.root) else page
        p, f, msg = run_page(page, run, args, env) if run else (0, 0, [])
        passed, failed, skipped = passed + p, failed + f, skipped + n_skipped
        skip_text = f"{n_skipped} skipped" + (f" ({reason})" if reason and n_skipped else "")
        print(f"{name}: {p + f} run, {skip_text}, {f} failed")
        for m in msg:
            print(m)
        sys.stdout.flush()
    shutil.rmtree(python_dir, ignore_errors=True)
    print(f"{skipped} skipped")
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
