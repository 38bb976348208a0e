"""Mechanical rewrites of a copied file: what a copier's small script does to hide a copy.

Each rewriter is an ``ast.NodeTransformer`` whose ``rewrite(tree)`` returns a rewritten
copy of a module; none changes what the file computes (up to floating-point rounding where
it moves arithmetic), nor the names the grader looks up (``keep``). ``REWRITES`` names
them and their combinations; ``rewritten(source, rewrite, keep)`` gives the text a student
would hand in. The copy detector (``ptlab.course.sandbox.copies``) must see through every one:
``scripts/copy_detection.py`` measures it, ``tests/attacks/test_copies.py`` checks it.
"""

from __future__ import annotations

import ast
import builtins
import copy
from collections.abc import Iterator

#: Operators and the ``operator`` functions a rewrite writes them as.
BINARY_FUNCTIONS = {
    ast.Add: "add",
    ast.Sub: "sub",
    ast.Mult: "mul",
    ast.Div: "truediv",
    ast.FloorDiv: "floordiv",
    ast.Mod: "mod",
    ast.Pow: "pow",
    ast.MatMult: "matmul",
    ast.BitAnd: "and_",
    ast.BitOr: "or_",
    ast.BitXor: "xor",
    ast.LShift: "lshift",
    ast.RShift: "rshift",
}
UNARY_FUNCTIONS = {ast.USub: "neg", ast.UAdd: "pos", ast.Invert: "invert", ast.Not: "not_"}
COMPARE_FUNCTIONS = {ast.Lt: "lt", ast.LtE: "le", ast.Eq: "eq", ast.NotEq: "ne", ast.Gt: "gt", ast.GtE: "ge"}


class Rewriter(ast.NodeTransformer):
    """A mechanical rewrite of a module that keeps the names ``keep`` (what the grader
    looks up: the exercise's functions, classes and methods)."""

    def __init__(self, keep: frozenset[str] = frozenset()):
        self.keep = keep

    def rewrite(self, tree: ast.Module) -> ast.Module:
        """A rewritten copy of ``tree``."""
        return ast.fix_missing_locations(self.apply(copy.deepcopy(tree)))

    def apply(self, tree: ast.Module) -> ast.Module:
        """``tree`` rewritten in place (and returned)."""
        return self.visit(tree)


def _name(text: str, ctx: ast.expr_context | None = None) -> ast.Name:
    return ast.Name(text, ctx or ast.Load())


def _call(function: str, *arguments: ast.expr) -> ast.Call:
    parts = function.split(".")
    func: ast.expr = _name(parts[0])
    for part in parts[1:]:
        func = ast.Attribute(func, part, ast.Load())
    return ast.Call(func, list(arguments), [])


def _with_import(tree: ast.Module, statement: str) -> ast.Module:
    """``tree`` with ``statement`` (an import) after its ``from __future__`` imports."""
    at = sum(1 for s in tree.body if isinstance(s, ast.ImportFrom) and s.module == "__future__")
    tree.body[at:at] = ast.parse(statement).body
    return tree


def _functions(tree: ast.AST) -> Iterator[ast.FunctionDef]:
    return (node for node in ast.walk(tree) if isinstance(node, ast.FunctionDef))


def _top_level_names(tree: ast.Module) -> set[str]:
    """The functions, classes and assigned names of the module's top level."""
    names = set()
    for node in tree.body:
        if isinstance(node, ast.FunctionDef | ast.ClassDef):
            names.add(node.name)
        elif isinstance(node, ast.Assign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            names |= {t.id for t in targets if isinstance(t, ast.Name)}
    return names


def _imported_names(tree: ast.Module) -> set[str]:
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import | ast.ImportFrom):
            names |= {(a.asname or a.name).split(".")[0] for a in node.names}
    return names


def _bound_in(function: ast.AST) -> set[str]:
    """The names a function binds: its parameters and whatever it assigns (nested ones too)."""
    names = {a.arg for a in ast.walk(function) if isinstance(a, ast.arg)}
    names |= {n.id for n in ast.walk(function) if isinstance(n, ast.Name) and not isinstance(n.ctx, ast.Load)}
    return names


