"""The structure of the runtime, read from its source: imports run one way through the
layers (kernels -> element -> model -> solve -> app -> studies -> cli), no module imports
itself back through others, the items of a scene never import the model, and every
sub-package says in its docstring what it owns and what it may import."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

RUNTIME = Path(__file__).resolve().parent.parent / "runtime"
# rank of each layer; a module may import its own layer (without cycles) and lower ones
LAYERS = {"catalog": 0, "progress": 0, "kernels": 1, "element": 2, "model": 3, "solve": 4,
          "app": 5, "api": 6, "studies": 7, "cli": 8}


def _module(path: Path) -> str:
    parts = path.relative_to(RUNTIME.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _layer(module: str) -> str:
    parts = module.split(".")
    if len(parts) == 1:
        return "api"     # runtime/__init__.py: the public API
    return parts[1]


def _imports(path: Path) -> set[str]:
    """Runtime modules imported by a file (package imports resolved to the package, names
    imported from a package resolved to its sub-module where one exists)."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name.split(".")[0] == "runtime")
        elif isinstance(node, ast.ImportFrom) and node.module and \
                node.module.split(".")[0] == "runtime":
            for alias in node.names:
                sub = f"{node.module}.{alias.name}"
                parts = sub.split(".")[1:]
                is_module = (RUNTIME.joinpath(*parts).with_suffix(".py").is_file()
                             or RUNTIME.joinpath(*parts, "__init__.py").is_file())
                out.add(sub if is_module else node.module)
    return out


GRAPH = {_module(p): _imports(p) for p in RUNTIME.rglob("*.py")}


def test_the_graph_is_read():
    assert "runtime.model.model" in GRAPH and "runtime.kernels.kind" in GRAPH
    assert "runtime.kernels.kind" in GRAPH["runtime.element.element"] | {
        m for m in GRAPH if m.startswith("runtime.kernels")}


@pytest.mark.parametrize("module", sorted(GRAPH))
def test_imports_run_down_the_layers(module):
    rank = LAYERS[_layer(module)]
    upward = sorted(target for target in GRAPH[module]
                    if target in GRAPH and LAYERS[_layer(target)] > rank)
    assert not upward, f"{module} imports higher layers: {upward}"


def test_no_import_cycle():
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(module: str) -> None:
        state[module] = 1
        stack.append(module)
        for target in sorted(GRAPH.get(module, ())):
            if target not in GRAPH or target == module or \
                    module.startswith(f"{target}."):   # a package face importing its own parts
                continue
            if state.get(target) == 1:
                cycle = stack[stack.index(target):] + [target]
                pytest.fail(f"import cycle: {' -> '.join(cycle)}")
            if target not in state:
                visit(target)
        stack.pop()
        state[module] = 2

    for module in sorted(GRAPH):
        if module not in state:
            visit(module)


def test_items_never_import_the_model():
    items = [m for m in GRAPH if m.startswith("runtime.model.items")]
    assert items
    for module in items:
        assert not {"runtime.model.model", "runtime.model.dae"} & GRAPH[module], module


@pytest.mark.parametrize("package", sorted(p.parent for p in RUNTIME.glob("*/__init__.py")))
def test_every_sub_package_says_what_it_owns_and_may_import(package):
    doc = ast.get_docstring(ast.parse((package / "__init__.py").read_text()))
    assert doc and len(doc) > 60 and "May import" in doc, package
