"""The canonical form's syntax: operators called as functions written as operators,
attributes read by name written as attributes, and arithmetic in one form.

``operator.add(a, b)``, ``np.add(a, b)`` and ``a.__add__(b)`` are ``a + b`` (every operator
of the ``operator`` module, and the NumPy functions that mean one); ``getattr(x, "a")`` and
``vars(x)["a"]`` are ``x.a``; ``a + (-b)`` is ``a - b``, ``a * (1 / b)`` is ``a / b``, ``x
** 0.5`` is ``np.sqrt(x)``, ``x + 0`` and ``x * 1`` are ``x``, arithmetic on numbers is done
(``1 / 2`` is ``0.5``), ``not a < b`` is ``a >= b``, ``b if not c else a`` is ``a if c else
b``. NumPy's functions that are one another are one: ``np.fmax`` is ``np.maximum``,
``np.select([c], [a], b)`` is ``np.where(c, a, b)``, ``np.nonzero(np.ravel(x))[0]`` is
``np.flatnonzero(x)``, ``a.take(r)`` and ``np.take(a, r)`` are ``a[r]``. The tree's
names are resolved first (``ptlab.course.sandbox.canonical_names``): ``np.add`` is read as
``numpy.add`` however the file imports it.
"""

from __future__ import annotations

import ast
from typing import TypeGuard

from ptlab.course.sandbox.syntax_trees import dotted_name, dotted_node, identifier


def as_syntax(tree: ast.AST) -> ast.AST:
    """``tree`` (changed in place, its names resolved) with its operators, attributes and
    arithmetic in one form (the module docstring lists the forms)."""
    return _Syntax().visit(tree)


# What functions and methods an operator is (Python's ``operator`` module, NumPy's ufuncs
# of the same meaning, the special methods): {operator: (its name, NumPy's names)}.
_BINARY = {
    ast.Add: ("add", ("add",)),
    ast.Sub: ("sub", ("subtract",)),
    ast.Mult: ("mul", ("multiply",)),
    ast.Div: ("truediv", ("divide", "true_divide")),
    ast.FloorDiv: ("floordiv", ("floor_divide",)),
    ast.Mod: ("mod", ("mod", "remainder")),
    ast.Pow: ("pow", ("power",)),
    ast.MatMult: ("matmul", ("matmul",)),
    ast.LShift: ("lshift", ("left_shift",)),
    ast.RShift: ("rshift", ("right_shift",)),
    ast.BitAnd: ("and", ("bitwise_and", "logical_and")),
    ast.BitOr: ("or", ("bitwise_or", "logical_or")),
    ast.BitXor: ("xor", ("bitwise_xor", "logical_xor")),
}
_UNARY = {
    ast.USub: ("neg", ("negative",)),
    ast.UAdd: ("pos", ("positive",)),
    ast.Invert: ("invert", ("invert", "bitwise_not", "logical_not")),
    ast.Not: ("not", ()),
}
_COMPARE = {
    ast.Lt: ("lt", ("less",)),
    ast.LtE: ("le", ("less_equal",)),
    ast.Eq: ("eq", ("equal",)),
    ast.NotEq: ("ne", ("not_equal",)),
    ast.GtE: ("ge", ("greater_equal",)),
    ast.Gt: ("gt", ("greater",)),
}
_INVERSE = {
    ast.Eq: ast.NotEq,
    ast.NotEq: ast.Eq,
    ast.Lt: ast.GtE,
    ast.GtE: ast.Lt,
    ast.Gt: ast.LtE,
    ast.LtE: ast.Gt,
    ast.In: ast.NotIn,
    ast.NotIn: ast.In,
    ast.Is: ast.IsNot,
    ast.IsNot: ast.Is,
}


