"""The canonical form's names: what each name stands for, and small helpers inlined.

In the canonical form (``ptlab.course.sandbox.canonical``) a name bound only to one import, or
only to one dotted name (``w = np.where``, in one function or several), is what it names
(read as ``np.where`` is); a builtin the file does not bind is read by name; a method's
first parameter is ``self``, a class of the file is read as ``cls``. A table of functions
(a dict of constant keys, a tuple or a list, bound once and only ever indexed by a constant)
indexed by a constant is the function it holds there: ``OPS["mul"](a, b)``, with ``OPS =
{"mul": lambda a, b: a * b}``, is a call of that lambda. Lambdas, and small
functions whose body comes down to returning one expression (``t = a * b; return t + 1``),
of the file or of the answers' modules (``Answers.helpers`` of ``ptlab.course.sandbox.copies``:
a copy may import them or paste them), are inlined where they are called.
"""

from __future__ import annotations

import ast
import builtins
from collections import defaultdict
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

from ptlab.course.sandbox.syntax_trees import (
    FunctionNode,
    assigned_name,
    dotted_name,
    dotted_node,
    identifier,
    node_count,
    statements_of,
    tree_copy,
)

#: Inlined helpers within inlined helpers, at most (a recursive one stops there).
INLINE_DEPTH = 5
#: The largest helper that is inlined (syntax-tree nodes of its body): a small helper.
HELPER_SIZE = 200
#: Syntax-tree nodes that inlining may add to one file, at most (a file built to blow up
#: when its helpers are inlined is read as written past it).
INLINE_BUDGET = 20_000
#: The attribute of a canonical function that names the helpers inlined into it.
_INLINED = "ptlab_inlined_helpers"


def resolved(tree: ast.AST) -> tuple[ast.AST, Names]:
    """``tree`` (changed in place) with every method's first parameter called ``self`` (or
    ``cls``) and the names that stand for an import, a builtin or a function written as
    what they stand for; and how its names are bound (for ``inlined``)."""
    _name_self(tree)
    names = Names(tree)
    return _Resolve(names).visit(tree), names


def inlined(tree: ast.AST, names: Names, helpers: Iterable[tuple[str, FunctionNode]] = ()) -> ast.AST:
    """``tree`` (changed in place) with the calls of its small helpers and of ``helpers``
    (the library's that it may import: (dotted name, canonical function)) replaced by what
    they return; ``names``: how its names are bound, as ``resolved`` read them."""
    names.library = dict(helpers)
    names.tables = _tables(tree, names)
    names.read_helpers(tree)
    return _Inline(names).visit(tree)


def inlined_helpers(function: FunctionNode) -> set[str]:
    """The names of the helpers ``inlined`` inlined into ``function``: their statements are
    reached from it as a called function's are."""
    return getattr(function, _INLINED, set())


def _name_self(tree: ast.AST) -> None:
    """Call every method's first parameter ``self`` (``cls`` in a class method)."""
    for node in ast.walk(tree):
        if not isinstance(node, ast.ClassDef):
            continue
        for method in node.body:
            decorators = _decorators(method)
            if not isinstance(method, FunctionNode) or "staticmethod" in decorators:
                continue
            parameters = method.args.posonlyargs + method.args.args
            name = "cls" if "classmethod" in decorators else "self"
            if parameters and parameters[0].arg != name:
                old, parameters[0].arg = parameters[0].arg, name
                for inner in ast.walk(method):
                    if isinstance(inner, ast.Name) and inner.id == old:
                        inner.id = name


