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


def _no_type_docstrings(app, what, name, obj, options, lines):
    """A constant re-exported from a private module has no doc comment where autodoc looks
    (its text is in api.rst); the docstring of its type (tuple, str, CentralityCache) is not
    about it and is dropped."""
    import inspect

    doc = type(obj).__doc__
    first = inspect.cleandoc(doc).strip().splitlines()[0] if isinstance(doc, str) and doc.strip() else None
    if what == "data" and first and any(line.strip() == first for line in lines):
        lines.clear()


def setup(app):
    app.connect("autodoc-process-docstring", _no_type_docstrings, priority=400)  # before numpydoc
