"""The canonical form's blocks: choices of a value as conditional expressions, loops that
build a list or a dict as comprehensions, and no dead code.

``if c: x = a`` / ``else: x = b`` (or ``x = b`` then ``if c: x = a``) is ``x = a if c else
b``, and so for ``return``; ``setattr(x, "a", v)`` is ``x.a = v`` (``operator.setitem(x, k,
v)`` is ``x[k] = v``); a loop that only appends to a list (or fills a dict) made empty just
before it is a comprehension; what follows a ``return`` and what ``if False`` guards go.
"""

from __future__ import annotations

import ast

from ptlab.course.sandbox.syntax_trees import assigned_name, dotted_name, identifier, statements_of

#: Statements between ``out = []`` and the loop that fills it, at most (``_comprehensions``).
LOOK_BACK = 8


def simplified_blocks(tree: ast.AST) -> ast.AST:
    """``tree`` (changed in place, its names resolved) with each block of statements in one
    form (the module docstring lists what), the innermost first."""
    return _Blocks().visit(tree)


class _Blocks(ast.NodeTransformer):
    """Each block of statements simplified (``_block``), the innermost first."""

    def generic_visit(self, node: ast.AST) -> ast.AST:
        super().generic_visit(node)
        for field in ("body", "orelse", "finalbody"):
            value = getattr(node, field, None)
            if isinstance(value, list) and value and all(isinstance(s, ast.stmt) for s in value):
                setattr(node, field, _block(value) or ([ast.Pass()] if field == "body" else []))
        return node


def _block(statements: list[ast.stmt]) -> list[ast.stmt]:
    """``statements`` without dead code, choices of a value as conditional expressions, and
    loops that build a list or a dict as comprehensions."""
    out: list[ast.stmt] = []
    todo = list(reversed(statements))
    while todo:
        statement = todo.pop()
        test = getattr(statement, "test", None)
        if isinstance(statement, ast.If | ast.While) and isinstance(test, ast.Constant):
            if isinstance(statement, ast.If) and test.value:
                todo.extend(reversed(statement.body))
            elif not test.value:
                todo.extend(reversed(statement.orelse))
            else:
                out.append(statement)
            continue
        statement = _as_assignment(statement)
        merged = _merged(out[-1], statement) if out else None
        if merged is not None:
            out[-1] = merged
        elif (default := _default_before(out, statement)) is not None:
            out.append(_merged(out.pop(default), statement) or statement)
        else:
            out.append(statement)
        if isinstance(statement, ast.Return | ast.Raise | ast.Continue | ast.Break):
            break
    return _comprehensions(out)


def _as_assignment(statement: ast.stmt) -> ast.stmt:
    """``setattr(x, "a", v)`` and ``operator.setitem(x, k, v)`` as assignments; an ``if``
    whose branches each assign one name (or return) as one conditional expression."""
    if isinstance(statement, ast.Expr) and isinstance(statement.value, ast.Call):
        call = statement.value
        dotted, arguments = dotted_name(call.func), call.args
        if len(arguments) == 3 and not call.keywords:
            target: ast.expr | None = None
            if dotted == "builtins.setattr" and (name := identifier(arguments[1])):
                target = ast.Attribute(arguments[0], name, ast.Store())
            elif dotted in ("operator.setitem", "operator.__setitem__"):
                target = ast.Subscript(arguments[0], arguments[1], ast.Store())
            if target is not None:
                return ast.copy_location(ast.Assign([target], arguments[2]), statement)
    if isinstance(statement, ast.If) and len(statement.body) == 1 and len(statement.orelse) == 1:
        chosen = _choice(statement.body[0], statement.orelse[0], statement.test)
        if chosen is not None:
            return ast.copy_location(chosen, statement)
    return statement


def _choice(then: ast.stmt, otherwise: ast.stmt, test: ast.expr) -> ast.stmt | None:
    """``x = a if test else b`` for ``x = a`` and ``x = b`` (``return`` for two returns)."""
    if isinstance(then, ast.Return) and isinstance(otherwise, ast.Return) and then.value and otherwise.value:
        return ast.Return(ast.IfExp(test, then.value, otherwise.value))
    name = assigned_name(then)
    if (
        isinstance(then, ast.Assign)
        and isinstance(otherwise, ast.Assign)
        and name is not None
        and name == assigned_name(otherwise)
    ):
        value = ast.IfExp(test, then.value, otherwise.value)
        return ast.Assign([ast.Name(name, ast.Store())], value)
    return None


