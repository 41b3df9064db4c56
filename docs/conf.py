"""Sphinx configuration of fempipe's documentation.

Build (warnings are errors)::

    python -m sphinx -W -b html docs docs/_build/html

Generated at build time, ignored by git: the main job's files (``_generated/``, the
README's main command, whose figure the getting-started page shows), the API stubs
(``api/generated/``),
one page per validation case from the committed report (``report/``, by
``_ext/validation_report.py``), and the sphinx-gallery output of ``examples/``
and ``course/`` (``gallery/``, ``lessons/``).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
# The package of this tree, not an installed copy of another version.
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(DOCS / "_ext"))
os.environ.setdefault("MPLBACKEND", "Agg")

from fempipe.core.version import __version__  # noqa: E402

project = "fempipe"
author = "fempipe authors"
copyright = "2026, fempipe authors"
release = __version__
version = __version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    # MathJax served from the built site (_static/mathjax), not from a CDN: the pages'
    # equations render offline.
    "sphinx-mathjax-offline",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    "sphinxarg.ext",
    "myst_parser",
    "validation_report",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = [
    "_build",
    "**/GALLERY_HEADER.rst",
    "**.ipynb_checkpoints",
    "sg_execution_times.rst",
    "**/sg_execution_times.rst",
]
templates_path = ["_templates"]

# -- MyST: the pages moved from the README are Markdown ----------------------
myst_enable_extensions = ["dollarmath", "colon_fence"]
# Links to sections such as [Error estimates](options.md#error-estimates---error-estimate).
myst_heading_anchors = 3

# -- autodoc, autosummary, numpydoc ------------------------------------------
autosummary_generate = True
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types
autodoc_member_order = "bysource"
numpydoc_show_class_members = False  # the class pages list their members via autodoc
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# -- sphinx-gallery: the example gallery and the course ----------------------
# The sources live in ../examples (plot_*.py) and course/ (lesson_*.py); a
# missing source folder is skipped, so the site builds with or without them.
_GALLERIES = [("../examples", "gallery"), ("course", "lessons")]
_present = [(src, out) for src, out in _GALLERIES if (DOCS / src).is_dir()]
sphinx_gallery_conf = {
    "examples_dirs": [src for src, _ in _present],
    "gallery_dirs": [out for _, out in _present],
    "filename_pattern": r"/(plot_|lesson_)",  # execute every script
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "matplotlib_animations": False,
    "show_memory": False,
    # its timing pages load jQuery and DataTables from CDNs; the site works offline
    "write_computation_times": False,
    # The notebooks offered for download: pandoc (pypandoc-binary, in the docs extra)
    # converts the RST text to Markdown, maths and collapsed solutions included; the
    # filter turns Sphinx roles (:class:, :func:, :doc:) into code and plain text.
    "pypandoc": {"filters": [str(DOCS / "_ext" / "notebook_markdown.lua")]},
}
#: gallery output folders that exist in this build, for the toctree of index.rst
gallery_indexes = [f"{out}/index" for _, out in _present]

# -- HTML ---------------------------------------------------------------------
# No typographic dashes: the CLI reference prints options (--alpha) that readers copy.
smartquotes = False

html_theme = "pydata_sphinx_theme"
html_title = f"fempipe {version}"
html_theme_options = {
    "show_toc_level": 2,
    "navigation_with_keys": False,
    "secondary_sidebar_items": ["page-toc"],
}
html_static_path: list[str] = []
# The theme's left sidebar lists the pages under the current top-level page; the top-level
# pages without any would show an empty "Section Navigation" box.
html_sidebars = {
    page: [] for page in ("index", "getting_started", "glossary", "verification", "development")
}
html_show_sourcelink = False


def _gallery_toctree(app, docname, source):
    """Fill the ``GALLERY-TOCTREE`` placeholder of index.rst with the built galleries."""
    if docname != "index":
        return
    entries = "".join(f"   {name}\n" for name in gallery_indexes)
    block = (
        f".. toctree::\n   :maxdepth: 1\n   :caption: Examples and course\n\n{entries}"
        if entries
        else ""
    )
    source[0] = source[0].replace(".. GALLERY-TOCTREE\n", block)


def _main_job_figure(app) -> None:
    """Run the README's main command into ``_generated/main_job/``: the getting-started
    page shows the figure it writes (``shapes.png``), made by the code being documented."""
    import shlex

    from fempipe.cli import main

    text = (ROOT / "README.md").read_text(encoding="utf-8")
    line = text.split("<!-- main-command -->")[1].split("<!-- /main-command -->")[0]
    command = line.strip().strip("`").strip().splitlines()[-1].split("&& fempipe ", 1)[1]
    argv = shlex.split(command)
    argv = argv[: argv.index("--out")] + ["--out", str(DOCS / "_generated" / "main_job")]
    if main([*argv, "--quiet"]) != 0:
        raise RuntimeError(f"the README's main command failed: fempipe {command}")


def setup(app):
    app.connect("builder-inited", _main_job_figure)
    app.connect("source-read", _gallery_toctree)
