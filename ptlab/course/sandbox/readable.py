"""Code the grader can read: whether what runs for a graded name is in the submission's text.

A check grades the code a student wrote, and the grader, like a teacher, must be able to
read that code in the files handed in. A graded function whose code is made from data
when it runs (``exec``, ``eval``, ``compile``, ``marshal``, a pickle, ``types.FunctionType``,
an ``importlib`` loader: an encoded, compressed or compiled blob), that is reached by a
name built at run time (``globals()[...]``, ``getattr(m, "ex" + "ec")``, ``sys.modules``),
or that is imported from outside the submission, earns nothing for the checks it serves,
and its message says that a teacher should look at the file. Two readings decide, and
either is enough:

1. **The files' text** (``unreadable_in_text``; the grader's own reading with ``ast``, which
   nothing the file does can change). It is an allowlist of what a readable file does
   (``ptlab.course.sandbox.uses``): it computes with built-ins, the harmless dunders, and the
   modules of ``uses.MODULES`` (NumPy, SciPy, ptlab's kit, the standard library's modules
   that compute), each use resolved in the grader's own copy of the modules; it does not
   reach Python's machinery that makes code from data or finds objects by names built at
   run time, in any spelling (``__import__``, ``type(f)(...)``, ``globals()[...]``,
   ``getattr`` with a name built at run time, ``__globals__``, frames, ``gc``,
   ``sys.settrace``...). The reading covers:

   * where the graded name is bound: its last binding at the module's top level must be a
     ``def`` or a ``class`` of the file, an import from another file of the submission
     (followed there), or an assignment the grader can follow; a name bound nowhere in the
     text (made by ``exec``, ``globals()[...]``) or imported from a module that is not a file
     of the submission is unreadable;
   * what the file runs when it is imported (statements at the top level, class bodies,
     decorators, default values; not the ``if __name__ == "__main__":`` block), and what the
     files of the submission it imports run: anything out of the allowlist there may define
     or change any function of the file;
   * what the graded name runs (its body, with the functions and classes of the submission
     it names, transitively, and the values at the top level they name);
   * how the files are written: a source encoding that shows a reader other text than
     Python runs (``# coding: utf-7``, ``unicode_escape``), or characters that reorder the
     text on screen (bidirectional controls), are unreadable too.

   So a function that uses ``exec`` or ``eval`` for something of its own, and that no graded
   name reaches and nothing runs at import, costs nothing; nor does the ``__main__`` block.
2. **What runs** (``ptlab.course.sandbox.code_ran``), for what only running the file shows: the
   student's process records every code object that runs while it serves the grader's
   requests (``ptlab.course.sandbox.child.CodeRecorder``, a trace function) and the files of
   the modules it loaded from the student's folder; the grader compiles the submission's
   files itself (compiling runs nothing) and the library files named, and each code
   object must be the grader's own code at the place it names. That process is the
   student's: its code could turn the recording off or forge the report, which is why the
   reading of the text, which refuses every way to reach the recorder (``sys.settrace``,
   ``gc``, frames, ``sys.modules``, ``ptlab.course.sandbox``), comes first.
"""

from __future__ import annotations

import ast
import codecs
import contextlib
import io
import re
import sys
import tokenize
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import TypeGuard

from ptlab.course.sandbox.intake import Taken
from ptlab.course.sandbox.uses import IMPORTLIB_HINT, FileUses, annotations_of, importable_here, star_names

FunctionNode = ast.FunctionDef | ast.AsyncFunctionDef
#: Characters that reorder text on screen (Unicode's bidirectional embeddings, overrides and
#: isolates): a reader would see the code in another order than Python reads it.
REORDERING = re.compile("[\u202a-\u202e\u2066-\u2069]")
#: ASCII that some source encodings Python accepts read as other text (escapes, UTF-7).
_ASCII_SAMPLE = bytes(range(32, 127)) + b"\\x41 \\u0041 \\N{DIGIT ONE} +AEE- \\101"


@dataclass(frozen=True)
class Unreadable:
    """Why the grader cannot read the code of a graded name: a message of the catalogues
    (``unreadable.*`` in ``ptlab.course.messages``), its fields, and a hint (a key of the
    catalogues, or "")."""

    reason: str
    fields: dict = field(default_factory=dict)
    hint: str = ""

    def message(self, name: str) -> str:
        """The line for the student, in the active language."""
        from ptlab.course.messages import text  # (the catalogues are the course's)

        why = text(self.reason, **self.fields) + (text(self.hint) if self.hint else "")
        return text("require.unreadable", name=name, why=why)


