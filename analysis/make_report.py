#!/usr/bin/python3
"""Builds the microsim validation report from scratch: runs the validation suite and the
measurements behind the figures, draws the figures (PNG) and writes OUT/index.html.

    analysis/make_report.py --out report/                 # the default report (<= 10 min, 2 cores)
    analysis/make_report.py --out /tmp/r --profile smoke  # seconds: the CTest smoke test
    analysis/make_report.py --out report/ --figures docs/img/findings  # also the findings pages' figures

Exit code: 0 when the report was built and every exact identity passed; 1 when an identity
FAILED or a section's command failed (the page is still written, with the failing rows and
sections in red), or when the validation run itself failed; 2 for bad arguments. Needs Debian's python3-numpy, python3-matplotlib and python3-openimageio.
"""
import argparse
import os
import shutil
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from msreport import report  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def find_microsim(given):
    if given:
        return given
    for cand in (os.path.join(ROOT, "build", "microsim"), shutil.which("microsim")):
        if cand and os.path.isfile(cand) and os.access(cand, os.X_OK):
            return cand
    return None


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, help="report folder (created; index.html, figures/, data/)")
    ap.add_argument("--microsim", help="the microsim binary (default: build/microsim, then PATH)")
    ap.add_argument("--profile", choices=sorted(report.PROFILES), default="default",
                    help="run sizes: default (the full report) or smoke (seconds)")
    ap.add_argument("--threads", type=int, help="worker threads for microsim (default: all cores)")
    ap.add_argument("--figures", metavar="DIR",
                    help="also write the figures of the documentation's findings pages into DIR "
                         "(stable names, palette PNGs; the default profile draws all of them)")
    ap.add_argument("--quiet", action="store_true", help="print only errors and the final line")
    args = ap.parse_args(argv)

    microsim = find_microsim(args.microsim)
    if not microsim or not os.path.isfile(microsim):
        print("make_report: error: --microsim: no microsim binary found (build it, or pass --microsim PATH)",
              file=sys.stderr)
        return 2
    if args.threads is not None and args.threads < 1:
        print("make_report: error: --threads must be >= 1", file=sys.stderr)
        return 2
    out = os.path.abspath(args.out)
    # From scratch: the data and figures of an earlier build are removed first.
    for sub in ("data", "figures"):
        shutil.rmtree(os.path.join(out, sub), ignore_errors=True)
    os.makedirs(out, exist_ok=True)
    ctx = report.Context(os.path.abspath(microsim), out, args.profile, args.threads, verbose=not args.quiet)
    try:
        sections, wall = report.build(ctx)
    except RuntimeError as e:
        print("make_report: failed: %s" % e, file=sys.stderr)
        return 1
    page = report.write_html(ctx, sections, wall)
    missing = [p for s in sections for p, _ in s.figures if not os.path.isfile(os.path.join(out, p))]
    if missing:
        print("make_report: failed: figures missing: %s" % ", ".join(missing), file=sys.stderr)
        return 1
    nfig = sum(len(s.figures) for s in sections)
    skipped = [s.key for s in sections if s.skipped]
    print("wrote %s: %d figures in %.0f s%s" % (page, nfig, wall,
                                                "; skipped: " + ", ".join(skipped) if skipped else ""))
    if args.figures:
        try:
            written = report.export_figures(ctx, os.path.abspath(args.figures))
        except RuntimeError as e:
            print("make_report: failed: %s" % e, file=sys.stderr)
            return 1
        print("wrote %d figures into %s" % (len(written), args.figures))
    failed = [s.key for s in sections if s.failed]
    if failed:
        print("make_report: sections failed (see the page): %s" % ", ".join(failed), file=sys.stderr)
    if ctx.validation_failed:
        print("make_report: exact identities FAILED (see the validation table)", file=sys.stderr)
    return 1 if failed or ctx.validation_failed else 0


if __name__ == "__main__":
    sys.exit(main())
