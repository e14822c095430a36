"""Sphinx configuration of flipstudy's documentation.

Build (offline, warnings as errors; the gallery scripts run during the build)::

    pip install -e '.[docs]'
    python -m sphinx -W --keep-going -b html docs docs/_build/html
"""
import os
import sys
from pathlib import Path

# the gallery renders offscreen (VTK through EGL) and draws with matplotlib's Agg
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
os.environ.setdefault("MPLBACKEND", "Agg")
sys.path.insert(0, str(Path(__file__).parent / "_ext"))

import flipstudy  # noqa: E402

project = "flipstudy"
author = "the flipstudy authors"
copyright = "flipstudy authors, MIT licence"
version = release = flipstudy.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "flipstudy_formats",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "examples/*.py", "examples/README.txt"]
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3
suppress_warnings = ["myst.header"]   # the guide pages keep the README's heading levels

autosummary_generate = True
autosummary_imported_members = True
autodoc_default_options = {"members": False}
numpydoc_show_class_members = False
numpydoc_xref_param_type = False
# every public function and class on the API page has an Examples section (numpydoc
# validation, as tests/stimuli/test_docstrings.py checks without Sphinx); their methods
# and properties (Class.member) and the module constants (ALL_CAPS, documented by their
# ``#:`` comment) are not validated
numpydoc_validation_checks = {"EX01"}
numpydoc_validation_exclude = {r"\.[A-Z]\w*\.\w+$", r"\.[A-Z][A-Z0-9_]+$"}

sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    # the comparison example makes a study's sources from the CMU clips (minutes, ../shared):
    # run by hand and by tests/study/test_compare_example.py, not by the docs build
    "ignore_pattern": r"__init__\.py|compare_models\.py",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
    "show_memory": False,
    "min_reported_time": 0,
}

html_theme = "pydata_sphinx_theme"
html_title = "flipstudy"
html_static_path = []
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "navbar_end": ["theme-switcher", "navbar-icon-links"],
}
html_show_sourcelink = False


# --- the API page lists every public name: written at each build from the code ---------
STABLE = ["load_bvh", "save_bvh", "builtin", "analyse", "Clip", "Body", "FlipstudyError"]
PARTS = [("flipstudy", "Stable entry points", STABLE),
         ("flipstudy.stimuli", "Stimuli: motion in, stimuli out", None),
         ("flipstudy.render", "Render: offscreen PyVista", None),
         ("flipstudy.analysis", "Analysis: ratings, d′, psychometric fits", None)]


def write_api_page(app, config=None):
    """docs/reference/api.rst from the stable entry points and each part's ``__all__``
    (a name the root already lists is listed once), so a new public name appears
    without editing the docs."""
    import importlib
    out = ["API reference", "=============", "",
           "Generated from the docstrings (numpydoc). The stable entry points are at the",
           "package root; each part exports the names in its ``__all__`` (the stable",
           "entry points that :mod:`flipstudy.stimuli` also exports are listed once, at the root).",
           ""]
    for mod, title, names in PARTS:
        m = importlib.import_module(mod)
        names = names or [n for n in m.__all__ if n not in STABLE]
        out += [title, "-" * len(title), "", f".. currentmodule:: {mod}", "",
                ".. autosummary::", "   :toctree: generated", "   :nosignatures:", ""]
        out += [f"   {n}" for n in names] + [""]
    page = Path(app.srcdir) / "reference" / "api.rst"
    text = "\n".join(out)
    if not page.is_file() or page.read_text() != text:
        page.write_text(text)


def setup(app):
    # before the source files are found and autosummary generates the stub pages from it
    app.connect("config-inited", write_api_page)
