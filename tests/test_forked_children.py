"""A process that a test forks is a copy of the test run: whatever its code raises, it must
end there (``os._exit`` in a ``finally``), or it goes on to run the rest of the suite as a
second pytest, mixing its results into the first's. Every fork in the tests' code, and in
the code they give a Python to run, has that shape. (The hostile submissions in
``attacks/submissions`` are students' code as written, run in a grader's sandbox: not checked.)
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

TESTS = Path(__file__).parent
SUBMISSIONS = TESTS / "attacks" / "submissions"


def test_every_child_a_test_forks_ends_whatever_it_raises():
    unsafe = [f"{where} (line {line})" for where, tree in _codes() for line in forks_that_may_return(tree)]
    assert unsafe == [], "a forked child that raises would run the rest of the tests"


def test_the_check_tells_a_child_that_may_return_from_one_that_cannot():
    returns = "import os\nif os.fork() == 0:\n    work()\n    os._exit(0)\n"
    ends = (
        "import os\nchild = os.fork()\nif child == 0:\n"
        "    try:\n        work()\n    finally:\n        os._exit(0)\n"
    )
    assert forks_that_may_return(ast.parse(returns)) == [2]
    assert forks_that_may_return(ast.parse(ends)) == []
    assert forks_that_may_return(ast.parse("import os\npid = os.fork()\nwork(pid)\n")) == [2]


def forks_that_may_return(tree: ast.Module) -> list[int]:
    """The lines of the forks in ``tree`` whose child branch (``if FORK == 0:``, FORK the call
    or a name given its result) is not one ``try`` whose ``finally`` calls ``os._exit``."""
    forks = [node for node in ast.walk(tree) if _calls(node, "os.fork")]
    named: dict[str, list[ast.AST]] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign) and _calls(node.value, "os.fork"):
            for target in node.targets:
                if isinstance(target, ast.Name):
                    named.setdefault(target.id, []).append(node.value)
    ending: set[int] = set()
    for node in ast.walk(tree):
        if not (isinstance(node, ast.If) and _is_child_test(node.test) and _ends(node.body)):
            continue
        tested = node.test.left  # type: ignore[attr-defined]
        forks_tested = named.get(tested.id, []) if isinstance(tested, ast.Name) else [tested]
        ending.update(id(fork) for fork in forks_tested)
    return [fork.lineno for fork in forks if id(fork) not in ending]


def _is_child_test(test: ast.expr) -> bool:
    """``X == 0``, X a call or a name."""
    return (
        isinstance(test, ast.Compare)
        and isinstance(test.left, ast.Call | ast.Name)
        and [type(op) for op in test.ops] == [ast.Eq]
        and ast.unparse(test.comparators[0]) == "0"
    )


def _ends(body: list[ast.stmt]) -> bool:
    """One ``try`` whose ``finally`` calls ``os._exit``."""
    return (
        len(body) == 1
        and isinstance(body[0], ast.Try)
        and any(_calls(node, "os._exit") for statement in body[0].finalbody for node in ast.walk(statement))
    )


def _calls(node: ast.AST, function: str) -> bool:
    return isinstance(node, ast.Call) and ast.unparse(node.func) == function


def _codes() -> Iterator[tuple[str, ast.Module]]:
    """Each test module, and each string in it that is Python code that forks."""
    for path in sorted(TESTS.rglob("*.py")):
        if SUBMISSIONS in path.parents:
            continue
        name = str(path.relative_to(TESTS))
        tree = ast.parse(path.read_text(encoding="utf-8"), name)
        yield name, tree
        if path == Path(__file__):
            continue  # (its strings are examples of both shapes)
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and "os.fork()" in node.value:
                try:
                    yield f"{name}, the code at line {node.lineno}", ast.parse(node.value)
                except SyntaxError:  # (words about a fork, not code)
                    continue