def _default_before(out: list[ast.stmt], statement: ast.stmt) -> int | None:
    """For ``if c: x = a`` (one assignment, no else), the place in ``out`` of an earlier
    ``x = b`` that may as well come just before it (``_merged`` then makes them one): ``b``
    calls nothing, and the statements between neither use nor assign ``x`` nor assign what
    ``b`` reads. A copier moves such a default away from its ``if`` without changing the code;
    else None."""
    if not (isinstance(statement, ast.If) and not statement.orelse and len(statement.body) == 1):
        return None
    name = assigned_name(statement.body[0])
    if name is None:
        return None
    for place in range(len(out) - 1, -1, -1):
        default = out[place]
        if isinstance(default, ast.Assign) and assigned_name(default) == name:
            if any(isinstance(node, ast.Call) for node in ast.walk(default.value)):
                return None
            read = _names(default.value)
            between = out[place + 1 :]
            if all(name not in _names(s) and not (_assigned(s) & read) for s in between):
                return place
            return None
    return None


def _names(node: ast.AST) -> set[str]:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}


def _assigned(node: ast.AST) -> set[str]:
    return {
        n.id for n in ast.walk(node) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store | ast.Del)
    }


def _merged(previous: ast.stmt, statement: ast.stmt) -> ast.stmt | None:
    """One statement for ``x = b`` then ``if c: x = a`` (``x = a if c else b``), and for
    ``if c: return a`` then ``return b``; else None."""
    if (
        isinstance(previous, ast.If)
        and not previous.orelse
        and len(previous.body) == 1
        and isinstance(statement, ast.Return)
        and isinstance(previous.body[0], ast.Return)
    ):
        return _choice(previous.body[0], statement, previous.test)
    if isinstance(statement, ast.If) and not statement.orelse and len(statement.body) == 1:
        name = assigned_name(previous)
        if name is not None and name == assigned_name(statement.body[0]):
            return _choice(statement.body[0], previous, statement.test)
    return None


def _comprehensions(statements: list[ast.stmt]) -> list[ast.stmt]:
    """``out = []`` then a loop that only appends to ``out`` as ``out = [... for ...]`` (and
    ``d = {}`` then a loop that only sets ``d[k]`` as a dict comprehension)."""
    out = list(statements)
    for i in range(len(out) - 1, -1, -1):
        loop = out[i] if i < len(out) else None
        built = _built(loop) if isinstance(loop, ast.For) else None
        if built is None:
            continue
        name, comprehension = built
        for j in range(i - 1, max(-1, i - 1 - LOOK_BACK), -1):
            if not any(isinstance(n, ast.Name) and n.id == name for n in ast.walk(out[j])):
                continue
            earlier = out[j]
            if (
                isinstance(earlier, ast.Assign)
                and assigned_name(earlier) == name
                and _is_empty(earlier.value, type(comprehension))
            ):
                out[j] = ast.copy_location(ast.Assign([ast.Name(name, ast.Store())], comprehension), earlier)
                del out[i]
            break
    return out


def _is_empty(value: ast.expr, kind: type) -> bool:
    """Whether ``value`` makes an empty list (``kind`` ListComp) or dict (DictComp)."""
    if kind is ast.ListComp and isinstance(value, ast.List) and not value.elts:
        return True
    if kind is ast.DictComp and isinstance(value, ast.Dict) and not value.keys:
        return True
    builder = "builtins.list" if kind is ast.ListComp else "builtins.dict"
    return (
        isinstance(value, ast.Call)
        and dotted_name(value.func) == builder
        and not value.args
        and not value.keywords
    )


def _built(loop: ast.For) -> tuple[str, ast.ListComp | ast.DictComp] | None:
    """(the name, the comprehension) if ``loop`` (with the loops and ifs nested in it) only
    appends to a list or sets a dict's items, and reads that name nowhere else."""
    generators: list[ast.comprehension] = []
    node: ast.stmt = loop
    while isinstance(node, ast.For | ast.If) and not node.orelse:
        if isinstance(node, ast.For):
            generators.append(ast.comprehension(node.target, node.iter, [], 0))
        elif generators:
            generators[-1].ifs.append(node.test)
        body = statements_of(node.body)
        if len(body) != 1:
            return None
        node = body[0]
    filled = _filled(node, generators) if generators else None
    if filled is None:
        return None
    name, built = filled
    reads = [n for g in generators for n in ast.walk(g)] + list(ast.walk(built))
    return None if any(isinstance(n, ast.Name) and n.id == name for n in reads) else (name, built)


def _filled(
    step: ast.stmt, generators: list[ast.comprehension]
) -> tuple[str, ast.ListComp | ast.DictComp] | None:
    """(name, comprehension) for a loop's only step ``out.append(e)`` or ``out[k] = v``."""
    call = step.value if isinstance(step, ast.Expr) else None
    if isinstance(call, ast.Call) and len(call.args) == 1 and not call.keywords:
        func = call.func
        if isinstance(func, ast.Attribute) and func.attr == "append" and isinstance(func.value, ast.Name):
            return func.value.id, ast.ListComp(call.args[0], generators)
    if isinstance(step, ast.Assign) and len(step.targets) == 1:
        target = step.targets[0]
        if isinstance(target, ast.Subscript) and isinstance(target.value, ast.Name):
            return target.value.id, ast.DictComp(target.slice, step.value, generators)
    return None
