"""Sphinx configuration of warpbem's documentation (built by ``tests/docs/test_docs.py`` with
warnings as errors; by hand: ``python -m sphinx -W -b html docs docs/_build``)."""

import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "docs" / "_ext"))  # options_table: the options' tables in the API reference

project = "warpbem"
author = "the warpbem developers"
copyright = "2026, the warpbem developers"
extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.napoleon", "options_table"]
source_suffix = {".md": "markdown"}
root_doc = "index"
# figures/ holds charts and their data (and one working note) that the pages show, not pages
exclude_patterns = ["_build", "_ext", "figures/*.md", "figures/**"]
myst_heading_anchors = 3
autodoc_member_order = "bysource"
autodoc_typehints = "description"
napoleon_google_docstring = True
napoleon_numpy_docstring = True
html_theme = "alabaster"
html_static_path = []
# the pages quote code paths of the checkout (`scenes/...`, `warpbem/...`) as text; links
# between pages are checked (warnings are errors)
suppress_warnings = []
