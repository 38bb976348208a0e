"""The package's folders are its architecture (docs/architecture.md): imports flow one way.

Every ``import`` of ptlab's own modules, at the top of a file or inside a function, is read
from the source (``ast``), so an import made lazily to dodge a cycle still counts.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
from helpers import PACKAGE, library_modules

#: The layers, lowest first (docs/architecture.md draws the same). A module may import its own
#: layer and those below it, never one above; within a layer, the no-cycle test keeps order.
LAYERS = [
    ("foundation", ["ptlab.vectors", "ptlab.errors", "ptlab.atomic"]),
    (
        "concepts",
        [
            "ptlab.sampling",
            "ptlab.samplers",
            "ptlab.scattering",
            "ptlab.camera",
            "ptlab.image",
            "ptlab.accel",
            "ptlab.textures",
            "ptlab.materials",
            "ptlab.lights",
            "ptlab.meshes",
            "ptlab.scene",
            "ptlab.scene_file",
            # (the relMSE's definition: the renderer's own estimate of it uses it too)
            "ptlab.measure.metrics",
        ],
    ),
    ("integrators", ["ptlab.integrators"]),
    ("rendering", ["ptlab.rendering", "ptlab", "ptlab.inspector"]),
    (
        "tools",
        [
            "ptlab.measure",
            "ptlab.untrusted",
            "ptlab.grading",
            # (the catalogues of what students read, in English and Chinese: the grader's
            # tools say some of it too, and they import nothing but their two languages)
            "ptlab.exercises.messages",
        ],
    ),
    ("exercises", ["ptlab.exercises"]),
    ("command line", ["ptlab.cli", "ptlab.__main__"]),
]


def imports_of(path: Path, modules: dict[str, Path]) -> set[str]:
    """The ptlab modules a file imports, anywhere in it."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
            found.update(f"{node.module}.{alias.name}" for alias in node.names)
        elif isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
    return {name for name in found if name in modules}


def import_graph() -> dict[str, set[str]]:
    modules = library_modules()
    return {name: imports_of(path, modules) - {name} for name, path in modules.items()}


def layer_of(module: str) -> int:
    """The index of the layer a module belongs to (the longest matching prefix wins)."""
    best, best_length = None, -1
    for index, (_, prefixes) in enumerate(LAYERS):
        for prefix in prefixes:
            matches = module == prefix or (prefix != "ptlab" and module.startswith(prefix + "."))
            if matches and len(prefix) > best_length:
                best, best_length = index, len(prefix)
    if best is None:
        raise AssertionError(f"{module} is in no layer: add it to LAYERS and docs/architecture.md")
    return best


def test_every_module_has_a_layer():
    for module in library_modules():
        layer_of(module)


def test_imports_only_go_down_the_layers():
    upward = [
        f"{module} ({LAYERS[layer_of(module)][0]}) imports {target} ({LAYERS[layer_of(target)][0]})"
        for module, targets in import_graph().items()
        for target in targets
        if layer_of(target) > layer_of(module)
    ]
    assert not upward, "\n".join(upward)


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of the graph as a list of modules, or None (depth-first search)."""
    state: dict[str, str] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = "open"
        stack.append(node)
        for target in sorted(graph[node]):
            if state.get(target) == "open":
                return [*stack[stack.index(target) :], target]
            if target not in state and (cycle := visit(target)):
                return cycle
        state[node] = "done"
        stack.pop()
        return None

    for node in sorted(graph):
        if node not in state and (cycle := visit(node)):
            return cycle
    return None


def test_no_import_cycles():
    cycle = find_cycle(import_graph())
    assert cycle is None, " -> ".join(cycle)


def test_find_cycle_finds_one():
    # The checker itself must see a cycle, or the test above proves nothing.
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


@pytest.mark.parametrize(
    "module",
    [
        "ptlab.render",
        "ptlab.render_result",
        "ptlab.load_scene",
        "ptlab.Scene",
        "ptlab.RenderResult",
        "ptlab.RenderOptions",
    ],
)
def test_the_api_is_at_the_top(module):
    import ptlab

    assert callable(getattr(ptlab, module.removeprefix("ptlab.")))


def test_top_level_holds_concepts_not_machinery():
    # The machinery of a render and the measurements live in their subpackages.
    top = {p.stem for p in PACKAGE.glob("*.py")}
    assert top <= {
        "__init__",
        "cli",
        "__main__",
        "vectors",
        "errors",
        "atomic",
        "sampling",
        "samplers",
        "scattering",
        "camera",
        "image",
        "lights",
        "meshes",
        "scene",
        "scene_file",
        "textures",
    }, top


def test_the_version_is_written_once():
    """pyproject.toml reads the version from ptlab/__init__.py (hatch's dynamic version): the
    installed package's metadata and ``ptlab.__version__`` cannot disagree."""
    from importlib.metadata import version

    import ptlab

    assert version("ptlab") == ptlab.__version__
    assert "version =" not in (PACKAGE.parent / "pyproject.toml").read_text().split("[tool")[0]
