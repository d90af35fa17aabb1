#!/usr/bin/python3
"""The study pages' heading rules (analysis/study_page.py): one title, no skipped level."""
import subprocess
import sys
from pathlib import Path

tool = Path(__file__).resolve().parent.parent / "analysis" / "study_page.py"
study = "\n".join(["# Study title", "### deep first", "text", "# second grid", "##### deeper", "```", "# not a heading", "```"])
page = subprocess.run([sys.executable, str(tool), "Page", "study_x"], input=study, text=True,
                      capture_output=True, check=True).stdout
headings = [l for l in page.splitlines() if l.startswith("#")]
expected = ["# Page", "## Study title", "### deep first", "## second grid", "### deeper", "# not a heading"]
if headings != expected:
    sys.exit(f"headings {headings}, expected {expected}")
single = subprocess.run([sys.executable, str(tool), "Page", "study_x"], input="# Own title\n## a\n", text=True,
                        capture_output=True, check=True).stdout
if [l for l in single.splitlines() if l.startswith("#")] != ["# Page", "## a"]:
    sys.exit("a study's sole title must give way to the page title:\n" + single)
commented = subprocess.run([sys.executable, str(tool), "Page", "study_x"],
                           input="# Own title\n## a\n## b\n```sh\n# long example\nrun\n```\n", text=True,
                           capture_output=True, check=True).stdout
if [l for l in commented.splitlines() if l.startswith("#")] != ["# Page", "## a", "## b", "# long example"]:
    sys.exit("a comment in a fenced block is not a second title:\n" + commented)
print("study pages: headings ok")
