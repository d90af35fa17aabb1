# Sphinx configuration of the microsim documentation (Markdown pages read by MyST, furo theme).
# Build: python3 -m sphinx -W --keep-going -b html docs OUT   (CTest `docs_site` does the same).
# Nothing is fetched from the network: no intersphinx, no remote images, the theme's own assets.

project = "microsim"
author = "the microsim developers"
copyright = "the microsim developers"
release = "0.1.0"
version = release

extensions = ["myst_parser"]
source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "img/README*"]

# Section anchors for links such as [columns](measure.md#columns), up to level-3 headings.
myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath", "deflist"]

html_theme = "furo"
html_title = "microsim"
html_static_path = []
html_last_updated_fmt = None
html_show_sourcelink = False

# Code blocks: `sh` blocks are commands (run by the docs test), `text` blocks are output.
highlight_language = "none"
