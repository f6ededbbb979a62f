"""The package's layout: the top level is the physics and the public API, the pipeline's
plumbing is in ``bouncing_ball.workflow``, the physics never imports the plumbing, and no module
grows past LARGEST_MODULE lines."""

import ast
import importlib
import pkgutil

import pytest

import bouncing_ball
import bouncing_ball.workflow

WORKFLOW = sorted(module.name for module in pkgutil.iter_modules(bouncing_ball.workflow.__path__))
# every physics module, those of its subpackages (bouncing_ball.distribution) included, by its
# file below the package
PHYSICS_FILES = sorted(
    path.relative_to(bouncing_ball.PACKAGE).as_posix()
    for path in bouncing_ball.PACKAGE.rglob("*.py")
    if path.relative_to(bouncing_ball.PACKAGE).parts[0] != "workflow"
)

#: The most lines a module of the package may hold: a module past it is split along its seams
#: into a subpackage (as distribution/ and flight_time/ are).
LARGEST_MODULE = 1100


def _dotted(file: str) -> str:
    """bouncing_ball's module of a file below the package ("distribution/position.py")."""
    parts = file.removesuffix(".py").split("/")
    return ".".join(["bouncing_ball", *(parts[:-1] if parts[-1] == "__init__" else parts)])


@pytest.mark.parametrize(
    "name",
    [_dotted(file) for file in PHYSICS_FILES]
    + [f"bouncing_ball.workflow.{name}" for name in WORKFLOW],
)
def test_every_module_imports(name):
    importlib.import_module(name)


def imports_the_workflow(source: str, depth: int = 0) -> bool:
    """Whether a physics module's source imports ``bouncing_ball.workflow`` (or a module in
    it), absolutely or relatively; ``depth`` is how many subpackages deep the module lies
    (0 at the top level, 1 in bouncing_ball.distribution)."""
    root = depth + 1  # the relative level of the package bouncing_ball
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom):
            module = node.module or ""
            names = {alias.name for alias in node.names}
            if node.level == root and (module.split(".")[0] == "workflow" or "workflow" in names):
                return True
            if node.level == 0 and module.startswith("bouncing_ball.workflow"):
                return True
            if node.level == 0 and module == "bouncing_ball" and "workflow" in names:
                return True
        elif isinstance(node, ast.Import) and any(
            alias.name.startswith("bouncing_ball.workflow") for alias in node.names
        ):
            return True
    return False


@pytest.mark.parametrize(
    "source, expected",
    [
        ("from .workflow.io import read_table", True),
        ("from .workflow import stages", True),
        ("from . import workflow", True),
        ("import bouncing_ball.workflow.io", True),
        ("from bouncing_ball.workflow import io", True),
        ("from .tallies import SCALARS\nfrom . import exact", False),
    ],
)
def test_imports_the_workflow_sees_every_form(source, expected):
    assert imports_the_workflow(source) is expected


@pytest.mark.parametrize(
    "source, expected",
    [
        ("from ..workflow.io import read_table", True),
        ("from .. import workflow", True),
        ("from ..solver import DEFAULT_STEP\nfrom .position import position_density", False),
    ],
)
def test_imports_the_workflow_sees_every_form_in_a_subpackage(source, expected):
    assert imports_the_workflow(source, depth=1) is expected


@pytest.mark.parametrize(
    "source, expected",
    [
        ("from ...workflow.io import read_table", True),
        ("from ... import workflow", True),
        ("from ..workflow import io", False),  # a sibling subpackage's own workflow module
        ("from ...solver import DEFAULT_STEP", False),
    ],
)
def test_imports_the_workflow_sees_every_form_two_subpackages_deep(source, expected):
    assert imports_the_workflow(source, depth=2) is expected


@pytest.mark.parametrize("file", PHYSICS_FILES)
def test_the_library_does_not_import_the_workflow(file):
    source = (bouncing_ball.PACKAGE / file).read_text()
    depth = file.count("/")
    assert not imports_the_workflow(source, depth), f"bouncing_ball/{file} imports the workflow"


