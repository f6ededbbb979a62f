"""The package's layout: the top level is the physics and the public API, the pipeline's
plumbing is in ``bouncing_ball.workflow``, and the physics never imports the plumbing."""

import ast
import importlib
import pkgutil

import pytest

import bouncing_ball
import bouncing_ball.workflow

TOP_LEVEL = sorted(
    module.name
    for module in pkgutil.iter_modules(bouncing_ball.__path__)
    if module.name != "workflow"
)
WORKFLOW = sorted(module.name for module in pkgutil.iter_modules(bouncing_ball.workflow.__path__))


@pytest.mark.parametrize(
    "name",
    [f"bouncing_ball.{name}" for name in TOP_LEVEL]
    + [f"bouncing_ball.workflow.{name}" for name in WORKFLOW],
)
def test_every_module_imports(name):
    importlib.import_module(name)


def imports_the_workflow(source: str) -> bool:
    """Whether a top-level module's source imports ``bouncing_ball.workflow`` (or a module in
    it), absolutely or relatively."""
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom):
            module = node.module or ""
            names = {alias.name for alias in node.names}
            if node.level == 1 and (module.split(".")[0] == "workflow" or "workflow" in names):
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


@pytest.mark.parametrize("name", TOP_LEVEL)
def test_the_library_does_not_import_the_workflow(name):
    source = (bouncing_ball.PACKAGE / f"{name}.py").read_text()
    assert not imports_the_workflow(source), f"bouncing_ball.{name} imports the workflow's plumbing"


def test_public_api_is_the_top_level():
    assert {"Equilibrium", "ExactEquilibrium", "simulate", "SimulationResult"} <= set(
        bouncing_ball.__all__
    )
    for name in bouncing_ball.__all__:
        assert getattr(bouncing_ball, name) is not None


def test_the_simulation_stage_names_every_module_the_shard_loop_compiles():
    """An edit of any module numba compiles for the shard loop must re-run the shards: the
    simulation stage's sources hold simulation.py and every compiled module it imports."""
    from bouncing_ball import jit
    from bouncing_ball.workflow import stages

    tree = ast.parse((bouncing_ball.PACKAGE / "simulation.py").read_text())
    imported = {
        node.module.split(".")[0]
        for node in ast.walk(tree)
        if isinstance(node, ast.ImportFrom) and node.level == 1 and node.module
    }
    loop = ({"simulation"} | imported) & set(jit.COMPILED)
    assert {"free_flight", "pcg64", "simulation", "tallies"} <= loop
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
