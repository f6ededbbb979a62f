"""Sphinx configuration of the documentation site (``python -m sphinx -W -b html docs docs/_build/html``)."""

import re
import types
from pathlib import Path

import jinja2
import sphinx.ext.autosummary
import yaml

import bouncing_ball

DOCS = Path(__file__).resolve().parent
REPOSITORY = DOCS.parent

project = "bouncing-ball"
author = "The bouncing-ball developers"
copyright = "2026, the bouncing-ball developers"
release = bouncing_ball.__version__
version = release

extensions = [
    "myst_nb",  # Markdown pages (MyST) and the tutorial, a text notebook executed at build time
    "numpydoc",  # the API reference from the numpydoc docstrings
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.intersphinx",  # numpy.ndarray, pandas.DataFrame, ... link to their projects' pages
    "sphinx.ext.viewcode",  # each documented name links to its highlighted source
]

# .rst first: autosummary writes its generated pages (reStructuredText) with the first suffix
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb"}
exclude_patterns = ["_build", "_intersphinx", "gallery", "requirements.txt"]
root_doc = "index"

# anchors for the pages' "#section" links, as GitHub makes them
myst_heading_anchors = 4
myst_enable_extensions = ["dollarmath", "colon_fence"]

# the tutorial runs on every build, so it cannot rot; a failing cell fails the build
nb_execution_mode = "force"
nb_execution_timeout = 300
nb_execution_raise_on_error = True
nb_merge_streams = True

autosummary_generate = True
# a module's page (docs/_templates/autosummary/module_page.rst) lists the names of its __all__
autosummary_ignore_module_all = False
templates_path = ["_templates"]
# a summary line of the API tables ends at its first sentence, and "eq. (label)" does not end one
sphinx.ext.autosummary.WELL_KNOWN_ABBREVIATIONS += ("eq.", "eqs.", "Eq.", "Eqs.", "Fig.", "Figs.")
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
# the types of the Parameters and Returns sections link to their documentation (intersphinx below)
numpydoc_xref_param_type = True
numpydoc_xref_aliases = {"DataFrame": "pandas.DataFrame", "mapping": ":term:`python:mapping`"}
numpydoc_xref_ignore = {"of", "or", "optional", "default", "shape", "to"}

# The inventories are files kept in docs/_intersphinx/ (written by make_inventories.py there), not
# fetched: a build reads no network, so it neither waits nor fails where there is none.
intersphinx_mapping = {
    project: (site, str(DOCS / "_intersphinx" / f"{project}.inv"))
    for project, site in {
        "python": "https://docs.python.org/3/",
        "numpy": "https://numpy.org/doc/stable/",
        "scipy": "https://docs.scipy.org/doc/scipy/",
        "pandas": "https://pandas.pydata.org/docs/",
        "matplotlib": "https://matplotlib.org/stable/",
    }.items()
}
intersphinx_timeout = 5  # seconds, for a mapping that names a URL instead of a file

html_theme = "pydata_sphinx_theme"
html_title = f"bouncing-ball {release}"
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2}


# Pages kept outside docs/ (so that they read well where they live) and shown on the site through
# an {include} page; a Markdown link to one of them, from a page or an included file, points to its
# site page instead.
SITE_PAGES = {
    REPOSITORY / "README.md": "index.md",
    REPOSITORY / "config" / "README.md": "config.md",
    REPOSITORY / "profiles" / "slurm" / "README.md": "slurm.md",
    REPOSITORY / "CHANGELOG.md": "changelog.md",
}
_LINK = re.compile(r"\]\(([^)#\s]+\.md)(#[^)\s]*)?\)")


def _site_links(text: str, folder: Path) -> str:
    """``text`` (Markdown in ``folder``) with its links to repository pages made site links."""

    def replace(match: re.Match) -> str:
        target = (folder / match.group(1)).resolve()
        if target in SITE_PAGES:
            return f"]({SITE_PAGES[target]}{match.group(2) or ''})"
        if target.parent == DOCS:
            return f"]({target.name}{match.group(2) or ''})"
        return match.group(0)

    return _LINK.sub(replace, text)


def _on_source_read(app, docname, source):
    source[0] = _site_links(source[0], DOCS)


# The captions of the figures (workflow/report/fig*.rst, which Snakemake's report renders with the
# run's config) as the gallery shows them: rendered with the config that made docs/gallery/*.png.
CAPTIONS = REPOSITORY / "workflow" / "report"
GALLERY_CONFIGS = [
    REPOSITORY / "config" / "config.yaml",
    DOCS / "gallery" / "gallery.yaml",
]


def _merged(base: dict, overlay: dict) -> dict:
    """``base`` with ``overlay`` laid over it, key by key, as Snakemake merges --configfile files."""
    merged = dict(base)
    for key, value in overlay.items():
        both = isinstance(value, dict) and isinstance(base.get(key), dict)
        merged[key] = _merged(base[key], value) if both else value
    return merged


def _gallery_caption(text: str) -> str:
    config = {}
    for path in GALLERY_CONFIGS:
        config = _merged(config, yaml.safe_load(path.read_text()))
    return jinja2.Template(text).render(snakemake=types.SimpleNamespace(config=config))


def _on_include_read(app, relative_path, parent_docname, content):
    path = (DOCS / relative_path).resolve()
    if path.parent == CAPTIONS:
        content[0] = _gallery_caption(content[0])
    content[0] = _site_links(content[0], path.parent)


def setup(app):
    app.connect("source-read", _on_source_read)
    app.connect("include-read", _on_include_read)
