"""The operators' modules import one another in one direction (DESIGN.md §2): the description of
an operator at the bottom, importing none of them; its discrete forms above it; the rule that
picks a form at the top. Read from their source with ``ast``, every import, a deferred one inside
a function too, so that a circle cannot hide there."""

import ast
import graphlib
from pathlib import Path

import warpbem.hydro.operators as operators

PACKAGE = "warpbem.hydro.operators"
FORMS = ("discrete", "dense", "direct_sum", "treecode_form", "kept_blocks", "forms")


def sibling_imports(folder: Path, package: str) -> dict:
    """{module: the modules of the same package it imports} for every module in ``folder``
    (``__init__`` where a module imports the package itself)."""
    modules = {path.stem: path for path in folder.glob("*.py")}
    graph = {}
    for name, path in modules.items():
        imported = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                base = package.rsplit(".", node.level - 1)[0] if node.level else ""
                full = ".".join(part for part in (base, node.module) if part)
                targets = [f"{full}.{alias.name}" for alias in node.names]  # a module, or a name in one
            elif isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            else:
                continue
            for target in targets:
                if target == package or target.startswith(package + "."):
                    child = target[len(package) + 1:].split(".")[0]
                    imported.add(child if child in modules else "__init__")
        graph[name] = imported - {name}
    return graph


def test_the_operators_import_one_another_without_a_circle():
    graph = sibling_imports(Path(operators.__file__).parent, PACKAGE)
    assert set(FORMS) | {"description", "__init__"} <= set(graph)
    try:
        list(graphlib.TopologicalSorter(graph).static_order())
    except graphlib.CycleError as circle:
        raise AssertionError(f"the operators import one another in a circle: {circle.args[1]}") from None
    assert not graph["description"], f"the description imports {sorted(graph['description'])}, none of its forms"
    assert all("description" in graph[form] for form in ("discrete", "dense", "treecode_form", "forms"))
