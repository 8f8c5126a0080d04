"""Sphinx configuration: the API reference from the docstrings (numpydoc) and the user
guides (Markdown, MyST). Built with warnings as errors by tests/docs/test_docs.py:

    .venv/bin/python -m sphinx -W --keep-going -b html docs docs/_build/html
"""
import impactlib

project = "Impact Explorer"
author = "Impact Explorer contributors"
release = version = impactlib.__version__
extensions = ["sphinx.ext.autodoc", "sphinx.ext.autosummary", "numpydoc", "myst_parser"]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "notebooks", "screenshots"]
autodoc_member_order = "bysource"
autodoc_default_options = {"members": False}
numpydoc_show_class_members = False
numpydoc_validation_checks = set()
myst_heading_anchors = 3
html_theme = "alabaster"
suppress_warnings = ["myst.xref_missing"]
