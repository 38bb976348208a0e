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
            "ptlab.transforms",
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
    # (the denoiser and its error's estimate, arrays in and out, share the noise target's
    # stand-in for the truth: ptlab.rendering.adaptive)
    ("rendering", ["ptlab.rendering", "ptlab", "ptlab.inspector", "ptlab.denoise"]),
    ("tools", ["ptlab.measure", "ptlab.grading"]),
    # The course: it imports the renderer, never the reverse.
    (
        "course's tools",
        [
            "ptlab.course.sandbox",
            # (the catalogues of what students read, in English and Chinese: the sandbox
            # says some of it too, and they import nothing but their two languages)
            "ptlab.course.messages",
        ],
    ),
    ("course", ["ptlab.course"]),
    ("command line", ["ptlab.cli", "ptlab.__main__"]),
]


def imports_of(path: Path, modules: dict[str, Path]) -> set[str]:
    """The ptlab modules a file imports, anywhere in it, by statement or by name.

    ``importlib.import_module(...)`` and ``__import__(...)`` count too: with a constant, the
    module it names; with an f-string, every module its constant start is a prefix of (a
    package whose modules are found by ``pkgutil``); with anything else (a name looked up in
    a table), every module that a string of the file names.
    """
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
            found.update(f"{node.module}.{alias.name}" for alias in node.names)
        elif isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif _imports_by_name(node):
            found.update(_modules_named(node.args[0], tree, modules))
    return {name for name in found if name in modules}


def _imports_by_name(node: ast.AST) -> bool:
    """Whether ``node`` is a call of ``import_module`` or ``__import__`` with an argument."""
    if not isinstance(node, ast.Call) or not node.args:
        return False
    function = node.func
    name = function.attr if isinstance(function, ast.Attribute) else getattr(function, "id", None)
    return name in ("import_module", "__import__")


def _modules_named(argument: ast.expr, tree: ast.Module, modules: dict[str, Path]) -> set[str]:
    """The modules an ``import_module`` argument can name (``imports_of`` says how)."""
    if isinstance(argument, ast.Constant) and isinstance(argument.value, str):
        return {argument.value}
    if isinstance(argument, ast.JoinedStr) and argument.values:
        start = argument.values[0]
        if isinstance(start, ast.Constant) and isinstance(start.value, str):
            return {name for name in modules if name.startswith(start.value)}
    # A name looked up in a table: the module-level dicts' string values, each the module
    # it names or the module of the attribute it names ("ptlab.scattering.reflect").
    named = set()
    for statement in tree.body:
        table = statement.value if isinstance(statement, ast.Assign | ast.AnnAssign) else None
        if isinstance(table, ast.Dict):
            for value in table.values:
                if isinstance(value, ast.Constant) and isinstance(value.value, str):
                    named.add(_longest_module(value.value, modules))
    return named - {None}


def _longest_module(dotted: str, modules: dict[str, Path]) -> str | None:
    """The longest module of ptlab that ``dotted`` is or starts with."""
    parts = dotted.split(".")
    for end in range(len(parts), 0, -1):
        if ".".join(parts[:end]) in modules:
            return ".".join(parts[:end])
    return None


#: The one arrow the graph leaves out: ``reflect`` moved from ``ptlab.vectors`` to
#: ``ptlab.scattering``, and students' files written before keep importing it from its old
#: place (``tests/course/test_exercises.py`` holds them to full marks). ``ptlab.vectors`` forwards
#: that name on first use (PEP 562); nothing of its own code uses scattering.
OLD_NAMES_FORWARDED = {"ptlab.vectors": {"ptlab.scattering"}}


def import_graph() -> dict[str, set[str]]:
    modules = library_modules()
    return {
        name: imports_of(path, modules) - {name} - OLD_NAMES_FORWARDED.get(name, set())
        for name, path in modules.items()
    }


def test_the_forwarded_old_names_are_only_forwarded():
    # The arrow left out above is the forwarder's and nothing else's: no import statement.
    import ptlab.vectors

    statements = imports_of(PACKAGE / "vectors.py", {"ptlab.scattering": PACKAGE / "scattering.py"})
    assert statements == {"ptlab.scattering"}  # (seen, through the table MOVED)
    assert set(ptlab.vectors.MOVED.values()) == {"ptlab.scattering.reflect"}
    source = (PACKAGE / "vectors.py").read_text(encoding="utf-8")
    assert "import ptlab.scattering" not in source
    assert "from ptlab.scattering" not in source


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


def test_the_renderer_imports_nothing_of_the_course():
    # The two trees (docs/architecture.md): the course imports the renderer, never the reverse.
    course = ("ptlab.course", "ptlab.cli", "ptlab.__main__")
    arrows = [
        f"{module} imports {target}"
        for module, targets in import_graph().items()
        if not module.startswith(course)
        for target in targets
        if target.startswith(course)
    ]
    assert not arrows, "\n".join(arrows)


def test_no_import_cycles():
    cycle = find_cycle(import_graph())
    assert cycle is None, " -> ".join(cycle)


def test_an_import_by_name_is_an_import(tmp_path):
    # A circle made with import_module (a PEP 562 forwarder, a table of homes, a package's
    # modules found by pkgutil) is a circle: the graph must see all three spellings.
    source = tmp_path / "m.py"
    source.write_text(
        "import importlib\n"
        "HOMES = {'x': 'ptlab.camera', 'y': 'ptlab.sampling.cosine_hemisphere'}\n"
        "def f(name):\n"
        "    importlib.import_module('ptlab.vectors')\n"
        "    importlib.import_module(HOMES[name])\n"
        "    __import__(f'ptlab.accel.{name}')\n"
    )
    modules = library_modules()
    assert imports_of(source, modules) == {"ptlab.vectors", "ptlab.camera", "ptlab.sampling"} | {
        name for name in modules if name.startswith("ptlab.accel.")
    }


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
        "transforms",
    }, top


def test_the_version_is_written_once():
    """pyproject.toml reads the version from ptlab/__init__.py (hatch's dynamic version): the
    installed package's metadata and ``ptlab.__version__`` cannot disagree."""
    from importlib.metadata import version

    import ptlab

    assert version("ptlab") == ptlab.__version__
    assert "version =" not in (PACKAGE.parent / "pyproject.toml").read_text().split("[tool")[0]