def _operator_functions() -> tuple[dict[str, tuple[str, type]], dict[str, tuple[str, type, bool]]]:
    """({dotted function: (kind, operator)}, {special method: (kind, operator, reflected)})."""
    functions: dict[str, tuple[str, type]] = {}
    methods: dict[str, tuple[str, type, bool]] = {}
    for kind, table in (("binary", _BINARY), ("unary", _UNARY), ("compare", _COMPARE)):
        for op, (name, numpy_names) in table.items():
            plain = f"{name}_" if name in ("and", "or", "not") else name
            names = [plain, f"__{name}__"] + ([f"i{name}", f"__i{name}__"] if kind == "binary" else [])
            functions.update((f"operator.{n}", (kind, op)) for n in names)
            functions.update((f"numpy.{n}", (kind, op)) for n in numpy_names)
            methods[f"__{name}__"] = (kind, op, False)
            if kind == "binary":
                methods[f"__r{name}__"] = (kind, op, True)
                methods[f"__i{name}__"] = (kind, op, False)
    functions.update({"operator.inv": ("unary", ast.Invert), "operator.__inv__": ("unary", ast.Invert)})
    functions.update({"math.pow": ("binary", ast.Pow), "builtins.pow": ("binary", ast.Pow)})
    functions.update({"operator.is_": ("compare", ast.Is), "operator.is_not": ("compare", ast.IsNot)})
    functions.update(
        {"operator.getitem": ("item", ast.Subscript), "operator.__getitem__": ("item", ast.Subscript)}
    )
    functions.update(
        {"operator.contains": ("contains", ast.In), "operator.__contains__": ("contains", ast.In)}
    )
    methods.update(
        {"__getitem__": ("item", ast.Subscript, False), "__contains__": ("contains", ast.In, False)}
    )
    return functions, methods


_OPERATOR_FUNCTIONS, _OPERATOR_METHODS = _operator_functions()
#: Functions that are one another (read as the first name's function).
_SYNONYMS = {
    "numpy.absolute": "builtins.abs",
    "numpy.abs": "builtins.abs",
    "math.fabs": "builtins.abs",
    "operator.abs": "builtins.abs",
    "operator.__abs__": "builtins.abs",
    "math.sqrt": "numpy.sqrt",
    # (they differ only where an operand is NaN)
    "numpy.fmax": "numpy.maximum",
    "numpy.fmin": "numpy.minimum",
}
#: The ways to read an attribute by its name: ``getattr(x, "a")`` and the special methods.
_ATTRIBUTE_READERS = ("builtins.getattr", "builtins.object.__getattribute__")


class _Syntax(ast.NodeTransformer):
    """Operators called as functions written as operators, attributes read by name written
    as attributes, and arithmetic in one form (the module docstring lists the forms)."""

    def visit_Call(self, node: ast.Call) -> ast.expr:
        self.generic_visit(node)
        return _call_as_syntax(node)

    def visit_BinOp(self, node: ast.BinOp) -> ast.expr:
        self.generic_visit(node)
        return _arithmetic(node)

    def visit_UnaryOp(self, node: ast.UnaryOp) -> ast.expr:
        self.generic_visit(node)
        return _unary(node)

    def visit_IfExp(self, node: ast.IfExp) -> ast.expr:
        self.generic_visit(node)
        if isinstance(node.test, ast.UnaryOp) and isinstance(node.test.op, ast.Not):
            node.test, node.body, node.orelse = node.test.operand, node.orelse, node.body
        return node

    def visit_Attribute(self, node: ast.Attribute) -> ast.expr:
        self.generic_visit(node)
        if dotted_name(node) == "numpy.newaxis":
            return ast.copy_location(ast.Constant(None), node)
        return node

    def visit_Subscript(self, node: ast.Subscript) -> ast.expr:
        # ``vars(x)["a"]`` and ``x.__dict__["a"]`` are ``x.a``, read or written.
        self.generic_visit(node)
        name = identifier(node.slice)
        value = node.value
        if name is None:
            return _flat_nonzero(node)
        if (
            isinstance(value, ast.Call)
            and dotted_name(value.func) == "builtins.vars"
            and len(value.args) == 1
        ):
            return ast.copy_location(ast.Attribute(value.args[0], name, node.ctx), node)
        if isinstance(value, ast.Attribute) and value.attr == "__dict__":
            return ast.copy_location(ast.Attribute(value.value, name, node.ctx), node)
        return node


