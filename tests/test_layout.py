"""The project's shape, as the design card names it: the top level, no import circles between
modules, shaders_sdf/ depending only downward, and no module over MAX_MODULE_LINES.

The import graph is read from the sources (every `import` and `from ... import`, at the top of a
module or inside a function: a lazy import still ties two modules together), so this runs without
Taichi and fails on the first circle anyone adds.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("renderer", "viewer", "shaders_sdf")
TOP_LEVEL = ("app.py", "viewer", "renderer", "shaders_sdf", "assets", "tests")
MAX_MODULE_LINES = 800
# What shaders_sdf/ may import of the renderer: the geometry contract it implements and the upload
# helper. Nothing else, so nothing that imports shaders_sdf can be imported back by it.
SDF_MAY_IMPORT = ("renderer.geometry.interface", "renderer.geometry.emitter_shapes", "renderer.runtime.upload")


def module_files(root: Path = ROOT) -> dict[str, Path]:
    """Dotted module name -> file, for the project's packages and app.py."""
    modules = {"app": root / "app.py"}
    for package in PACKAGES:
        for path in (root / package).rglob("*.py"):
            parts = path.relative_to(root).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            modules[name] = path
    return modules


def _known(name: str, modules) -> str | None:
    """The project module `name` refers to (a module, or the package holding a name), or None."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name or None


def imports_of(name: str, path: Path, modules) -> set[str]:
    """The project modules one module imports, wherever in it the import stands."""
    found = set()
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package
                for _ in range(node.level - 1):
                    anchor = anchor.rpartition(".")[0]
                base = f"{anchor}.{base}" if base else anchor
            # `from a.b import c` imports the module a.b.c where there is one, else a name of a.b
            targets = [f"{base}.{alias.name}" if f"{base}.{alias.name}" in modules else base for alias in node.names]
        else:
            continue
        found.update(t for t in (_known(target, modules) for target in targets) if t and t != name)
    return found


def import_graph(root: Path = ROOT) -> dict[str, set[str]]:
    modules = module_files(root)
    return {name: imports_of(name, path, modules) for name, path in modules.items()}


def import_circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm, iterative)."""
    index, low, on_stack, stack, circles = {}, {}, set(), [], []
    counter = 0
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    circles.append(sorted(component))
    return circles


def reachable(graph: dict[str, set[str]], start: str) -> set[str]:
    seen, todo = set(), [start]
    while todo:
        for nxt in graph.get(todo.pop(), ()):
            if nxt not in seen:
                seen.add(nxt)
                todo.append(nxt)
    return seen


def test_top_level_is_the_design_cards():
    missing = [name for name in TOP_LEVEL if not (ROOT / name).exists()]
    assert not missing, f"the design card's top level lacks {missing}"


def test_no_import_circles():
    circles = import_circles(import_graph())
    assert not circles, "modules that import each other (directly or round a circle): " + "; ".join(
        " <-> ".join(c) for c in circles)


def test_the_circle_finder_finds_circles():
    """The check above can fail: a two-module and a three-module circle are found, a chain is not."""
    graph = {"a": {"b"}, "b": {"a"}, "c": {"d"}, "d": {"e"}, "e": {"c"}, "f": {"a"}, "g": set()}
    assert sorted(import_circles(graph)) == [["a", "b"], ["c", "d", "e"]]
    assert import_circles({"a": {"b"}, "b": {"c"}, "c": set()}) == []


def test_lazy_imports_count(tmp_path):
    """An import inside a function ties modules together as much as one at the top."""
    for package in PACKAGES:
        (tmp_path / package).mkdir()
        (tmp_path / package / "__init__.py").write_text("")
    (tmp_path / "app.py").write_text("")
    (tmp_path / "renderer" / "one.py").write_text("from renderer.two import thing\n")
    (tmp_path / "renderer" / "two.py").write_text("def thing():\n    from renderer import one\n")
    assert import_circles(import_graph(tmp_path)) == [["renderer.one", "renderer.two"]]


def test_shaders_sdf_depends_only_downward():
    graph = import_graph()
    sdf_modules = [name for name in graph if name.split(".")[0] == "shaders_sdf"]
    assert sdf_modules, "no shaders_sdf modules found"
    for name in sdf_modules:
        outside = {m for m in graph[name] if m.split(".")[0] != "shaders_sdf"}
        assert outside <= set(SDF_MAY_IMPORT) | {"renderer", "renderer.geometry", "renderer.runtime"}, (
            f"{name} imports {sorted(outside - set(SDF_MAY_IMPORT))}: shaders_sdf/ depends only on the geometry "
            "contract it implements")
        back = {m for m in reachable(graph, name) if m.split(".")[0] != "shaders_sdf"}
        assert not any(name in reachable(graph, m) for m in back), f"{name} reaches a module that imports it back"
    assert any(m.startswith("shaders_sdf") for m in graph["renderer.renderer"]), "the renderer no longer uses shaders_sdf"


@pytest.mark.parametrize("package", PACKAGES + ("tests", "scripts"))
def test_no_module_over_the_size_limit(package):
    long = {str(path.relative_to(ROOT)): count for path in (ROOT / package).rglob("*.py")
            if (count := len(path.read_text().splitlines())) > MAX_MODULE_LINES}
    assert not long, f"modules over {MAX_MODULE_LINES} lines (split them by job): {long}"