def unreadable_in_text(taken: Taken, name: str) -> Unreadable | None:
    """Why the text of the submission ``taken`` does not show the code of its graded
    ``name``, or None if it does (see the module docstring)."""
    files = _Files(taken)
    graded = files.graded
    for file in files.imported_at_import(graded):
        hidden = hidden_text(file.name, taken.files.get(file.name, b""))
        if hidden is not None:
            return hidden
        made = file.made_at_import()
        if made is not None:
            return _made("unreadable.at_import", made)
    return files.binding_of(graded, name, set())


def hidden_text(name: str, source: bytes) -> Unreadable | None:
    """Why a reader of the file ``name`` would not see the text Python runs, or None: a
    source encoding that reads ASCII as other text, or characters that reorder the text."""
    try:
        encoding, _ = tokenize.detect_encoding(io.BytesIO(source).readline)
        readable = codecs.decode(_ASCII_SAMPLE, encoding, "replace") == _ASCII_SAMPLE.decode("ascii")
        text = source.decode(encoding, errors="replace")
    except (SyntaxError, LookupError, UnicodeDecodeError, ValueError):
        return None  # (Python refuses it too: the file does not import)
    if not readable:
        return Unreadable("unreadable.encoding", {"file": name, "encoding": encoding[:40]})
    found = REORDERING.search(text)
    if found is not None:
        return Unreadable(
            "unreadable.reordered", {"file": name, "line": text.count("\n", 0, found.start()) + 1}
        )
    return None


def _made(reason: str, made: dict) -> Unreadable:
    what = made["what"]
    hint = IMPORTLIB_HINT if what.startswith(("importlib", "__import__")) else ""
    return Unreadable(reason, made, hint)


class _File:
    """One Python file of the submission, as read: what it defines and imports."""

    def __init__(self, name: str, tree: ast.Module, files: _Files):
        self.name, self.tree = name, tree
        self.aliases = _aliases(tree, files)
        self.uses = FileUses(tree, self.aliases, files.library_name)
        self.defined: dict[str, list[ast.AST]] = {}
        for node in ast.walk(tree):
            if isinstance(node, FunctionNode | ast.ClassDef):
                self.defined.setdefault(node.name, []).append(node)
        self.top = list(_top_level(tree.body))
        #: {name: (place, statement)}: the last statement of ``top`` that binds it; "*" for
        #: the last ``from m import *``, which may bind any name.
        self.last: dict[str, tuple[int, ast.stmt]] = {}
        for place, statement in enumerate(self.top):
            self.last.update(dict.fromkeys(_bound_by(statement), (place, statement)))

    def binding(self, name: str) -> ast.stmt | None:
        """The last statement at the top level (outside ``__main__``) that binds ``name``."""
        found = [self.last[key] for key in (name, "*") if key in self.last]
        return max(found, key=lambda entry: entry[0])[1] if found else None

    def made_at_import(self) -> dict | None:
        """Where the file, when it is imported, uses what a readable file does not:
        {what, file, line}."""
        return self._first_made(_runs_at_import(self.tree.body))

    def made_in(self, node: ast.AST) -> dict | None:
        """Where ``node`` (a function, a class, an expression) uses what a readable file does
        not: {what, file, line}."""
        return self._first_made(ast.walk(node))

    def _first_made(self, nodes) -> dict | None:
        """The first place in the text, of ``nodes``, out of the allowlist."""
        found = [
            (getattr(n, "lineno", 0), getattr(n, "col_offset", 0), what)
            for n in nodes
            if (what := self.uses.problem(n))
        ]
        if not found:
            return None
        line, _, what = min(found)
        return {"what": what[:80], "file": self.name, "line": line}


