"""Sphinx configuration of the nfs-startup documentation.

Build from the repository root (what ``.ci/run`` does)::

    python -m sphinx -W --keep-going -b html docs docs/_build/html

The site documents the checkout it lives in: the repository root goes first on
``sys.path``. The API reference lists what each package exports (its ``__all__``), read at
build time by the ``nfs-exports`` directive below, so a module moved between files inside a
package changes nothing here.
"""

from __future__ import annotations

import functools
import importlib
import inspect
import os
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ.setdefault("MPLBACKEND", "Agg")
# one BLAS thread per process: the gallery's small fits gain nothing from more on 2 cores
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import nfs  # noqa: E402

project = "nfs-startup"
author = "the nfs-startup authors"
copyright = "the nfs-startup authors"
release = nfs.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "auto_examples/*.ipynb", "auto_examples/*.py",
                    "auto_examples/*.zip", "auto_examples/*.json", "auto_examples/*.md5",
                    "**.ipynb_checkpoints"]
templates_path: list[str] = []

# -- MyST: the user guide pages are Markdown that reads the same on GitHub ------------------
myst_heading_anchors = 4
# $...$ and $$...$$ math (GitHub renders the same); a display equation carries its own number,
# \tag{2.4}, the number the code cites ("docs/physics.md (2.4)"). Its rows are separated with
# \cr, not \\, which Sphinx would wrap in a split environment that refuses the \tag.
myst_enable_extensions = ["colon_fence", "dollarmath", "amsmath"]
# An unlabelled code block (a docstring's literal block) is not highlighted, never guessed as
# Python; the pages label theirs: ```text for a program's printout (wrapped, nfs.css), ```sh
# for commands, ```none for data
highlight_language = "none"

# -- autodoc / numpydoc ---------------------------------------------------------------------
autodoc_default_options = {"member-order": "bysource"}
autodoc_typehints = "none"          # numpydoc's parameter lists carry the types and units
autosummary_generate = False        # the API pages list each package's __all__ themselves
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_attributes_as_param_list = True
# scikit-learn's generated metadata-routing methods are documented by scikit-learn
_SKLEARN_MEMBERS = {"set_fit_request", "set_predict_request", "set_score_request",
                    "set_partial_fit_request", "set_transform_request",
                    "get_metadata_routing", "set_output"}

# -- sphinx-gallery -------------------------------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples" / "gallery"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "ignore_pattern": r"__init__\.py",
    "download_all_examples": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "show_memory": False,
}

# -- HTML -----------------------------------------------------------------------------------
html_theme = "alabaster"
html_theme_options = {
    "description": "Start-up experiments on FOG north finders",
    "fixed_sidebar": True,
    # at a 1280 px window the text column is 960 px: an 88-character code line fits
    # (docs/_static/nfs.css scrolls what does not); below 1240 px the narrow layout
    "page_width": "1240px",
    "sidebar_width": "220px",
    "body_max_width": "none",
}
html_static_path = ["_static"]
html_css_files = ["nfs.css"]
html_title = f"nfs-startup {release}"


# -- the API reference: a package's exports, read from its __all__ --------------------------

def _bindings(package, name, obj):
    """(module, name) of every module of the project whose top level binds ``obj``: first
    those binding it under ``name``, then those inside ``package`` (a constant is often
    imported where it is used, and re-exported from another subpackage)."""
    top = package.__name__.split(".")[0]
    found = [(modname, key) for modname, mod in sorted(sys.modules.items())
             if (modname == top or modname.startswith(top + ".")) and mod is not None
             for key, value in list(vars(mod).items()) if value is obj]

    def inside(modname):
        return modname == package.__name__ or modname.startswith(package.__name__ + ".")
    return sorted(found, key=lambda pair: (pair[1] != name, not inside(pair[0])))


def _data_doc(package, name, obj) -> list[str]:
    """The ``#:`` comment or docstring of a re-exported constant, from the module defining it."""
    from sphinx.pycode import ModuleAnalyzer

    for modname, key in _bindings(package, name, obj):
        try:
            docs = ModuleAnalyzer.for_module(modname).find_attr_docs()
        except Exception:  # pragma: no cover - a module without source
            continue
        if ("", key) in docs:
            return list(docs[("", key)])
    return []


@functools.cache
def _exported_by_subpackages() -> frozenset[int]:
    """The ids of the objects that the API pages of packages other than ``nfs`` document
    (every ``.. nfs-exports::`` in docs/api names one)."""
    ids = set()
    for page in sorted((Path(__file__).parent / "api").glob("*.rst")):
        for modname in re.findall(r"^\.\. nfs-exports:: (\S+)",
                                  page.read_text(encoding="utf-8"), flags=re.M):
            if modname != "nfs":
                mod = importlib.import_module(modname)
                ids |= {id(getattr(mod, n)) for n in getattr(mod, "__all__", ())}
    return frozenset(ids)