class Names:
    """How each name of a tree is bound: by imports, assignments, definitions, parameters.

    Attributes:
        sites: {name: [(kind, what)]}, kind ``"import"`` (what: the dotted name imported),
            ``"value"`` (an assignment of one name: the value), ``"def"`` (a function or
            class: its node) or ``"other"`` (a parameter, a loop variable, a tuple target...).
        owners: {id of a function node: the class it is a method of, or None}.
    """

    def __init__(self, tree: ast.AST):
        self.sites: dict[str, list[tuple[str, object]]] = defaultdict(list)
        self.owners: dict[int, ast.ClassDef | None] = {}
        self.classes: dict[str, list[ast.ClassDef]] = defaultdict(list)
        self.helpers: dict[int, Helper | None] = {}
        self.budget = INLINE_BUDGET
        self.library: dict[str, FunctionNode] = {}
        self.tables: dict[str, dict[object, ast.expr]] = {}
        assigned: dict[int, ast.expr] = {}
        for node in ast.walk(tree):  # (breadth first: an assignment before its target)
            if (
                isinstance(node, ast.Assign)
                and len(node.targets) == 1
                and isinstance(node.targets[0], ast.Name)
            ):
                assigned[id(node.targets[0])] = node.value
            elif (
                isinstance(node, ast.AnnAssign)
                and node.value is not None
                and isinstance(node.target, ast.Name)
            ):
                assigned[id(node.target)] = node.value
            elif isinstance(node, ast.ClassDef):
                self.owners.update((id(m), node) for m in node.body if isinstance(m, FunctionNode))
                self.classes[node.name].append(node)
            for name, kind, what in bindings(node, assigned):
                self.sites[name].append((kind, what))

    def dotted(self, name: str, seen: tuple[str, ...] = ()) -> str | None:
        """What ``name`` stands for, if that is an import or a builtin (``numpy.where``,
        ``builtins.len``): every binding of the name imports it or assigns a dotted name
        that stands for it (``w = np.where``, in one function or several); or the name is
        a builtin the tree does not bind."""
        sites = self.sites.get(name)
        if not sites:
            return f"builtins.{name}" if hasattr(builtins, name) else None
        if name in seen or any(kind not in ("import", "value") for kind, _ in sites):
            return None
        found = {
            str(what) if kind == "import" else self.dotted_value(what, (*seen, name)) for kind, what in sites
        }
        return found.pop() if len(found) == 1 else None

    def dotted_value(self, node, seen: tuple[str, ...] = ()) -> str | None:
        """What the expression ``node`` stands for, if it is a dotted name (see ``dotted``)."""
        if isinstance(node, ast.Name):
            return self.dotted(node.id, seen)
        if isinstance(node, ast.Attribute):
            base = self.dotted_value(node.value, seen)
            return f"{base}.{node.attr}" if base else None
        if isinstance(node, ast.Call) and len(node.args) == 2 and not node.keywords:
            # (``getattr(np, "where")`` is ``np.where``, as ``canonical_syntax`` will write it)
            name = identifier(node.args[1])
            if name and self.dotted_value(node.func, seen) == "builtins.getattr":
                base = self.dotted_value(node.args[0], seen)
                return f"{base}.{name}" if base else None
        return None

    def definition(self, name: str) -> FunctionNode | ast.Lambda | None:
        """The function or lambda ``name`` is bound to, if it is bound once (directly, or
        through one assignment of another such name)."""
        sites = self.sites.get(name, [])
        if len(sites) != 1:
            return None
        kind, what = sites[0]
        if kind == "def" and isinstance(what, FunctionNode):
            return what
        if kind == "value" and isinstance(what, ast.Lambda):
            return what
        if kind == "value" and isinstance(what, ast.Name) and what.id != name:
            found = self.sites.get(what.id, [])
            if len(found) == 1 and isinstance(found[0][1], FunctionNode):
                return found[0][1]
        return None

    def read_helpers(self, tree: ast.AST) -> None:
        """Read every function and lambda of ``tree`` as a helper (``helper_of``) as it is
        written, before inlining changes any: what is inlined does not depend on the order
        of the file's functions."""
        for node in ast.walk(tree):
            if isinstance(node, FunctionNode | ast.Lambda):
                small = node_count(node) <= 2 * HELPER_SIZE  # (a bigger one is none: no need to copy it)
                self.helpers[id(node)] = helper_of(tree_copy(node)) if small else None

    def helper(self, definition: FunctionNode | ast.Lambda) -> Helper | None:
        """``helper_of(definition)``, worked out once."""
        if id(definition) not in self.helpers:
            self.helpers[id(definition)] = helper_of(definition)
        return self.helpers[id(definition)]

    def is_class(self, name: str) -> bool:
        """Whether ``name`` is bound only to one class of the tree."""
        sites = self.sites.get(name, [])
        return len(sites) == 1 and sites[0][0] == "def" and isinstance(sites[0][1], ast.ClassDef)

    def method(self, owner: str, name: str) -> FunctionNode | None:
        """The method ``name`` that ``owner.name(...)`` calls: of the one class called
        ``owner``, or for ``self`` and ``cls``, the one method of that name in the tree."""
        if owner in ("self", "cls"):
            classes = [c for found in self.classes.values() for c in found]
        else:
            classes = self.classes.get(owner, [])[:1] if len(self.classes.get(owner, [])) == 1 else []
        found = [m for c in classes for m in c.body if isinstance(m, FunctionNode) and m.name == name]
        return found[0] if len(found) == 1 else None