def _reads(node: ast.AST) -> set[str]:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}


def _writes(node: ast.AST) -> set[str]:
    """The names ``node`` assigns, and those whose attributes or items it assigns."""
    targets = [
        t
        for n in ast.walk(node)
        if isinstance(n, ast.Assign | ast.AugAssign | ast.AnnAssign)
        for t in (n.targets if isinstance(n, ast.Assign) else [n.target])
    ]
    written = {n.id for n in ast.walk(node) if isinstance(n, ast.Name) and not isinstance(n.ctx, ast.Load)}
    return written | {n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)}


def _is_text(node: ast.AST) -> bool:
    return isinstance(node, ast.Constant) and isinstance(node.value, str | bytes)


def _is_docstring(statement: ast.stmt) -> bool:
    return (
        isinstance(statement, ast.Expr)
        and isinstance(statement.value, ast.Constant)
        and isinstance(statement.value.value, str)
    )


class RenameEverything(Rewriter):
    """Every variable, parameter, helper and class of the file renamed (``v0``, ``v1``...,
    and the keyword arguments that name its own functions' parameters), docstrings and
    annotations dropped."""

    def apply(self, tree: ast.Module) -> ast.Module:
        fixed = _imported_names(tree) | set(dir(builtins)) | {"self", "cls"}
        module = sorted(_top_level_names(tree) - self.keep - fixed)
        local = sorted({name for f in _functions(tree) for name in _bound_in(f)} - fixed - set(module))
        self.names = {name: f"g{i}" for i, name in enumerate(module)}
        self.names |= {name: f"v{i}" for i, name in enumerate(local)}
        self.own = _top_level_names(tree)
        return ast.fix_missing_locations(self.visit(tree))

    def visit_FunctionDef(self, node: ast.FunctionDef) -> ast.FunctionDef:
        node.returns = None
        node.body = [s for s in node.body if not _is_docstring(s)] or [ast.Pass()]
        node.name = self.names.get(node.name, node.name)
        self.generic_visit(node)
        return node

    def visit_ClassDef(self, node: ast.ClassDef) -> ast.ClassDef:
        node.body = [s for s in node.body if not _is_docstring(s)] or [ast.Pass()]
        node.name = self.names.get(node.name, node.name)
        self.generic_visit(node)
        return node

    def visit_arg(self, node: ast.arg) -> ast.arg:
        node.arg, node.annotation = self.names.get(node.arg, node.arg), None
        return node

    def visit_Name(self, node: ast.Name) -> ast.Name:
        node.id = self.names.get(node.id, node.id)
        return node

    def visit_AnnAssign(self, node: ast.AnnAssign) -> ast.stmt:
        self.generic_visit(node)
        return ast.Assign([node.target], node.value) if node.value is not None else ast.Pass()

    def visit_Call(self, node: ast.Call) -> ast.Call:
        func = node.func
        own = (isinstance(func, ast.Name) and func.id in self.own) or (
            isinstance(func, ast.Attribute)
            and isinstance(func.value, ast.Name)
            and func.value.id in ("self", "cls")
        )
        self.generic_visit(node)
        for keyword in node.keywords if own else []:
            keyword.arg = self.names.get(keyword.arg, keyword.arg) if keyword.arg else None
        return node