def _documented_elsewhere(name: str) -> bool:
    """``nfs.<name>`` is an object a subpackage's API page documents (and indexes) too."""
    return id(getattr(nfs, name)) in _exported_by_subpackages()


def _source_module(app, modname, attribute):
    """viewcode: the module whose source holds the object documented as ``modname.attribute``.

    A class or function: the module defining it. A re-export of the top-level package that a
    subpackage's page documents (``:no-index:`` on the nfs page): the package itself, whose
    ``__init__`` defines no such object, so that only the page with the object's anchor gets
    a ``[source]`` link and the source's ``[docs]`` link lands on it. Anything else (a
    constant): its documented module, which shows no source for it, instead of the module of
    the value's type (a tuple's is ``builtins``, a page that viewcode never writes).
    """
    if not modname or not modname.split(".")[0] in ("nfs", "thermal"):
        return None
    try:
        obj = getattr(importlib.import_module(modname), attribute.split(".")[0])
    except (ImportError, AttributeError):
        return modname
    if modname == "nfs" and _documented_elsewhere(attribute.split(".")[0]):
        return modname
    if inspect.isclass(obj) or inspect.isroutine(obj):
        return obj.__module__
    return modname


def _export_rst(modname: str) -> list[str]:
    """reST documenting every name in ``modname.__all__``: a summary, then each object."""
    mod = importlib.import_module(modname)
    names = list(getattr(mod, "__all__", ()))
    lines = [f".. currentmodule:: {modname}", "", ".. autosummary::", "   :nosignatures:", ""]
    lines += [f"   {n}" for n in names if n != "__version__"] + [""]
    for n in names:
        obj = getattr(mod, n)
        # the top-level package re-exports names its subpackages document: list them there
        # without indexing them twice (what only the top level exports is indexed here)
        opts = ["   :no-index:"] if modname == "nfs" and _documented_elsewhere(n) else []
        if n == "__version__":
            lines += [".. py:data:: __version__", "",
                      "   The installed package's version (``nfs-startup``).", ""]
        elif inspect.isclass(obj) and issubclass(obj, BaseException):
            lines += [f".. autoexception:: {modname}.{n}", "   :show-inheritance:", *opts, ""]
        elif inspect.isclass(obj):
            lines += [f".. autoclass:: {modname}.{n}", "   :members:", *opts, ""]
        elif callable(obj) and not isinstance(obj, (dict, list, tuple)):
            lines += [f".. autofunction:: {modname}.{n}", *opts, ""]
        else:
            doc = _data_doc(mod, n, obj)
            # the name is relative to the current module: ``nfs.effects.KINDS``
            lines += [f".. py:data:: {n}", *opts, ""]
            lines += [f"   {d}" if d.strip() else "" for d in doc] + [""]
    return lines


def _constant_summary(app, what, name, obj, options, lines):
    """autosummary's line for a constant: its ``#:`` comment, not its type's docstring.

    A re-exported constant's comment sits in the module that defines it, where autodoc,
    reading the package, does not look: the summary table would show ``str(object='') ->
    str`` for a string constant.
    """
    if what != "data" or type(obj).__module__ != "builtins":
        return              # a constant of a type of ours documents itself
    modname, _, attr = name.rpartition(".")
    try:
        package = importlib.import_module(modname)
    except ImportError:
        return
    lines[:] = _data_doc(package, attr, obj)   # nothing rather than the type's docstring


def setup(app):
    from docutils.statemachine import StringList
    from sphinx.util.docutils import SphinxDirective

    class Exports(SphinxDirective):
        """``.. nfs-exports:: nfs.compensate``: document what the package exports."""

        required_arguments = 1
        has_content = False

        def run(self):
            from docutils import nodes

            text = _export_rst(self.arguments[0])
            container = nodes.container()
            self.state.nested_parse(StringList(text, source=f"<{self.arguments[0]}.__all__>"),
                                    self.content_offset, container, match_titles=True)
            return container.children

    app.add_directive("nfs-exports", Exports)
    app.connect("viewcode-follow-imported", _source_module)
    app.connect("autodoc-process-docstring", _constant_summary)
    app.connect("autodoc-skip-member",
                lambda app, what, name, obj, skip, options:
                True if name in _SKLEARN_MEMBERS else None)
    return {"parallel_read_safe": True}