def bindings(node: ast.AST, assigned: dict[int, ast.expr]) -> Iterator[tuple[str, str, object]]:
    """The names ``node`` binds, each with its kind (see ``Names.sites``)."""
    if isinstance(node, ast.Import):
        for alias in node.names:
            top = alias.name.split(".")[0]
            yield (alias.asname, "import", alias.name) if alias.asname else (top, "import", top)
    elif isinstance(node, ast.ImportFrom):
        module = node.module or ""
        for alias in node.names:
            if alias.name != "*":
                yield alias.asname or alias.name, "import", f"{module}.{alias.name}"
    elif isinstance(node, FunctionNode | ast.ClassDef):
        yield node.name, "def", node
    elif isinstance(node, ast.arg):
        yield node.arg, "other", None
    elif isinstance(node, ast.Name) and not isinstance(node.ctx, ast.Load):
        value = assigned.get(id(node))
        yield (node.id, "value", value) if value is not None else (node.id, "other", None)
    elif isinstance(node, ast.ExceptHandler | ast.MatchAs | ast.MatchStar) and node.name:
        yield node.name, "other", None
    elif isinstance(node, ast.MatchMapping) and node.rest:
        yield node.rest, "other", None


def _tables(tree: ast.AST, names: Names) -> dict[str, dict[object, ast.expr]]:
    """{name: {key: function}} of the tables of functions of ``tree``: names bound once to a
    dict literal of constant keys, or to a tuple or a list, and read only as indexed by a
    constant (nothing can change what they hold); each with the entries that are functions
    (a lambda, a function of the file, an imported one)."""
    read: dict[str, int] = defaultdict(int)
    indexed: dict[str, int] = defaultdict(int)
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load):
            read[node.id] += 1
        elif (index := _table_index(node)) is not None:
            indexed[index[0]] += 1
    tables = {}
    for assignment in ast.walk(tree):  # (as the tree reads now: its operators as syntax)
        name = assigned_name(assignment)
        sites = names.sites.get(name or "", [])
        if name is None or len(sites) != 1 or sites[0][0] != "value" or read[name] != indexed[name]:
            continue
        if not isinstance(assignment, ast.Assign):  # (never: only an assignment has a name)
            continue
        value = assignment.value
        entries: list[tuple[object, ast.expr]] = []
        if isinstance(value, ast.Dict) and all(isinstance(k, ast.Constant) for k in value.keys):
            # (Every key is a constant, as tested: none is None, the ``**`` of a dict display.)
            entries = [(k.value, v) for k, v in zip(value.keys, value.values, strict=True)]  # type: ignore[union-attr]
        elif isinstance(value, ast.Tuple | ast.List) and not any(
            isinstance(e, ast.Starred) for e in value.elts
        ):
            count = len(value.elts)
            entries = [(i, e) for i, e in enumerate(value.elts)]
            entries += [(i - count, e) for i, e in enumerate(value.elts)]
        functions = {key: entry for key, entry in entries if _is_function(entry, names)}
        if functions:
            tables[name] = functions
    return tables


def _table_index(node: ast.AST) -> tuple[str, object] | None:
    """(name, key) if ``node`` reads ``name[key]``, ``key`` a constant."""
    if (
        isinstance(node, ast.Subscript)
        and isinstance(node.ctx, ast.Load)
        and isinstance(node.value, ast.Name)
        and isinstance(node.slice, ast.Constant)
    ):
        return node.value.id, node.slice.value
    return None


def _is_function(node: ast.expr, names: Names) -> bool:
    """Whether ``node`` is a lambda, or names a function of the file or an import."""
    if isinstance(node, ast.Lambda):
        return True
    if isinstance(node, ast.Name) and names.definition(node.id) is not None:
        return True
    return isinstance(node, ast.Name | ast.Attribute) and names.dotted_value(node) is not None


def _decorators(node: ast.AST) -> set[str]:
    """The names of ``node``'s decorators (``staticmethod``, resolved to a builtin or not)."""
    return {(dotted_name(d) or "").removeprefix("builtins.") for d in getattr(node, "decorator_list", ())}