class OperatorCalls(Rewriter):
    """Every operator written as its ``operator`` function: ``operator.add(a, b)``,
    ``operator.neg(a)``, ``operator.lt(a, b)``, ``operator.getitem(a, k)``."""

    def apply(self, tree: ast.Module) -> ast.Module:
        return _with_import(self.visit(tree), "import operator")

    def visit_BinOp(self, node: ast.BinOp) -> ast.expr:
        self.generic_visit(node)
        return _call(f"operator.{BINARY_FUNCTIONS[type(node.op)]}", node.left, node.right)

    def visit_UnaryOp(self, node: ast.UnaryOp) -> ast.expr:
        self.generic_visit(node)
        if isinstance(node.operand, ast.Constant):
            return node  # (``-1`` is a number, not an operation)
        return _call(f"operator.{UNARY_FUNCTIONS[type(node.op)]}", node.operand)

    def visit_Compare(self, node: ast.Compare) -> ast.expr:
        self.generic_visit(node)
        if len(node.ops) != 1 or type(node.ops[0]) not in COMPARE_FUNCTIONS:
            return node
        return _call(f"operator.{COMPARE_FUNCTIONS[type(node.ops[0])]}", node.left, node.comparators[0])

    def visit_Subscript(self, node: ast.Subscript) -> ast.expr:
        self.generic_visit(node)
        if not isinstance(node.ctx, ast.Load):
            return node
        return _call("operator.getitem", node.value, _as_value(node.slice))


def _as_value(index: ast.expr) -> ast.expr:
    """A subscript's index as a value (``a:b`` as ``slice(a, b)``)."""
    if isinstance(index, ast.Slice):
        parts = [index.lower, index.upper, index.step]
        return _call("slice", *[p if p is not None else ast.Constant(None) for p in parts])
    if isinstance(index, ast.Tuple):
        return ast.Tuple([_as_value(e) for e in index.elts], ast.Load())
    return index


class GetattrReads(Rewriter):
    """Every attribute read through ``getattr(x, "name")``, every one written through
    ``setattr(x, "name", value)``."""

    def visit_Attribute(self, node: ast.Attribute) -> ast.expr:
        self.generic_visit(node)
        if not isinstance(node.ctx, ast.Load) or node.attr.startswith("__"):
            return node
        return _call("getattr", node.value, ast.Constant(node.attr))

    def visit_Assign(self, node: ast.Assign) -> ast.stmt:
        self.generic_visit(node)
        target = node.targets[0]
        if len(node.targets) == 1 and isinstance(target, ast.Attribute):
            return ast.Expr(_call("setattr", target.value, ast.Constant(target.attr), node.value))
        return node


class Aliases(Rewriter):
    """Imported modules under other names (``import numpy as xp``), and in every function a
    local alias for each module function it calls (``where = xp.where``)."""

    def apply(self, tree: ast.Module) -> ast.Module:
        self.renamed: dict[str, str] = {}
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    if "." not in alias.name:
                        self.renamed[alias.asname or alias.name] = f"mod_{alias.name}"
                        alias.asname = f"mod_{alias.name}"
        tree = self.visit(tree)
        for function in _functions(tree):
            self._alias_calls(function)
        return ast.fix_missing_locations(tree)

    def visit_Name(self, node: ast.Name) -> ast.Name:
        node.id = self.renamed.get(node.id, node.id)
        return node

    def _alias_calls(self, function: ast.FunctionDef) -> None:
        modules = set(self.renamed.values())
        aliases: dict[str, str] = {}
        for node in ast.walk(function):
            func = node.func if isinstance(node, ast.Call) else None
            if (
                isinstance(func, ast.Attribute)
                and isinstance(func.value, ast.Name)
                and func.value.id in modules
            ):
                dotted = f"{func.value.id}.{func.attr}"
                aliases.setdefault(dotted, f"alias_{len(aliases)}_{func.attr}")
                node.func = _name(aliases[dotted])  # type: ignore[union-attr]
        start = 1 if function.body and _is_docstring(function.body[0]) else 0
        function.body[start:start] = [
            ast.parse(f"{alias} = {dotted}").body[0] for dotted, alias in aliases.items()
        ]


class ReorderStatements(Rewriter):
    """Adjacent assignments that neither reads nor writes what the other writes swapped, in
    every block."""

    def generic_visit(self, node: ast.AST) -> ast.AST:
        super().generic_visit(node)
        for field in ("body", "orelse", "finalbody"):
            body = getattr(node, field, None)
            if not isinstance(body, list):
                continue
            i = 0
            while i < len(body) - 1:
                first, second = body[i], body[i + 1]
                if (
                    isinstance(first, ast.Assign)
                    and isinstance(second, ast.Assign)
                    and _independent(first, second)
                ):
                    body[i], body[i + 1] = second, first
                    i += 2
                else:
                    i += 1
        return node


