"""The kits (``ptlab/course/sandbox/kit.py``): ptlab with a chapter's answers left out as stubs."""

from __future__ import annotations

import ast
import importlib.util
import inspect

import pytest

from ptlab.course import all_chapters
from ptlab.course.sandbox.kit import KitError, defined_as, kit_for
from ptlab.errors import NotInKitError


def _tree(kit, relative: str) -> ast.Module:
    return ast.parse((kit / "ptlab" / relative).read_text())


def _functions(tree: ast.AST) -> dict[str, ast.FunctionDef]:
    found = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            found[node.name] = node
        elif isinstance(node, ast.ClassDef):
            found.update({f"{node.name}.{f.name}": f for f in node.body if isinstance(f, ast.FunctionDef)})
    return found


def _is_stub(function: ast.FunctionDef) -> bool:
    return (
        len(function.body) == 1
        and isinstance(function.body[0], ast.Raise)
        and "NotInKitError" in ast.unparse(function.body[0])
    )


def test_a_function_left_out_is_a_stub_with_its_signature_and_the_rest_is_whole():
    kit = kit_for(("ptlab.scattering.reflect",))
    functions = _functions(_tree(kit, "scattering.py"))
    import ptlab.scattering as scattering

    original = _functions(ast.parse(inspect.getsource(scattering)))
    assert _is_stub(functions["reflect"])
    assert ast.dump(functions["reflect"].args) == ast.dump(original["reflect"].args)
    for name in ("refract", "fresnel_dielectric", "F_schlick"):
        assert ast.dump(functions[name]) == ast.dump(original[name]), name


def test_a_stub_raises_not_in_kit_with_the_name_it_stands_for():
    kit = kit_for(("ptlab.scattering.reflect",))
    spec = importlib.util.spec_from_file_location("kit_scattering", kit / "ptlab" / "scattering.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    with pytest.raises(NotInKitError, match=r"ptlab\.scattering\.reflect is left out of the kit"):
        module.reflect(None, None)


def test_a_class_or_a_module_left_out_has_every_method_and_function_stubbed():
    kit = kit_for(("ptlab.materials.Diffuse", "ptlab.rendering.adaptive"))
    diffuse = _functions(_tree(kit, "materials/diffuse.py"))
    assert {"Diffuse.eval", "Diffuse.pdf", "Diffuse.sample", "Diffuse.__init__"} <= set(diffuse)
    assert all(_is_stub(f) for name, f in diffuse.items() if name.startswith("Diffuse."))
    adaptive = _functions(_tree(kit, "rendering/adaptive.py"))
    assert adaptive
    assert all(_is_stub(f) for f in adaptive.values())
    assert not any(_is_stub(f) for f in _functions(_tree(kit, "materials/microfacet.py")).values())


def test_no_kit_holds_the_graders_code_but_the_childs_side():
    kit = kit_for(()) / "ptlab"
    assert not (kit / "grading").exists()
    assert not (kit / "cli.py").exists()
    assert sorted(p.name for p in (kit / "course").glob("*.py")) == ["__init__.py", "given.py"]
    assert not (kit / "course" / "solutions").exists()
    assert not (kit / "course" / "chapters").exists()
    untrusted = {p.name for p in (kit / "course" / "sandbox").glob("*.py")}
    assert {"child.py", "channel.py", "plain_data.py"} <= untrusted
    assert not {"submission.py", "kit.py", "sandbox.py", "intake.py"} & untrusted
    assert list((kit / "course" / "sandbox" / "__pycache__").glob("child.*.pyc"))  # compiled beforehand


def test_names_are_resolved_where_they_are_defined_and_unknown_ones_refused():
    assert defined_as("ptlab.materials.Diffuse") == "ptlab.materials.diffuse.Diffuse"
    assert defined_as("ptlab.scattering") == "ptlab.scattering"
    with pytest.raises(KitError, match=r"ptlab\.nothing_here"):
        kit_for(("ptlab.nothing_here",))


def _module_file(kit, dotted: str):
    """The kit's file of the module that defines ``dotted``, and the name inside it."""
    parts = dotted.split(".")
    for split in range(len(parts) - 1, 0, -1):
        path = kit.joinpath(*parts[:split]).with_suffix(".py")
        if path.exists():
            return path, ".".join(parts[split:])
    raise AssertionError(f"no module of {dotted} in the kit")


@pytest.mark.parametrize("chapter", all_chapters(), ids=lambda c: c.stem)
def test_every_chapters_kit_leaves_out_its_answers(chapter):
    kit = kit_for(chapter.rules.left_out)
    for name in chapter.answers:
        path, inside = _module_file(kit, defined_as(name))
        functions = _functions(ast.parse(path.read_text()))
        stubs = [f for key, f in functions.items() if key == inside or key.startswith(inside + ".")]
        assert stubs, (chapter.number, name)
        assert all(_is_stub(f) for f in stubs), (chapter.number, name)
