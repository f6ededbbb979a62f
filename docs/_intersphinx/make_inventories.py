"""Write the intersphinx inventories of Python, numpy, scipy, pandas and matplotlib kept here.

The site links the names it shares with those projects (``numpy.ndarray``, ``pandas.DataFrame``,
...) to their documentation through these files, so that a build reads no network and cannot
hang or fail where there is none.  Each inventory lists the objects the site names, each at the
address that project's site gives it.  Run from the repository root after adding a name:

    python docs/_intersphinx/make_inventories.py

With a network, ``python docs/_intersphinx/make_inventories.py --fetch`` replaces them with each
project's published ``objects.inv`` instead (larger files, every object of the project).
"""

import sys
import urllib.request
import zlib
from pathlib import Path

FOLDER = Path(__file__).resolve().parent

#: project: (site, version shown, [(name, role, page, anchor, shown)]); anchor "$" is the name
#: itself, shown "-" too
INVENTORIES = {
    # the targets of numpydoc's default type aliases (bool, iterable, ...) and the builtin types
    "python": (
        "https://docs.python.org/3/",
        "3",
        [
            ("bltin-boolean-values", "std:label", "library/stdtypes.html", "$", "Boolean Values"),
            ("iterable", "std:term", "glossary.html", "term-iterable", "iterable"),
            ("sequence", "std:term", "glossary.html", "term-sequence", "sequence"),
            ("mapping", "std:term", "glossary.html", "term-mapping", "mapping"),
            ("None", "py:data", "library/constants.html", "$"),
            ("True", "py:data", "library/constants.html", "$"),
            ("False", "py:data", "library/constants.html", "$"),
            ("callable", "py:function", "library/functions.html", "$"),
            ("bool", "py:class", "library/functions.html", "$"),
            ("int", "py:class", "library/functions.html", "$"),
            ("float", "py:class", "library/functions.html", "$"),
            ("object", "py:class", "library/functions.html", "$"),
            ("str", "py:class", "library/stdtypes.html", "$"),
            ("dict", "py:class", "library/stdtypes.html", "$"),
            ("list", "py:class", "library/stdtypes.html", "$"),
            ("tuple", "py:class", "library/stdtypes.html", "$"),
            ("pathlib.Path", "py:class", "library/pathlib.html", "$"),
            ("fractions.Fraction", "py:class", "library/fractions.html", "$"),
        ],
    ),
    "numpy": (
        "https://numpy.org/doc/stable/",
        "stable",
        [
            ("numpy.ndarray", "py:class", "reference/generated/numpy.ndarray.html", "$"),
            ("numpy.int64", "py:attribute", "reference/arrays.scalars.html", "$"),
            ("numpy.float64", "py:attribute", "reference/arrays.scalars.html", "$"),
            ("numpy.random.Generator", "py:class", "reference/random/generator.html", "$"),
            (
                "numpy.random.SeedSequence",
                "py:class",
                "reference/random/bit_generators/generated/numpy.random.SeedSequence.html",
                "$",
            ),
            ("numpy.random.PCG64", "py:class", "reference/random/bit_generators/pcg64.html", "$"),
            (
                "numpy.polynomial.Chebyshev",
                "py:class",
                "reference/generated/numpy.polynomial.chebyshev.Chebyshev.html",
                "numpy.polynomial.chebyshev.Chebyshev",
            ),
            (
                "numpy.polynomial.Polynomial",
                "py:class",
                "reference/generated/numpy.polynomial.polynomial.Polynomial.html",
                "numpy.polynomial.polynomial.Polynomial",
            ),
            ("numpy.typing.ArrayLike", "py:data", "reference/typing.html", "$"),
            ("array_like", "std:term", "glossary.html", "term-array_like", "array_like"),
            ("numpy.trapezoid", "py:function", "reference/generated/numpy.trapezoid.html", "$"),
            ("numpy.geomspace", "py:function", "reference/generated/numpy.geomspace.html", "$"),
            ("numpy.linspace", "py:function", "reference/generated/numpy.linspace.html", "$"),
        ],
    ),
    "scipy": (
        "https://docs.scipy.org/doc/scipy/",
        "stable",
        [
            (f"scipy.{name}", "py:function", f"reference/generated/scipy.{name}.html", "$")
            for name in (
                "integrate.quad",
                "integrate.solve_ivp",
                "optimize.brentq",
                "optimize.curve_fit",
                "special.airy",
                "special.kv",
                "special.erf",
            )
        ]
        + [
            ("scipy.stats.t", "py:data", "reference/generated/scipy.stats.t.html", "$"),
            ("scipy.stats.f", "py:data", "reference/generated/scipy.stats.f.html", "$"),
        ],
    ),
    "pandas": (
        "https://pandas.pydata.org/docs/",
        "stable",
        [
            ("pandas.DataFrame", "py:class", "reference/api/pandas.DataFrame.html", "$"),
            ("pandas.Series", "py:class", "reference/api/pandas.Series.html", "$"),
            ("pandas.read_parquet", "py:function", "reference/api/pandas.read_parquet.html", "$"),
            (
                "pandas.DataFrame.to_parquet",
                "py:method",
                "reference/api/pandas.DataFrame.to_parquet.html",
                "$",
            ),
        ],
    ),
    "matplotlib": (
        "https://matplotlib.org/stable/",
        "stable",
        [
            ("matplotlib.axes.Axes", "py:class", "api/_as_gen/matplotlib.axes.Axes.html", "$"),
            (
                "matplotlib.figure.Figure",
                "py:class",
                "api/_as_gen/matplotlib.figure.Figure.html",
                "$",
            ),
            (
                "matplotlib.pyplot.subplots",
                "py:function",
                "api/_as_gen/matplotlib.pyplot.subplots.html",
                "$",
            ),
            (
                "matplotlib.rc_context",
                "py:function",
                "api/matplotlib_configuration_api.html",
                "$",
            ),
        ],
    ),
}


def inventory(project: str, version: str, entries) -> bytes:
    """The bytes of a Sphinx inventory (version 2) holding ``entries``."""
    header = (
        "# Sphinx inventory version 2\n"
        f"# Project: {project}\n"
        f"# Version: {version}\n"
        "# The remainder of this file is compressed using zlib.\n"
    )
    lines = "".join(
        f"{name} {role} 1 {page}#{anchor} {shown[0] if shown else '-'}\n"
        for name, role, page, anchor, *shown in entries
    )
    return header.encode() + zlib.compress(lines.encode(), 9)


def main(fetch: bool) -> None:
    for project, (site, version, entries) in INVENTORIES.items():
        path = FOLDER / f"{project}.inv"
        if fetch:
            with urllib.request.urlopen(site + "objects.inv", timeout=30) as answer:
                path.write_bytes(answer.read())
        else:
            path.write_bytes(inventory(project, version, entries))
        print(path.relative_to(FOLDER.parents[1]))


if __name__ == "__main__":
    main("--fetch" in sys.argv[1:])