def _independent(first: ast.stmt, second: ast.stmt) -> bool:
    return not (_writes(first) & (_reads(second) | _writes(second)) or _writes(second) & _reads(first))


class DeadCode(Rewriter):
    """What does nothing added: an unused variable and a branch that never runs at the top
    of every function, an unused parameter, ``x = x`` for its first parameter, and an
    unused helper."""

    def apply(self, tree: ast.Module) -> ast.Module:
        tree = self.visit(tree)
        tree.body += ast.parse("def _unused_helper(a, b):\n    c = a * b\n    return c + 1").body
        return ast.fix_missing_locations(tree)

    def visit_FunctionDef(self, node: ast.FunctionDef) -> ast.FunctionDef:
        self.generic_visit(node)
        start = 1 if node.body and _is_docstring(node.body[0]) else 0
        dead = ast.parse("unused_total = 0\nif unused_total > 1:\n    unused_total = unused_total * 2").body
        parameters = [a.arg for a in node.args.args if a.arg not in ("self", "cls")]
        if parameters:
            dead += ast.parse(f"{parameters[0]} = {parameters[0]}").body
        node.body[start:start] = dead
        if not node.args.vararg and not node.args.kwarg:
            node.args.kwonlyargs.append(ast.arg("unused_option"))
            node.args.kw_defaults.append(ast.Constant(None))
        return node


class ConstantForms(Rewriter):
    """Numbers in arithmetic written otherwise: an integer divided or divided by as a float
    (``x / 2`` as ``x / 2.0``), a half or a quarter as a division (``0.5`` as ``1 / 2``)."""

    def visit_BinOp(self, node: ast.BinOp) -> ast.expr:
        self.generic_visit(node)
        floats = isinstance(node.op, ast.Div)
        node.left, node.right = self._other_form(node.left, floats), self._other_form(node.right, floats)
        return node

    def _other_form(self, node: ast.expr, floats: bool) -> ast.expr:
        if not isinstance(node, ast.Constant) or isinstance(node.value, bool):
            return node
        if isinstance(node.value, int) and floats:
            return ast.Constant(float(node.value))
        if isinstance(node.value, float) and node.value in (0.5, 0.25):
            return ast.BinOp(ast.Constant(1), ast.Div(), ast.Constant(int(1 / node.value)))
        return node


#: Each comparison and the one that reads it from the other side (``a < b`` is ``b > a``).
MIRROR = {
    ast.Lt: ast.Gt,
    ast.Gt: ast.Lt,
    ast.LtE: ast.GtE,
    ast.GtE: ast.LtE,
    ast.Eq: ast.Eq,
    ast.NotEq: ast.NotEq,
}


class SwapOperands(Rewriter):
    """The operands of ``+ * & | ^ == !=`` swapped, and ``a < b`` written ``b > a``."""

    def visit_BinOp(self, node: ast.BinOp) -> ast.expr:
        self.generic_visit(node)
        sequences = (ast.List, ast.Tuple, ast.ListComp, ast.JoinedStr)
        if any(isinstance(o, sequences) or _is_text(o) for o in (node.left, node.right)):
            return node  # (``+`` joins those: their order matters)
        if isinstance(node.op, ast.Add | ast.Mult | ast.BitAnd | ast.BitOr | ast.BitXor):
            node.left, node.right = node.right, node.left
        return node

    def visit_Compare(self, node: ast.Compare) -> ast.expr:
        self.generic_visit(node)
        if len(node.ops) == 1 and type(node.ops[0]) in MIRROR:
            node.left, node.comparators = node.comparators[0], [node.left]
            node.ops = [MIRROR[type(node.ops[0])]()]
        return node


