"""Sphinx configuration: API reference from the numpydoc docstrings, built with warnings as errors."""

from importlib.metadata import version as _version

project = "centrality-vision"
author = "centrality-vision developers"
copyright = "2026, centrality-vision developers (BSD-3-Clause)"
release = _version("centrality-vision")
version = release

extensions = ["sphinx.ext.autodoc", "sphinx.ext.mathjax", "sphinx.ext.viewcode", "numpydoc"]

# numpydoc renders Parameters/Returns/Examples; autodoc follows each module's __all__.
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
# scikit-learn generates set_*_request methods on every estimator: they are not ours to document.
_SKLEARN_REQUESTS = ",".join(
    f"set_{m}_request" for m in ("fit", "transform", "predict", "score", "partial_fit", "split")
)
autodoc_default_options = {"members": True, "show-inheritance": False, "exclude-members": _SKLEARN_REQUESTS}
autodoc_member_order = "bysource"
autodoc_typehints = "none"  # the docstrings carry the types

exclude_patterns = ["_build"]
html_theme = "alabaster"
html_static_path = []
nitpicky = False
