"""Sphinx configuration of the user guide: MyST Markdown pages, the PyData theme, the CLI
reference from the argparse parser (sphinx-argparse) and the reference pages written from
the code (_ext/reference.py). Build: sphinx-build -W -b html docs docs/_build/html"""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent / "_ext"))

project = "ballaststudy"
author = "the ballaststudy developers"
copyright = "2026, the ballaststudy developers"
extensions = ["myst_parser", "sphinxarg.ext", "reference"]
myst_enable_extensions = ["dollarmath", "amsmath", "deflist"]
myst_heading_anchors = 3
source_suffix = {".md": "markdown"}
# thesis-scale/parts, thesis-scale/differences: the records of the study's and the screening's
# parts (their README.md and differences.md are the pages); splitting-plan.md: the design
# notes the splitting stones were built from (a developer's page)
exclude_patterns = ["_build", "thesis-scale/parts", "thesis-scale/differences", "stone-models/splitting-plan.md"]
html_theme = "pydata_sphinx_theme"
html_title = "ballaststudy"
html_theme_options = {"navigation_depth": 2, "show_toc_level": 2}