class ConditionalForms(Rewriter):
    """``x = a if c else b`` and ``return a if c else b`` written as ``if``/``else``
    statements, and ``if``/``else`` statements that each assign one name as conditional
    expressions."""

    def generic_visit(self, node: ast.AST) -> ast.AST:
        super().generic_visit(node)
        for field in ("body", "orelse"):
            body = getattr(node, field, None)
            if isinstance(body, list) and body and isinstance(body[0], ast.stmt):
                setattr(node, field, [s for statement in body for s in self._other_form(statement)])
        return node

    def _other_form(self, statement: ast.stmt) -> list[ast.stmt]:
        value = getattr(statement, "value", None)
        if isinstance(statement, ast.Assign | ast.Return) and isinstance(value, ast.IfExp):
            then, otherwise = copy.deepcopy(statement), copy.deepcopy(statement)
            then.value, otherwise.value = value.body, value.orelse
            return [ast.If(value.test, [then], [otherwise])]
        if isinstance(statement, ast.If) and len(statement.body) == 1 and len(statement.orelse) == 1:
            then, otherwise = statement.body[0], statement.orelse[0]
            if isinstance(then, ast.Assign) and isinstance(otherwise, ast.Assign):
                same = len(then.targets) == len(otherwise.targets) == 1
                same = same and ast.dump(then.targets[0]) == ast.dump(otherwise.targets[0])
                if same and isinstance(then.targets[0], ast.Name):
                    return [ast.Assign(then.targets, ast.IfExp(statement.test, then.value, otherwise.value))]
        return [statement]


class LoopForms(Rewriter):
    """List comprehensions assigned to a name written as a loop that appends, and loops
    that only append written as comprehensions."""

    def generic_visit(self, node: ast.AST) -> ast.AST:
        super().generic_visit(node)
        for field in ("body", "orelse"):
            body = getattr(node, field, None)
            if isinstance(body, list) and body and isinstance(body[0], ast.stmt):
                setattr(node, field, [s for statement in body for s in self._as_loop(statement)])
        return node

    def _as_loop(self, statement: ast.stmt) -> list[ast.stmt]:
        value = getattr(statement, "value", None)
        if not (isinstance(statement, ast.Assign) and isinstance(value, ast.ListComp)):
            return [statement]
        if len(statement.targets) != 1 or not isinstance(statement.targets[0], ast.Name):
            return [statement]
        name = statement.targets[0].id
        inner: ast.stmt = ast.Expr(_call(f"{name}.append", value.elt))
        for generator in reversed(value.generators):
            for test in reversed(generator.ifs):
                inner = ast.If(test, [inner], [])
            inner = ast.For(generator.target, generator.iter, [inner], [])
        return [ast.Assign([_name(name, ast.Store())], ast.List([], ast.Load())), inner]


class InlineHelpers(Rewriter):
    """Calls of the file's functions that only return an expression replaced by that
    expression (with the arguments in place of the parameters)."""

    def apply(self, tree: ast.Module) -> ast.Module:
        self.helpers = {}
        for node in tree.body:
            body = [s for s in getattr(node, "body", []) if not _is_docstring(s)]
            simple = isinstance(node, ast.FunctionDef) and not node.decorator_list and not node.args.vararg
            if simple and len(body) == 1 and isinstance(body[0], ast.Return) and body[0].value is not None:
                self.helpers[node.name] = node
        return ast.fix_missing_locations(self.visit(tree))

    def visit_Call(self, node: ast.Call) -> ast.expr:
        self.generic_visit(node)
        helper = self.helpers.get(node.func.id) if isinstance(node.func, ast.Name) else None
        parameters = [a.arg for a in helper.args.args] if helper else []
        if helper is None or node.keywords or len(node.args) != len(parameters) or helper.args.kwonlyargs:
            return node
        if any(isinstance(a, ast.Starred) for a in node.args):
            return node
        body = [s for s in helper.body if not _is_docstring(s)]
        return _Replace(dict(zip(parameters, node.args, strict=True))).visit(copy.deepcopy(body[0].value))