class _Resolve(ast.NodeTransformer):
    """Names that stand for an import or a builtin written as what they name; a name bound
    to another function's name written as that name."""

    def __init__(self, names: Names):
        self.names = names
        # (resolved before any is rewritten: an alias's value is read as written)
        self.dotted = {name: names.dotted(name) for name in names.sites}

    def visit_Name(self, node: ast.Name) -> ast.expr:
        if not isinstance(node.ctx, ast.Load):
            return node
        dotted = self.dotted[node.id] if node.id in self.dotted else self.names.dotted(node.id)
        if dotted is not None:
            return dotted_node(dotted, node)
        definition = self.names.definition(node.id)
        if isinstance(definition, FunctionNode) and definition.name != node.id:
            return ast.copy_location(ast.Name(definition.name, ast.Load()), node)
        return node

    def visit_Attribute(self, node: ast.Attribute) -> ast.expr:
        # A class of the file holds the student's own names, as ``self`` and ``cls`` do:
        # ``Helpers.f(x)`` reads as ``cls.f(x)`` (a function moved into a class).
        value = node.value
        if isinstance(value, ast.Name) and isinstance(value.ctx, ast.Load) and self.names.is_class(value.id):
            node.value = ast.copy_location(ast.Name("cls", ast.Load()), value)
            return node
        self.generic_visit(node)
        return node


class _Inline(ast.NodeTransformer):
    """Calls of small helpers replaced by what the helper returns, with the call's
    arguments in place of its parameters (``helper_of``): the tree's lambdas and functions
    bound once (a method called through ``self``, ``cls`` or its class), and the library's
    helpers it imports (``Names.library``). A function a helper was inlined into names it
    (``inlined_helpers``): the copy detector follows it there as it follows a call."""

    def __init__(self, names: Names, depth: int = 0, within: FunctionNode | None = None):
        self.names, self.depth, self.within = names, depth, within

    def visit_FunctionDef(self, node: FunctionNode) -> FunctionNode:
        outer, self.within = self.within, node
        self.generic_visit(node)
        self.within = outer
        return node

    def visit_AsyncFunctionDef(self, node: ast.AsyncFunctionDef) -> FunctionNode:
        return self.visit_FunctionDef(node)

    def visit_Subscript(self, node: ast.Subscript) -> ast.expr:
        # (``OPS["mul"]`` is the function the table holds there: see ``_tables``)
        self.generic_visit(node)
        index = _table_index(node)
        entry = self.names.tables.get(index[0], {}).get(index[1]) if index is not None else None
        if entry is None or self.depth >= INLINE_DEPTH:
            return node
        self.names.budget -= node_count(entry)
        if self.names.budget < 0:
            return node
        return _Inline(self.names, self.depth + 1, self.within).visit(
            ast.copy_location(tree_copy(entry), node)
        )

    def visit_Call(self, node: ast.Call) -> ast.expr:
        self.generic_visit(node)
        if self.depth >= INLINE_DEPTH:
            return node
        found = self._helper(node.func)
        if found is None:
            return node
        bound = _bind(*found, node)
        if bound is None:
            return node
        helper = found[0]
        self.names.budget -= helper.size
        if self.names.budget < 0:
            return node  # (a file of helpers made to blow up when inlined is read as it is)
        if self.within is not None and helper.name:
            # (the helper's own statements stay reachable from here: see ``inlined_helpers``)
            self.within.__dict__.setdefault(_INLINED, set()).add(helper.name)
        replaced = _Substitute(bound).visit(tree_copy(helper.expression))
        return _Inline(self.names, self.depth + 1, self.within).visit(ast.copy_location(replaced, node))

    def _helper(self, func: ast.expr) -> tuple[Helper, bool] | None:
        """The small helper ``func`` calls, and whether the call binds its first parameter
        (a method called through ``self``)."""
        if isinstance(func, ast.Lambda):  # (a lambda called where it is written, or out of a table)
            # (read here, not through ``Names.helper``: a copy made by inlining may reuse
            # the id of one inlining dropped)
            helper = helper_of(func) if node_count(func) <= 2 * HELPER_SIZE else None
            return (helper, False) if helper is not None else None
        if isinstance(func, ast.Name):
            definition = self.names.definition(func.id)
            if definition is None or self.names.owners.get(id(definition)) is not None:
                return None
            helper = self.names.helper(definition)
            return (helper, False) if helper is not None else None
        library = self.names.library.get(dotted_name(func) or "")
        if library is not None:
            helper = self.names.helper(library)
            return (helper, False) if helper is not None else None
        if not (isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name)):
            return None
        definition = self.names.method(func.value.id, func.attr)
        if definition is None:
            return None
        helper = self.names.helper(definition)
        if helper is None:
            return None
        decorators = _decorators(definition)
        bound_first = "classmethod" in decorators or (
            "staticmethod" not in decorators and func.value.id in ("self", "cls")
        )
        return helper, bound_first


