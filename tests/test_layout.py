"""The package's layers (pipeline/__init__.py): a module imports only from its own layer and the
layers before it, at the top of the file or inside a function."""

import ast
from pathlib import Path

import pipeline

ROOT = Path(pipeline.__file__).parent
LAYERS = ["errors", "model", "workspace", "app", "analyses"]  # then the entry points on top


def layer(module: str) -> int:
    """Rank of a dotted ``pipeline.*`` module name (an entry point ranks above every layer)."""
    parts = module.split(".")
    return LAYERS.index(parts[1]) if len(parts) > 1 and parts[1] in LAYERS else len(LAYERS)


def imported(path: Path) -> set[str]:
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
    return {name for name in found if name.startswith("pipeline.")}


def test_no_layer_imports_a_later_one():
    modules = sorted(ROOT.rglob("*.py"))
    assert len(modules) > 40
    wrong = []
    for path in modules:
        name = ".".join(("pipeline", *path.relative_to(ROOT).with_suffix("").parts))
        wrong += [f"{name} imports {other}" for other in imported(path) if layer(other) > layer(name)]
    assert not wrong, wrong


def test_every_layer_is_a_package_with_its_modules():
    for name in LAYERS[1:]:
        assert (ROOT / name / "__init__.py").exists()
        assert len(list((ROOT / name).glob("*.py"))) >= 5
    assert sorted(p.stem for p in ROOT.glob("*.py")) == ["__init__", "__main__", "api", "caspr", "errors", "report", "study",
                                                         "wirex"]


def test_no_two_modules_import_each_other_and_hydra_only_through_its_public_api():
    """The import graph of the package (imports inside functions included) has no cycle, no
    module reaches into Hydra's private modules (``hydra._internal``), and no Hydra plugin of
    the project's own remains (the runner is ``pipeline.app.run``; Hydra's launchers run
    through its stock application, ``pipeline.app.cli.main``)."""
    graph = {}
    for path in sorted(ROOT.rglob("*.py")):
        name = ".".join(("pipeline", *path.relative_to(ROOT).with_suffix("").parts)).removesuffix(".__init__")
        graph[name] = {other for other in imported(path) if other != name}
        for node in ast.walk(ast.parse(path.read_text())):
            modules = ([alias.name for alias in node.names] if isinstance(node, ast.Import)
                       else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            assert not any(m.startswith(("hydra._internal", "hydra_plugins")) for m in modules), (name, modules)
    done, active = set(), []

    def visit(module):
        assert module not in active, " -> ".join([*active[active.index(module):], module])
        if module in done or module not in graph:
            return
        active.append(module)
        for other in sorted(graph[module]):
            visit(other)
        active.pop()
        done.add(module)

    for module in graph:
        visit(module)
    assert not (ROOT.parent / "hydra_plugins").exists()
