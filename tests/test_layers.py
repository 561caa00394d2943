"""The package's import graph: layers along the data path, and no import cycles.

Read from the sources (every ``import`` statement, also those inside functions), so that
an import made lazily to dodge a cycle counts too.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import wetclutch

PKG = Path(wetclutch.__file__).resolve().parent
#: layer of each subpackage along the data path; the base modules (errors, params, output, the numba cache
#: keeper) sit below all, the command line (``cli``, and ``__main__`` that runs it) and the package's front
#: door above all
LAYERS = {"physics": 1, "sim": 2, "plant": 3, "rig": 4, "ident": 5, "launch": 6, "fmi": 7, "report": 8}
BASE = {"errors", "params", "output", "_jitcache"}
TOP = {"cli", "__main__"}


def _module_name(path: Path) -> str:
    rel = path.relative_to(PKG).with_suffix("")
    parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts  # a package is named by its folder
    return ".".join(("wetclutch", *parts))


def _layer(module: str) -> int:
    parts = module.split(".")[1:]
    if not parts:
        return 10  # the package's front door (wetclutch/__init__.py)
    if parts[0] in LAYERS:
        return LAYERS[parts[0]]
    if parts[0] in BASE:
        return 0
    if parts[0] in TOP:
        return 9
    raise AssertionError(f"{module}: not in any layer")


def _imports(path: Path) -> set[str]:
    """The package's modules that ``path`` imports."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.startswith("wetclutch")}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            elif node.module and node.module.startswith("wetclutch"):
                target = node.module
            else:
                continue
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                # "from pkg import module" names a module; "from module import name" names the module
                found.add(sub if (PKG / Path(*sub.split(".")[1:])).with_suffix(".py").exists()
                          or (PKG / Path(*sub.split(".")[1:]) / "__init__.py").exists() else target)
    found.discard(name)
    return found


def _graph() -> dict[str, set[str]]:
    return {_module_name(p): _imports(p) for p in PKG.rglob("*.py") if "__pycache__" not in p.parts}


def test_every_module_is_in_a_layer():
    for module in _graph():
        _layer(module)


def test_no_module_imports_a_higher_layer():
    bad = [f"{m} (layer {_layer(m)}) imports {d} (layer {_layer(d)})"
           for m, deps in _graph().items() for d in deps if _layer(d) > _layer(m)]
    assert not bad, "\n".join(bad)


def test_no_import_cycles():
    graph = _graph()
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    stack: list[str] = []

    def visit(m: str) -> None:
        state[m] = 1
        stack.append(m)
        for d in sorted(graph.get(m, ())):
            if state.get(d) == 1:
                pytest.fail("import cycle: " + " -> ".join(stack[stack.index(d):] + [d]))
            if d not in state:
                visit(d)
        stack.pop()
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m)


@pytest.mark.parametrize(("source", "target", "allowed"), [
    ("wetclutch.physics.friction", "wetclutch.sim.rhs", False),
    ("wetclutch.launch.loop", "wetclutch.rig.sensors", True),
])
def test_the_layer_rule_itself(source, target, allowed):
    # the rule the graph is checked against, on a pair either way
    assert (_layer(target) <= _layer(source)) is allowed
