"""The Examples of the public API's and the physics modules' docstrings run as doctests (cheap
ones: the exact solutions, the solve at r = 1/2, tiny simulations, and pure numpy/scipy
functions; the physics modules' Examples call a compiled function's ``py_func``, so they
compile nothing), and every public name of a physics module has a numpydoc docstring."""

import doctest
import importlib
import inspect
import pkgutil

import pytest

import bouncing_ball

# the public API's modules, and the physics modules (every other module at the top level, found
# so that a new one is held to the same standard), whose public names (their __all__) are
# documented in numpydoc style
API_MODULES = ["bouncing_ball.equilibrium", "bouncing_ball.simulation"]
DOCUMENTED = sorted(
    f"bouncing_ball.{module.name}"
    for module in pkgutil.iter_modules(bouncing_ball.__path__)
    if module.name != "workflow" and f"bouncing_ball.{module.name}" not in API_MODULES
)
MODULES = API_MODULES + DOCUMENTED


def _with_submodules(module) -> list:
    """The module, and every module of it if it is a package (bouncing_ball.distribution):
    doctest finds a function's Examples in the module that defines it only."""
    if not hasattr(module, "__path__"):
        return [module]
    found = pkgutil.walk_packages(module.__path__, prefix=f"{module.__name__}.")
    return [module, *(importlib.import_module(info.name) for info in found)]


@pytest.mark.parametrize("name", MODULES)
def test_examples_run(name, capsys):
    attempted = failed = 0
    for module in _with_submodules(importlib.import_module(name)):
        result = doctest.testmod(
            module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE, verbose=False
        )
        attempted, failed = attempted + result.attempted, failed + result.failed
    report = capsys.readouterr().out
    assert attempted > 0, f"{name} has no Examples"
    assert failed == 0, report


def _missing_sections(obj) -> list[str]:
    """The numpydoc sections a public function or class lacks: a one-line summary, Parameters
    where it takes arguments, Returns (or Yields) for a function (an exception: a summary)."""
    doc = inspect.getdoc(obj) or ""
    missing = [] if doc.strip() else ["docstring"]
    if "\n" in doc.split("\n\n")[0]:
        missing.append("one-line summary")
    function = getattr(obj, "py_func", obj)  # a numba dispatcher documents its Python function
    if inspect.isclass(obj) and issubclass(obj, BaseException):
        return missing
    if inspect.isclass(obj):
        if dataclass_fields := getattr(obj, "__dataclass_fields__", None):
            takes_arguments = bool(dataclass_fields)
        else:
            takes_arguments = len(inspect.signature(obj).parameters) > 0
    else:
        takes_arguments = len(inspect.signature(function).parameters) > 0
        if "Returns\n-------" not in doc and "Yields\n------" not in doc:
            missing.append("Returns")
    if takes_arguments and "Parameters\n----------" not in doc:
        missing.append("Parameters")
    return missing


@pytest.mark.parametrize("name", DOCUMENTED)
def test_public_names_documented(name):
    module = importlib.import_module(name)
    assert module.__all__, f"{name} has an empty __all__"
    undocumented = {
        public: missing
        for public in module.__all__
        if callable(value := getattr(module, public)) and (missing := _missing_sections(value))
    }
    assert not undocumented, f"{name}: numpydoc sections missing: {undocumented}"
    examples = [
        public for public in module.__all__ if ">>>" in (getattr(module, public).__doc__ or "")
    ]
    assert examples, f"{name}: no public name has Examples"


def test_the_api_reference_lists_every_physics_module():
    """docs/api.md's list of physics modules holds every documented module, so the site shows
    each one's page."""
    listed = set((bouncing_ball.PACKAGE.parent / "docs" / "api.md").read_text().split())
    missing = [name for name in DOCUMENTED if name.removeprefix("bouncing_ball.") not in listed]
    assert not missing, f"docs/api.md does not list {missing}"