def _call_as_syntax(node: ast.Call) -> ast.expr:
    """The call ``node`` written as the syntax it stands for, if it stands for one."""
    func, arguments = node.func, node.args
    plain = not node.keywords and not any(isinstance(a, ast.Starred) for a in arguments)
    dotted = dotted_name(func)
    synonym = _synonym(node)
    if synonym is not None:
        return ast.copy_location(synonym, node)
    built = None
    if plain and dotted in _OPERATOR_FUNCTIONS:
        built = _operation(*_OPERATOR_FUNCTIONS[dotted], arguments)
    elif plain and isinstance(func, ast.Attribute) and func.attr in _OPERATOR_METHODS:
        kind, op, reflected = _OPERATOR_METHODS[func.attr]
        operands = [func.value, *arguments]
        built = _operation(kind, op, operands[::-1] if reflected else operands)
    elif (
        plain and dotted in _ATTRIBUTE_READERS and len(arguments) == 2 and (name := identifier(arguments[1]))
    ):
        built = ast.Attribute(arguments[0], name, ast.Load())
    elif plain and isinstance(func, ast.Attribute) and func.attr in ("__getattribute__", "__getattr__"):
        if len(arguments) == 1 and (name := identifier(arguments[0])):
            built = ast.Attribute(func.value, name, ast.Load())
    elif isinstance(func, ast.Attribute) and func.attr == "__call__":
        built = ast.Call(func.value, arguments, node.keywords)
    elif plain and isinstance(func, ast.Call) and len(arguments) == 1:
        built = _curried(func, arguments[0])
    elif plain and dotted == "builtins.slice" and 1 <= len(arguments) <= 3:
        bounds = [None, *arguments] if len(arguments) == 1 else arguments
        bounds = [None if _is_none(b) else b for b in [*bounds, None, None][:3]]
        built = ast.Slice(*bounds)
    elif (
        plain
        and dotted in ("builtins.float", "builtins.int")
        and len(arguments) == 1
        and _is_number(arguments[0])
    ):
        built = ast.Constant(arguments[0].value)
    return ast.copy_location(built, node) if built is not None else node


def _synonym(node: ast.Call) -> ast.expr | None:
    """The call ``node`` as the function it is one with (``_SYNONYMS``, ``np.select`` of one
    condition, ``take`` without an axis), or None."""
    func, arguments, dotted = node.func, node.args, dotted_name(node.func)
    if dotted in _SYNONYMS:
        return ast.Call(dotted_node(_SYNONYMS[dotted], func), arguments, node.keywords)
    if dotted == "numpy.select":
        return _select_as_where(node)
    if node.keywords or any(isinstance(a, ast.Starred) for a in arguments):
        return None
    if dotted == "numpy.take":
        operands = arguments
    elif isinstance(func, ast.Attribute) and func.attr == "take":
        operands = [func.value, *arguments]
    else:
        return None
    if len(operands) == 2:  # (no axis: the flattened array's items, as ``a[r]`` for a vector)
        return ast.Subscript(operands[0], operands[1], ast.Load())
    return None


def _select_as_where(node: ast.Call) -> ast.expr | None:
    """``np.select([c], [a], b)`` (one condition; ``b`` 0 if not given) as ``np.where(c, a, b)``."""
    arguments = list(node.args)
    for keyword in node.keywords:
        if keyword.arg != "default" or len(arguments) != 2:
            return None
        arguments.append(keyword.value)
    if len(arguments) == 2:
        arguments.append(ast.Constant(0))
    conditions, choices, default = arguments
    if not (isinstance(conditions, ast.List | ast.Tuple) and isinstance(choices, ast.List | ast.Tuple)):
        return None
    if (
        len(conditions.elts) != 1
        or len(choices.elts) != 1
        or any(isinstance(a, ast.Starred) for a in arguments)
    ):
        return None
    where = dotted_node("numpy.where", node.func)
    return ast.Call(where, [conditions.elts[0], choices.elts[0], default], [])