class _Replace(ast.NodeTransformer):
    def __init__(self, values: dict[str, ast.expr]):
        self.values = values

    def visit_Name(self, node: ast.Name) -> ast.expr:
        return copy.deepcopy(self.values[node.id]) if node.id in self.values else node


class ExtractHelpers(Rewriter):
    """The value of every assignment and ``return`` that does arithmetic moved into a
    helper of its own at the top of the file, called with the names it reads."""

    def apply(self, tree: ast.Module) -> ast.Module:
        self.made: list[ast.stmt] = []
        self.outside = _top_level_names(tree) | _imported_names(tree) | set(dir(builtins))
        tree = self.visit(tree)
        at = sum(1 for s in tree.body if isinstance(s, ast.Import | ast.ImportFrom))
        tree.body[at:at] = self.made
        return ast.fix_missing_locations(tree)

    def visit_Assign(self, node: ast.Assign) -> ast.stmt:
        node.value = self._extracted(node.value)
        return node

    def visit_Return(self, node: ast.Return) -> ast.stmt:
        if node.value is not None:
            node.value = self._extracted(node.value)
        return node

    def _extracted(self, value: ast.expr) -> ast.expr:
        if not isinstance(value, ast.BinOp) or any(
            isinstance(n, ast.Lambda | ast.NamedExpr | ast.comprehension | ast.Yield | ast.Await)
            for n in ast.walk(value)
        ):
            return value
        if any(
            isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == "super"
            for n in ast.walk(value)
        ):
            return value
        reads = sorted(_reads(value) - self.outside)
        name = f"_part_{len(self.made)}"
        helper = ast.FunctionDef(
            name,
            ast.arguments([], [ast.arg(r) for r in reads], None, [], [], None, []),
            [ast.Return(value)],
            [],
        )
        self.made.append(helper)
        return ast.Call(_name(name), [_name(r) for r in reads], [])


class SplitFunctions(Rewriter):
    """Every function of four statements or more split in two: its first half a helper that
    returns what the second half needs, its second half a helper that gets it."""

    def apply(self, tree: ast.Module) -> ast.Module:
        self.made: list[ast.stmt] = []
        tree = self.visit(tree)
        tree.body += self.made
        return ast.fix_missing_locations(tree)

    def visit_FunctionDef(self, node: ast.FunctionDef) -> ast.FunctionDef:
        body = [s for s in node.body if not _is_docstring(s)]
        cut = len(body) // 2
        first, second = body[:cut], body[cut:]
        flow = (ast.Return, ast.Yield, ast.YieldFrom, ast.Global, ast.Nonlocal, ast.FunctionDef, ast.ClassDef)
        if (
            len(body) < 4
            or node.args.vararg
            or node.args.kwarg
            or any(isinstance(n, flow) for s in first for n in ast.walk(s))
        ):
            return node
        if any(isinstance(n, ast.Name) and n.id == "super" for n in ast.walk(node)):
            return node  # (``super()`` needs the method's class)
        parameters = [a.arg for a in node.args.posonlyargs + node.args.args + node.args.kwonlyargs]
        needed = sorted(_writes(ast.Module(first, [])) & _reads(ast.Module(second, [])))
        carried = [n for n in needed if n not in parameters]  # (parameters changed come back)
        stem = node.name.strip("_")  # (a name with two leading underscores is mangled in a class)
        names = f"_{stem}_first_{len(self.made)}", f"_{stem}_second_{len(self.made)}"
        result = ast.Tuple([_name(n) for n in needed], ast.Load()) if needed else ast.Constant(None)
        arguments = ast.arguments([], [ast.arg(p) for p in parameters], None, [], [], None, [])
        later = ast.arguments([], [ast.arg(p) for p in [*parameters, *carried]], None, [], [], None, [])
        self.made += [
            ast.FunctionDef(names[0], arguments, [*first, ast.Return(result)], []),
            ast.FunctionDef(names[1], later, second, []),
        ]
        call_first = ast.Call(_name(names[0]), [_name(p) for p in parameters], [])
        target = (
            ast.Tuple([_name(n, ast.Store()) for n in needed], ast.Store())
            if needed
            else _name("_", ast.Store())
        )
        call_second = ast.Call(_name(names[1]), [_name(p) for p in [*parameters, *carried]], [])
        node.body = [ast.Assign([target], call_first), ast.Return(call_second)]
        return node


