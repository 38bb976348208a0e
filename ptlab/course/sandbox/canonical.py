"""A Python file put back into one form: what a mechanical rewrite changes, written one way.

A copier changes what does not change the code: names, the order of independent
statements; writes an operator as a function, an attribute through ``getattr``, a function
through an alias; splits a function into helpers or inlines them; adds what does nothing.
The canonical form undoes such edits, in three steps and a last one:

* names (``ptlab.course.sandbox.canonical_names``): imports and aliases resolved (``w =
  np.where`` is ``numpy.where``), a method's first parameter called ``self``;
* syntax (``ptlab.course.sandbox.canonical_syntax``): operators called as functions written as
  operators, attributes read by name written as attributes, arithmetic in one form;
* blocks (``ptlab.course.sandbox.canonical_blocks``): choices of a value as conditional
  expressions, loops that build a list or a dict as comprehensions, no dead code;
* then small helpers and lambdas inlined where they are called (``canonical_names``), and
  what inlining brings in put in one form again.

``ptlab.course.sandbox.fingerprints`` reads the canonical form's tokens; ``ptlab.course.sandbox.copies``
compares a student's with the library's answers'.
"""

from __future__ import annotations

import ast
from collections.abc import Iterable
from typing import overload

from ptlab.course.sandbox.canonical_blocks import simplified_blocks
from ptlab.course.sandbox.canonical_names import inlined, resolved
from ptlab.course.sandbox.canonical_syntax import as_syntax
from ptlab.course.sandbox.syntax_trees import FunctionNode, tree_copy


# A module's canonical form is a module, a function's a function: the rewriting replaces
# expressions and statements inside them, never the module or the function itself.
@overload
def canonical(
    tree: ast.Module, inline: bool = True, helpers: Iterable[tuple[str, FunctionNode]] = ()
) -> ast.Module: ...


@overload
def canonical(
    tree: FunctionNode, inline: bool = True, helpers: Iterable[tuple[str, FunctionNode]] = ()
) -> FunctionNode: ...


@overload
def canonical(
    tree: ast.AST, inline: bool = True, helpers: Iterable[tuple[str, FunctionNode]] = ()
) -> ast.AST: ...


def canonical(
    tree: ast.AST, inline: bool = True, helpers: Iterable[tuple[str, FunctionNode]] = ()
) -> ast.AST:
    """A copy of ``tree`` (a module, or any part of one) with what mechanical rewriting
    changes put back in one form (the module docstring lists what); ``inline=False`` leaves
    the helpers' calls as they are (what a function weighs by itself); ``helpers``: small
    helpers the tree may import ((dotted name, canonical function), ``Answers.helpers`` of
    ``ptlab.course.sandbox.copies``), inlined as its own are."""
    tree, names = resolved(tree_copy(tree))
    tree = simplified_blocks(as_syntax(tree))
    if not inline:
        return tree
    return as_syntax(inlined(tree, names, helpers))