def _flat_nonzero(node: ast.Subscript) -> ast.expr:
    """``np.nonzero(np.ravel(x))[0]`` and ``np.nonzero(x.ravel())[0]`` as ``np.flatnonzero(x)``."""
    nonzero = node.value
    if not (
        isinstance(node.ctx, ast.Load)
        and _is_number(node.slice, 0)
        and isinstance(nonzero, ast.Call)
        and dotted_name(nonzero.func) == "numpy.nonzero"
        and len(nonzero.args) == 1
        and not nonzero.keywords
        and isinstance(nonzero.args[0], ast.Call)
    ):
        return node
    ravel = nonzero.args[0]
    if ravel.keywords or any(isinstance(a, ast.Starred) for a in ravel.args):
        return node
    if dotted_name(ravel.func) == "numpy.ravel" and len(ravel.args) == 1:
        flattened = ravel.args[0]
    elif isinstance(ravel.func, ast.Attribute) and ravel.func.attr == "ravel" and not ravel.args:
        flattened = ravel.func.value
    else:
        return node
    flat = dotted_node("numpy.flatnonzero", nonzero.func)
    return ast.copy_location(ast.Call(flat, [flattened], []), node)


def _curried(maker: ast.Call, operand: ast.expr) -> ast.expr | None:
    """``operator.attrgetter("a")(x)``, ``itemgetter(k)(x)`` and ``methodcaller("m",
    ...)(x)`` as the syntax they stand for."""
    dotted, arguments = dotted_name(maker.func), maker.args
    if dotted == "operator.attrgetter" and len(arguments) == 1 and isinstance(arguments[0], ast.Constant):
        path = str(arguments[0].value).split(".")
        if all(part.isidentifier() for part in path):
            for part in path:
                operand = ast.Attribute(operand, part, ast.Load())
            return operand
    if dotted == "operator.itemgetter" and len(arguments) == 1 and not maker.keywords:
        return ast.Subscript(operand, arguments[0], ast.Load())
    if dotted == "operator.methodcaller" and arguments and (name := identifier(arguments[0])):
        return ast.Call(ast.Attribute(operand, name, ast.Load()), arguments[1:], maker.keywords)
    return None


def _operation(kind: str, op: type, operands: list[ast.expr]) -> ast.expr | None:
    """The operator ``op`` (of ``kind``, see ``_operator_functions``) applied to ``operands``."""
    if kind == "binary" and len(operands) == 2:
        return _arithmetic(ast.BinOp(operands[0], op(), operands[1]))
    if kind == "unary" and len(operands) == 1:
        return _unary(ast.UnaryOp(op(), operands[0]))
    if kind == "compare" and len(operands) == 2:
        return ast.Compare(operands[0], [op()], [operands[1]])
    if kind == "item" and len(operands) == 2:
        return ast.Subscript(operands[0], operands[1], ast.Load())
    if kind == "contains" and len(operands) == 2:
        return ast.Compare(operands[1], [ast.In()], [operands[0]])
    return None


def _is_number(node: ast.AST, value: float | None = None) -> TypeGuard[ast.Constant]:
    """Whether ``node`` is a number (equal to ``value``, if given); booleans are not numbers."""
    if not isinstance(node, ast.Constant) or isinstance(node.value, bool):
        return False
    if not isinstance(node.value, int | float):
        return False
    return value is None or node.value == value


def _is_none(node: ast.AST | None) -> bool:
    return node is None or (isinstance(node, ast.Constant) and node.value is None)


def _negated(node: ast.AST) -> TypeGuard[ast.UnaryOp]:
    return isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub)


_FOLDED = {
    ast.Add: lambda a, b: a + b,
    ast.Sub: lambda a, b: a - b,
    ast.Mult: lambda a, b: a * b,
    ast.Div: lambda a, b: a / b,
    ast.FloorDiv: lambda a, b: a // b,
    ast.Mod: lambda a, b: a % b,
    ast.Pow: lambda a, b: a**b if abs(b) <= 64 and abs(a) <= 1e6 else None,
}


def _arithmetic(node: ast.BinOp) -> ast.expr:
    """``node`` in the one form the module docstring gives its kind of arithmetic."""
    folded = _folded(node)
    if folded is not None:
        return folded
    if isinstance(node.op, ast.Add | ast.Sub):
        return _sum(node)
    if isinstance(node.op, ast.Mult | ast.Div | ast.Pow):
        return _product(node)
    return node