class WrapInClass(Rewriter):
    """The file's functions made static methods of one class, and the exercise's functions
    taken from it under their names."""

    def apply(self, tree: ast.Module) -> ast.Module:
        functions = [n for n in tree.body if isinstance(n, ast.FunctionDef)]
        if not functions:
            return tree
        moved = {f.name for f in functions}
        for node in ast.walk(tree):
            if isinstance(node, ast.Name) and node.id in moved and isinstance(node.ctx, ast.Load):
                node.id = f"_Functions.{node.id}"  # (unparsed as the attribute it reads)
        for function in functions:
            function.decorator_list.append(_name("staticmethod"))
        holder = ast.ClassDef("_Functions", [], [], functions, [])
        exported = [ast.parse(f"{f.name} = _Functions.{f.name}").body[0] for f in functions]
        others = [n for n in tree.body if not isinstance(n, ast.FunctionDef)]
        first_class = next((i for i, n in enumerate(others) if isinstance(n, ast.ClassDef)), len(others))
        tree.body = [*others[:first_class], holder, *exported, *others[first_class:]]
        return ast.fix_missing_locations(ast.parse(ast.unparse(tree)))


class OperatorTable(Rewriter):
    """Every operator written as a call through a module-level dict of lambdas:
    ``OPS["Mult"](a, b)``, ``OPS["USub"](a)``, ``OPS["Lt"](a, b)`` (a red-team student's
    script; the table holds the lambdas the file calls)."""

    def apply(self, tree: ast.Module) -> ast.Module:
        taken = _top_level_names(tree) | _imported_names(tree)
        self.table = next(f"OPS{i or ''}" for i in range(len(taken) + 1) if f"OPS{i or ''}" not in taken)
        self.lambdas: dict[str, str] = {}
        tree = self.visit(tree)
        entries = ", ".join(f"{key!r}: {text}" for key, text in self.lambdas.items())
        return _with_import(tree, f"{self.table} = {{{entries}}}")

    def _through_table(self, key: str, text: str, *operands: ast.expr) -> ast.Call:
        self.lambdas[key] = text
        entry = ast.Subscript(_name(self.table), ast.Constant(key), ast.Load())
        return ast.Call(entry, list(operands), [])

    def visit_BinOp(self, node: ast.BinOp) -> ast.expr:
        self.generic_visit(node)
        key = type(node.op).__name__
        text = ast.unparse(ast.BinOp(_name("a"), node.op, _name("b")))
        return self._through_table(key, f"lambda a, b: {text}", node.left, node.right)

    def visit_UnaryOp(self, node: ast.UnaryOp) -> ast.expr:
        self.generic_visit(node)
        if isinstance(node.operand, ast.Constant):
            return node  # (``-1`` is a number, not an operation)
        key = "u" + type(node.op).__name__
        return self._through_table(
            key, f"lambda a: {ast.unparse(ast.UnaryOp(node.op, _name('a')))}", node.operand
        )

    def visit_Compare(self, node: ast.Compare) -> ast.expr:
        self.generic_visit(node)
        if len(node.ops) != 1 or type(node.ops[0]) not in COMPARE_FUNCTIONS:
            return node
        text = ast.unparse(ast.Compare(_name("a"), node.ops, [_name("b")]))
        return self._through_table(
            type(node.ops[0]).__name__, f"lambda a, b: {text}", node.left, node.comparators[0]
        )


