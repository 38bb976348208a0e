"""Using a student's functions inside the renderer, in place of the library's own.

The renderer's modules look their pieces up by name at call time (``ptlab.rendering.jobs`` calls
``generate_rays``, the NumPy BVH calls ``ray_triangle`` and ``slab_test``, ...), so setting
that name in the module swaps the piece for everything that runs afterwards. ``plugged`` does
it for the duration of a ``with`` block and puts the library's own back afterwards. The
grader runs each check in a process of its own, so nothing leaks into other checks.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from types import ModuleType


@contextmanager
def plugged(module: ModuleType, **replacements) -> Iterator[None]:
    """``module.name = function`` for each replacement, undone when the block ends."""
    missing = [name for name in replacements if not hasattr(module, name)]
    if missing:
        raise AttributeError(f"{module.__name__} has no {', '.join(missing)} to replace")
    originals = {name: getattr(module, name) for name in replacements}
    for name, function in replacements.items():
        setattr(module, name, function)
    try:
        yield
    finally:
        for name, function in originals.items():
            setattr(module, name, function)