def test_no_module_is_past_the_largest_size():
    """Every module of the package (the workflow's and the subpackages' included) holds at most
    LARGEST_MODULE lines."""
    lines = {
        path.relative_to(bouncing_ball.PACKAGE).as_posix(): len(path.read_text().splitlines())
        for path in bouncing_ball.PACKAGE.rglob("*.py")
    }
    too_large = {file: count for file, count in lines.items() if count > LARGEST_MODULE}
    assert not too_large, f"split these along their seams (at most {LARGEST_MODULE}): {too_large}"


#: What the estimators must not import: the theory they are held against (the simulation is the
#: independent check of it); its P(0, u) comes in as an argument (``outgoing_density``).
THEORY = {"solver", "distribution", "equilibrium", "relaxation", "exact", "quasi_elastic"}


def _imported_modules(source: str, depth: int) -> set[str]:
    """The package's modules a source imports (relative or absolute, at any level of the
    file, inside functions too), by their first dotted part below bouncing_ball."""
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom):
            if node.level == depth + 1:
                names = [node.module] if node.module else [alias.name for alias in node.names]
                found |= {name.split(".")[0] for name in names}
            elif node.level == 0 and (node.module or "").startswith("bouncing_ball."):
                found.add(node.module.split(".")[1])
            elif node.level == 0 and node.module == "bouncing_ball":
                found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.Import):
            found |= {
                alias.name.split(".")[1]
                for alias in node.names
                if alias.name.startswith("bouncing_ball.")
            }
    return found


@pytest.mark.parametrize("file", [file for file in PHYSICS_FILES if file.startswith("estimators/")])
def test_the_estimators_do_not_import_the_theory(file):
    source = (bouncing_ball.PACKAGE / file).read_text()
    assert not _imported_modules(source, file.count("/")) & THEORY, file


def test_imported_modules_sees_every_form():
    source = (
        "from ..solver import x\nfrom .. import distribution\n"
        "def f():\n    from bouncing_ball.exact import y\n    import bouncing_ball.relaxation\n"
        "from .jackknife import jackknife"
    )
    assert _imported_modules(source, 1) == {"solver", "distribution", "exact", "relaxation"}


BENCHMARKS = bouncing_ball.PACKAGE.parent / "benchmarks"


def benchmark_imports(source: str) -> set[str]:
    """The modules of ``benchmarks`` a module of it imports (relatively or as
    ``benchmarks.x``, at its top or inside a function)."""
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom):
            if node.level == 1:
                names = [node.module] if node.module else [alias.name for alias in node.names]
                found |= {name.split(".")[0] for name in names}
            elif node.level == 0 and (node.module or "").startswith("benchmarks."):
                found.add(node.module.split(".")[1])
            elif node.level == 0 and node.module == "benchmarks":
                found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.Import):
            found |= {
                alias.name.split(".")[1]
                for alias in node.names
                if alias.name.startswith("benchmarks.")
            }
    return found


def import_cycle(graph: dict[str, set[str]]) -> list[str]:
    """A cycle of ``graph`` (module: the modules it imports), as the modules along it, or []."""
    state = {}  # 1: on the current path, 2: done

    def visit(module, path):
        state[module] = 1
        for imported in sorted(graph.get(module, ())):
            if state.get(imported) == 1:
                return [*path[path.index(imported) :], imported]
            if imported not in state and (cycle := visit(imported, [*path, imported])):
                return cycle
        state[module] = 2
        return []

    for module in sorted(graph):
        if module not in state and (cycle := visit(module, [module])):
            return cycle
    return []


def test_import_cycle_finds_a_cycle():
    assert import_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert import_cycle({"a": {"b", "c"}, "b": {"c"}, "c": set()}) == []
    source = "from .efficiency import x\ndef f():\n    from .benchmark import _shard\n"
    assert benchmark_imports(source) == {"efficiency", "benchmark"}


def test_the_benchmarks_import_each_other_without_a_cycle():
    """Each shared piece of the benchmarks has one home that the others import (a function
    reaching back into the module that imports it is a cycle too)."""
    graph = {path.stem: benchmark_imports(path.read_text()) for path in BENCHMARKS.glob("*.py")}
    assert not import_cycle(graph), f"benchmarks import each other: {import_cycle(graph)}"