class _Files:
    """The submission's files, each read once (a file that does not parse is None)."""

    def __init__(self, taken: Taken):
        self.taken = taken
        self.read: dict[str, _File | None] = {taken.name: None}  # (None while it is read)
        self.graded = self.read[taken.name] = _File(taken.name, taken.tree, self)

    def get(self, name: str) -> _File | None:
        if name not in self.read:
            self.read[name] = None
            if name in self.taken.files:
                with contextlib.suppress(SyntaxError, ValueError, RecursionError, MemoryError):
                    self.read[name] = _File(name, ast.parse(self.taken.files[name], filename=name), self)
        return self.read[name]

    def module(self, dotted: str | None) -> _File | None:
        """The file of the submission that ``import dotted`` imports, if it is one (not when
        the library's module of that name is loaded already where the student's code runs:
        Python finds that one first)."""
        if not dotted or "." in dotted or f"{dotted}.py" not in self.taken.files:
            return None
        if dotted in sys.modules and importable_here(dotted):
            return None
        return self.get(f"{dotted}.py")

    def library_name(self, dotted: str, depth: int = 0) -> str | None:
        """The library's dotted name that ``dotted`` (an import, and attributes) stands for,
        through the submission's files (``helpers.np.load`` is ``numpy.load`` if helpers.py
        imports numpy as np); None if it is the submission's own code, whose text is read."""
        head, _, rest = dotted.partition(".")
        module = self.module(head)
        if module is None:
            return dotted
        attribute, _, further = rest.partition(".")
        inner = module.aliases.get(attribute) if attribute else None
        if inner is None or depth > 8:
            return None
        return self.library_name(f"{inner}.{further}" if further else inner, depth + 1)

    def imported_at_import(self, file: _File) -> list[_File]:
        """``file`` and the files of the submission it imports, transitively."""
        found, todo = {file.name: file}, [file]
        while todo:
            for dotted in todo.pop().aliases.values():
                other = self.module(dotted.split(".", 1)[0])
                if other is not None and other.name not in found:
                    found[other.name] = other
                    todo.append(other)
        return list(found.values())

    def binding_of(self, file: _File, name: str, seen: set) -> Unreadable | None:
        """Whether the text shows the code that ``name`` is bound to in ``file``."""
        if (file.name, name) in seen:
            return None  # (judged where the chain started)
        seen.add((file.name, name))
        binding = file.binding(name)
        if binding is None:
            return Unreadable("unreadable.not_in_text", {"file": file.name})
        if isinstance(binding, FunctionNode | ast.ClassDef):
            return self.reach(file, [binding], seen)
        if isinstance(binding, ast.Import | ast.ImportFrom):
            return self._imported(file, binding, name, seen)
        value = getattr(binding, "value", None)
        if value is None:  # (an annotation alone binds nothing)
            return Unreadable("unreadable.not_in_text", {"file": file.name})
        return self._expression(file, value, seen)

    def _imported(
        self, file: _File, statement: ast.Import | ast.ImportFrom, name: str, seen: set
    ) -> Unreadable | None:
        if isinstance(statement, ast.Import):
            dotted = next(a.name for a in statement.names if (a.asname or a.name.split(".")[0]) == name)
            return None if self.module(dotted) is not None else _from_outside(dotted)
        module = self.module(statement.module) if statement.level <= 1 else None
        for alias in statement.names:
            if alias.name == "*" or (alias.asname or alias.name) == name:
                if module is None:
                    return _from_outside(("." * statement.level) + (statement.module or ""))
                return self.binding_of(module, name if alias.name == "*" else alias.name, seen)
        return None

    def _expression(self, file: _File, value: ast.expr, seen: set) -> Unreadable | None:
        """An assignment's value: another name of the file, a name from a module (which must
        be one of the submission's), or an expression whose code is the file's."""
        if isinstance(value, ast.Name):
            return self.binding_of(file, value.id, seen)
        root = value
        while isinstance(root, ast.Attribute):
            root = root.value
        if isinstance(value, ast.Attribute) and isinstance(root, ast.Name) and root.id in file.aliases:
            module = self.module(file.aliases[root.id])
            if module is None:
                return _from_outside(file.aliases[root.id])
            return self.binding_of(module, value.attr, seen) if value.value is root else None
        return self.reach(file, [value], seen)

    def reach(self, file: _File, nodes: list[ast.AST], seen: set) -> Unreadable | None:
        """Whether the code of ``nodes`` (of ``file``), with the functions and classes of the
        submission it names, transitively, uses what a readable file does not."""
        todo = [(file, node) for node in nodes]
        done: set[int] = set()
        while todo:
            where, node = todo.pop()
            if id(node) in done:
                continue
            done.add(id(node))
            made = where.made_in(node)
            if made is not None:
                return _made("unreadable.runs_made_code", made)
            for name in _names_in(node):
                todo += [(where, found) for found in where.defined.get(name, [])]
                binding = where.binding(name)
                if isinstance(binding, ast.Assign | ast.AnnAssign | ast.AugAssign) and binding.value:
                    todo.append((where, binding.value))  # (what made a module-level value)
                elif isinstance(binding, ast.Import | ast.ImportFrom):
                    todo += self._imported_nodes(where, binding, name)
        return None

    def _imported_nodes(self, file: _File, statement: ast.Import | ast.ImportFrom, name: str) -> list:
        """The definitions of another file of the submission that ``name`` imports there."""
        if isinstance(statement, ast.Import):
            module = self.module(file.aliases.get(name, "").split(".", 1)[0])
            return [(module, node) for node in module.tree.body] if module is not None else []
        module = self.module(statement.module) if statement.level <= 1 else None
        if module is None:
            return []
        names = [a.name for a in statement.names if a.name == "*" or (a.asname or a.name) == name]
        wanted = name if names == ["*"] else names[0] if names else name
        return [(module, node) for node in module.defined.get(wanted, [])]