def _folded(node: ast.BinOp) -> ast.Constant | None:
    """Arithmetic on two numbers as the number it makes (``1 / 2`` as ``0.5``), or None."""
    if not (_is_number(node.left) and _is_number(node.right) and type(node.op) in _FOLDED):
        return None
    try:
        value = _FOLDED[type(node.op)](node.left.value, node.right.value)
    except (ZeroDivisionError, OverflowError, ValueError):
        return None
    return ast.copy_location(ast.Constant(value), node) if isinstance(value, int | float) else None


def _sum(node: ast.BinOp) -> ast.expr:
    """``a + (-b)`` as ``a - b``, ``a - (-b)`` as ``a + b``, ``0 - a`` as ``-a``, ``a + 0`` as ``a``."""
    left, right = node.left, node.right
    if isinstance(node.op, ast.Add) and _negated(right):
        return _arithmetic(ast.copy_location(ast.BinOp(left, ast.Sub(), right.operand), node))
    if isinstance(node.op, ast.Add) and _negated(left):
        return _arithmetic(ast.copy_location(ast.BinOp(right, ast.Sub(), left.operand), node))
    if isinstance(node.op, ast.Sub) and _negated(right):
        return _arithmetic(ast.copy_location(ast.BinOp(left, ast.Add(), right.operand), node))
    if _is_number(right, 0):
        return left
    if _is_number(left, 0):
        return (
            right
            if isinstance(node.op, ast.Add)
            else _unary(ast.copy_location(ast.UnaryOp(ast.USub(), right), node))
        )
    return node


def _product(node: ast.BinOp) -> ast.expr:
    """``a * (1 / b)`` as ``a / b``, ``-1 * a`` as ``-a``, ``a * 1`` and ``a / 1`` as ``a``,
    ``x ** 0.5`` as ``np.sqrt(x)``, ``x ** -1`` as ``1 / x``."""
    left, op, right = node.left, node.op, node.right
    if isinstance(op, ast.Pow) and _is_number(right, 0.5):
        return ast.copy_location(ast.Call(dotted_node("numpy.sqrt", node), [left], []), node)
    if isinstance(op, ast.Pow) and _is_number(right, -1):
        return _arithmetic(ast.copy_location(ast.BinOp(ast.Constant(1.0), ast.Div(), left), node))
    if isinstance(op, ast.Div) and _is_number(right, 1):
        return left
    for one, other in ((left, right), (right, left)) if isinstance(op, ast.Mult) else ():
        if _is_number(other, 1):
            return one
        if _is_number(other, -1):
            return _unary(ast.copy_location(ast.UnaryOp(ast.USub(), one), node))
        if isinstance(other, ast.BinOp) and isinstance(other.op, ast.Div) and _is_number(other.left, 1):
            return ast.copy_location(ast.BinOp(one, ast.Div(), other.right), node)
    return node


def _unary(node: ast.UnaryOp) -> ast.expr:
    """``node`` with constants folded, ``+x`` and ``--x`` as ``x``, ``not a < b`` as ``a >= b``."""
    operand = node.operand
    if isinstance(node.op, ast.USub | ast.UAdd) and _is_number(operand):
        # (``_is_number``: the constant is an int or a float, which negate.)
        value = -operand.value if isinstance(node.op, ast.USub) else operand.value  # type: ignore[operator]
        return ast.copy_location(ast.Constant(value), node)
    if isinstance(node.op, ast.UAdd):
        return operand
    if (
        isinstance(operand, ast.UnaryOp)
        and type(operand.op) is type(node.op)
        and isinstance(node.op, ast.USub | ast.Not)
    ):
        return operand.operand
    if isinstance(node.op, ast.Not) and isinstance(operand, ast.Compare) and len(operand.ops) == 1:
        inverse = _INVERSE.get(type(operand.ops[0]))
        if inverse is not None:
            return ast.copy_location(ast.Compare(operand.left, [inverse()], operand.comparators), node)
    return node