@dataclass(frozen=True)
class Helper:
    """A small helper: its parameters (with their defaults) and the expression it returns."""

    name: str | None
    positional: tuple[str, ...]
    keyword_only: tuple[str, ...]
    defaults: dict[str, ast.expr]
    expression: ast.expr

    @property
    def size(self) -> int:
        """The syntax-tree nodes of what it returns."""
        return sum(1 for _ in ast.walk(self.expression))


def helper_of(definition: FunctionNode | ast.Lambda) -> Helper | None:
    """``definition`` as a small helper, or None if it is not one (see ``returned``;
    ``*args`` or ``**kwargs``, decorators other than static and class methods)."""
    arguments = definition.args
    if arguments.vararg or arguments.kwarg:
        return None
    if isinstance(definition, ast.Lambda):
        expression: ast.expr | None = definition.body
    else:
        decorators = _decorators(definition)
        if isinstance(definition, ast.AsyncFunctionDef) or decorators - {"staticmethod", "classmethod"}:
            return None
        expression = returned(definition.body)
    if expression is None:
        return None
    positional = tuple(a.arg for a in arguments.posonlyargs + arguments.args)
    defaults = dict(
        zip(positional[len(positional) - len(arguments.defaults) :], arguments.defaults, strict=True)
    )
    keyword_only = tuple(a.arg for a in arguments.kwonlyargs)
    defaults.update(
        (name, d) for name, d in zip(keyword_only, arguments.kw_defaults, strict=True) if d is not None
    )
    name = getattr(definition, "name", None)
    return Helper(name, positional, keyword_only, defaults, expression)


def returned(body: list[ast.stmt]) -> ast.expr | None:
    """What a function body ending in its only ``return`` returns, its temporaries replaced
    by their values (``t = a * b; return t + 1`` returns ``a * b + 1``); None if the value
    depends on a name assigned otherwise than once, at the top, to one name. Statements
    that the value does not depend on (dead ones) change nothing."""
    body = statements_of(body)
    if not body or not isinstance(body[-1], ast.Return) or body[-1].value is None:
        return None
    if sum(1 for statement in body for _ in ast.walk(statement)) > HELPER_SIZE:
        return None  # (not a small helper)
    before = body[:-1]
    if any(isinstance(n, ast.Return | ast.Yield | ast.YieldFrom) for s in before for n in ast.walk(s)):
        return None
    stored: dict[str, int] = defaultdict(int)
    for statement in before:
        assigned = assigned_name(statement)
        if isinstance(statement, ast.Assign) and assigned and dotted_name(statement.value) == assigned:
            continue  # (``x = x`` assigns nothing)
        for node in ast.walk(statement):
            if isinstance(node, ast.Name) and not isinstance(node.ctx, ast.Load):
                stored[node.id] += 1
    values = {
        assigned: s.value
        for s in before
        if isinstance(s, ast.Assign) and (assigned := assigned_name(s)) and stored[assigned] == 1
    }
    value = body[-1].value
    for _ in range(len(values) + 1):
        nodes = list(ast.walk(value))
        names = {n.id for n in nodes if isinstance(n, ast.Name)}
        if len(nodes) > HELPER_SIZE * len(body) or any(stored[name] and name not in values for name in names):
            return None  # (temporaries that multiply, or not one value)
        if not names & values.keys():
            return value
        value = _Substitute({name: values[name] for name in names & values.keys()}).visit(tree_copy(value))
    return None


def _bind(helper: Helper, bound_first: bool, call: ast.Call) -> dict[str, ast.expr] | None:
    """{parameter: what ``call`` passes it, or its default}; None if the call leaves one
    without either, or passes what cannot be matched (``*a``, ``**k``, too many)."""
    positional = helper.positional[1:] if bound_first else helper.positional
    if bound_first and not helper.positional:
        return None
    if any(isinstance(a, ast.Starred) for a in call.args) or len(call.args) > len(positional):
        return None
    bound = dict(zip(positional, call.args, strict=False))
    for keyword in call.keywords:
        if (
            keyword.arg is None
            or keyword.arg in bound
            or keyword.arg not in (*positional, *helper.keyword_only)
        ):
            return None
        bound[keyword.arg] = keyword.value
    for name in (*positional, *helper.keyword_only):
        if name not in bound:
            if name not in helper.defaults:
                return None
            bound[name] = helper.defaults[name]
    return bound


class _Substitute(ast.NodeTransformer):
    """Names replaced by (copies of) the expressions ``bound`` gives them."""

    def __init__(self, bound: dict[str, ast.expr]):
        self.bound = bound

    def visit_Name(self, node: ast.Name) -> ast.expr:
        if isinstance(node.ctx, ast.Load) and node.id in self.bound:
            return tree_copy(self.bound[node.id])
        return node