def _from_outside(module: str) -> Unreadable:
    return Unreadable("unreadable.imported", {"module": module[:80]})


def _aliases(tree: ast.Module, files: _Files) -> dict[str, str]:
    """{name in the file: dotted name it was imported as} for every import of the file (a
    library's ``import *`` binds the names the grader's copy of it has; one of the
    submission's files, the modules that file imports)."""
    found = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                found[alias.asname or alias.name.split(".")[0]] = (
                    alias.name if alias.asname else alias.name.split(".")[0]
                )
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            for alias in node.names:
                if alias.name != "*":
                    found[alias.asname or alias.name] = f"{node.module}.{alias.name}"
                elif (own := files.module(node.module)) is not None:
                    found.update({n: d for n, d in own.aliases.items() if not n.startswith("_")})
                else:
                    found.update({n: f"{node.module}.{n}" for n in star_names(node.module) or ()})
    return found


def _is_main_block(node: ast.AST) -> TypeGuard[ast.If]:
    """``if __name__ == "__main__":`` (either way round), which never runs when graded."""
    if not (isinstance(node, ast.If) and isinstance(node.test, ast.Compare) and len(node.test.ops) == 1):
        return False
    sides = [node.test.left, node.test.comparators[0]]
    names = [side for side in sides if isinstance(side, ast.Name) and side.id == "__name__"]
    mains = [side for side in sides if isinstance(side, ast.Constant) and side.value == "__main__"]
    return isinstance(node.test.ops[0], ast.Eq) and len(names) == 1 and len(mains) == 1


def _top_level(body: list[ast.stmt]) -> Iterator[ast.stmt]:
    """The statements of the module's top level, and those in its compound statements (not
    in functions, classes or the ``__main__`` block), in order."""
    for statement in body:
        if _is_main_block(statement):
            yield from _top_level(statement.orelse)
            continue
        yield statement
        if isinstance(statement, FunctionNode | ast.ClassDef):
            continue
        for name in ("body", "orelse", "finalbody"):
            yield from _top_level(getattr(statement, name, []))
        for handler in getattr(statement, "handlers", []):
            yield from _top_level(handler.body)


def _bound_by(statement: ast.stmt) -> set[str]:
    """The names a top-level statement binds: a definition, an import, an assignment."""
    if isinstance(statement, FunctionNode | ast.ClassDef):
        return {statement.name}
    if isinstance(statement, ast.Import | ast.ImportFrom):
        return {
            (alias.asname or alias.name.split(".")[0]) if alias.name != "*" else "*"
            for alias in statement.names
        }
    if not isinstance(statement, ast.Assign | ast.AnnAssign | ast.AugAssign):
        return set()
    targets = statement.targets if isinstance(statement, ast.Assign) else [statement.target]
    return {node.id for target in targets for node in ast.walk(target) if isinstance(node, ast.Name)}


def _runs_at_import(body: list[ast.stmt]) -> Iterator[ast.AST]:
    """Every node of ``body`` that runs when the module is imported: all but the bodies of
    functions and lambdas, and the ``__main__`` block."""
    todo: list[ast.AST] = list(body)
    while todo:
        node = todo.pop()
        if _is_main_block(node):
            todo += node.orelse
            continue
        yield node
        if isinstance(node, FunctionNode | ast.Lambda):
            arguments = node.args
            todo += [*arguments.defaults, *(d for d in arguments.kw_defaults if d is not None)]
            if isinstance(node, FunctionNode):
                todo += [*node.decorator_list, *annotations_of(node)]
            continue
        todo += ast.iter_child_nodes(node)


def _names_in(node: ast.AST) -> set[str]:
    """The names and attribute names ``node`` uses (a function of the file is named either way)."""
    found = set()
    for inner in ast.walk(node):
        if isinstance(inner, ast.Name):
            found.add(inner.id)
        elif isinstance(inner, ast.Attribute):
            found.add(inner.attr)
    return found