def test_public_api_is_the_top_level():
    assert {"Equilibrium", "ExactEquilibrium", "simulate", "SimulationResult"} <= set(
        bouncing_ball.__all__
    )
    for name in bouncing_ball.__all__:
        assert getattr(bouncing_ball, name) is not None


def test_the_simulation_stage_names_every_module_the_shard_loop_compiles():
    """An edit of any module numba compiles for the shard loop must re-run the shards: the
    simulation stage's sources hold the loop (simulation/loop.py) and every compiled module it
    imports, of the simulation subpackage and of the package."""
    from bouncing_ball import jit
    from bouncing_ball.workflow import stages

    tree = ast.parse((bouncing_ball.PACKAGE / "simulation" / "loop.py").read_text())
    imported = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            if node.level == 1:
                imported.add(f"simulation.{node.module}")
            elif node.level == 2:
                imported.add(node.module)
    loop = ({"simulation.loop"} | imported) & set(jit.COMPILED)
    assert {"free_flight", "pcg64", "simulation.loop", "simulation.step_tallies", "tallies"} <= loop
    assert loop <= set(stages.SIMULATION)


def test_the_distribution_holds_every_package():
    """``pip install .`` (not editable) installs every package of the library, the workflow's
    plumbing included: pyproject.toml lists each folder with an __init__.py."""
    import tomllib

    project = tomllib.loads((bouncing_ball.PACKAGE.parent / "pyproject.toml").read_text())
    listed = set(project["tool"]["setuptools"]["packages"])
    packages = {
        ".".join(path.parent.relative_to(bouncing_ball.PACKAGE.parent).parts)
        for path in bouncing_ball.PACKAGE.rglob("__init__.py")
    }
    assert packages == listed


def test_a_subpackage_name_digests_every_file_of_it(tmp_path, monkeypatch):
    """source_digest("distribution") (a stage's module, jit's key) covers each of the
    subpackage's modules: an edit of any one changes it."""
    package = tmp_path / "distribution"
    package.mkdir()
    (package / "__init__.py").write_text("from .position import density\n")
    (package / "position.py").write_text("def density(x):\n    return x\n")
    monkeypatch.setattr(bouncing_ball, "PACKAGE", tmp_path)
    before = bouncing_ball.source_digest(["distribution"])
    (package / "position.py").write_text("def density(x):\n    return 2 * x\n")
    assert bouncing_ball.source_digest(["distribution"]) != before
    assert bouncing_ball.source_digest(["distribution.position"]) != before


def test_every_stage_names_modules_that_exist():
    """Each stage's modules (``workflow.stages``) resolve to files, a subpackage to its files."""
    from bouncing_ball.workflow import stages

    for name in dir(stages):
        modules = getattr(stages, name)
        if name.isupper() and isinstance(modules, tuple):
            for module in modules:
                assert bouncing_ball._module_files(module), module
                assert all(path.is_file() for path in bouncing_ball._module_files(module)), module


def test_the_simulation_package_names_every_public_name_of_its_modules_where_it_lives():
    """``bouncing_ball.simulation`` loads its names on first use from the module ``_HOMES``
    names: each such name is that module's, and every module's ``__all__`` is reachable from
    the package, so the lazy table and the modules cannot drift apart."""
    import bouncing_ball.simulation as simulation

    homes = simulation._HOMES
    for name, home in homes.items():
        module = importlib.import_module(f"bouncing_ball.simulation.{home}")
        assert hasattr(module, name), f"{name} is not in simulation.{home}"
    for info in pkgutil.iter_modules(simulation.__path__):
        module = importlib.import_module(f"bouncing_ball.simulation.{info.name}")
        missing = [name for name in getattr(module, "__all__", []) if homes.get(name) != info.name]
        assert not missing, f"simulation._HOMES lacks {missing} of simulation.{info.name}"
    assert set(simulation.__all__) <= set(homes)