class NumpySpellings(Rewriter):
    """NumPy's calls spelt otherwise (a red-team student's script): ``np.where(c, a, b)`` as
    ``np.select([c], [a], b)``, ``np.flatnonzero(x)`` as ``np.nonzero(np.ravel(x))[0]``,
    ``np.maximum``/``np.minimum`` as ``np.fmax``/``np.fmin`` (the same where no operand is
    NaN), ``a.take(r)`` as ``a[r]`` (the same for a vector, as the library's are)."""

    def apply(self, tree: ast.Module) -> ast.Module:
        self.numpy = {
            alias.asname or alias.name
            for node in ast.walk(tree)
            if isinstance(node, ast.Import)
            for alias in node.names
            if alias.name == "numpy"
        }
        return self.visit(tree)

    def visit_Call(self, node: ast.Call) -> ast.expr:
        self.generic_visit(node)
        func = node.func
        plain = not node.keywords and not any(isinstance(a, ast.Starred) for a in node.args)
        if not (plain and isinstance(func, ast.Attribute)):
            return node
        if isinstance(func.value, ast.Name) and func.value.id in self.numpy:
            module = func.value.id
            if func.attr == "where" and len(node.args) == 3:
                condition, chosen, default = node.args
                lists = [ast.List([condition], ast.Load()), ast.List([chosen], ast.Load())]
                return _call(f"{module}.select", *lists, default)
            if func.attr == "flatnonzero" and len(node.args) == 1:
                nonzero = _call(f"{module}.nonzero", _call(f"{module}.ravel", node.args[0]))
                return ast.Subscript(nonzero, ast.Constant(0), ast.Load())
            if func.attr in ("maximum", "minimum"):
                func.attr = {"maximum": "fmax", "minimum": "fmin"}[func.attr]
            return node
        if func.attr == "take" and len(node.args) == 1:
            return ast.Subscript(func.value, node.args[0], ast.Load())
        return node


class Combined(Rewriter):
    """Several rewrites, one after the other."""

    def __init__(self, steps: tuple[type[Rewriter], ...], keep: frozenset[str] = frozenset()):
        super().__init__(keep)
        self.steps = steps

    def apply(self, tree: ast.Module) -> ast.Module:
        for step in self.steps:
            tree = step(self.keep).apply(tree)
        return tree


#: {name: the rewrite (a Rewriter class, or the steps of a combination)}.
REWRITES: dict[str, type[Rewriter] | tuple[type[Rewriter], ...]] = {
    "as copied": (),
    "rename everything": RenameEverything,
    "operator calls": OperatorCalls,
    "getattr": GetattrReads,
    "aliases": Aliases,
    "split functions": SplitFunctions,
    "inline helpers": InlineHelpers,
    "extract helpers": ExtractHelpers,
    "reorder": ReorderStatements,
    "dead code": DeadCode,
    "constant forms": ConstantForms,
    "swap operands": SwapOperands,
    "wrap in a class": WrapInClass,
    "conditional forms": ConditionalForms,
    "loop forms": LoopForms,
    # The 35-line script: operators to ``operator`` calls, attributes to getattr.
    "operators and getattr": (RenameEverything, OperatorCalls, GetattrReads),
    "operator table": OperatorTable,
    "numpy spellings": NumpySpellings,
    # The red-team student's two scripts, one after the other.
    "numpy spellings and operator table": (NumpySpellings, OperatorTable),
    "all at once": (
        RenameEverything,
        ConditionalForms,
        LoopForms,
        InlineHelpers,
        ExtractHelpers,
        SplitFunctions,
        SwapOperands,
        ConstantForms,
        NumpySpellings,
        Aliases,
        OperatorTable,
        OperatorCalls,
        GetattrReads,
        ReorderStatements,
        DeadCode,
        WrapInClass,
    ),
}


def rewritten(source: str, rewrite: str, keep: frozenset[str] = frozenset()) -> str:
    """``source`` put through ``REWRITES[rewrite]``: the text a student would hand in."""
    steps = REWRITES[rewrite]
    rewriter = Combined(steps if isinstance(steps, tuple) else (steps,), keep)
    return ast.unparse(rewriter.rewrite(ast.parse(source))) + "\n"
