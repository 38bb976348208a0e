"""ptlab: a physically based path tracer in NumPy, for learning, teaching and grading.

    >>> import ptlab
    >>> scene = ptlab.load_scene("cornell-box")
    >>> image = ptlab.render(scene, spp=16, res=(512, 512), seed=0)   # (512, 512, 3) float32

The concepts of light transport are the top-level modules and the folders ``materials``,
``accel`` and ``integrators``; running a render is ``ptlab.rendering`` (whose API is
re-exported here), measuring it ``ptlab.measure``, grading ``ptlab.grading`` and
``ptlab.course`` (docs/architecture.md draws the layers).

The names below are imported when first used (PEP 562), so that ``import ptlab.cli`` stays
light until the command line has started its worker processes (``ptlab.rendering``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ptlab.inspector import inspect_pixel
    from ptlab.rendering.api import RenderResult, render, render_result
    from ptlab.rendering.display import show
    from ptlab.rendering.options import RenderOptions
    from ptlab.scene import Scene
    from ptlab.scene_file import load_dict, load_scene

__version__ = "0.1.0"

__all__ = [
    "RenderOptions",
    "RenderResult",
    "Scene",
    "__version__",
    "inspect_pixel",
    "load_dict",
    "load_scene",
    "render",
    "render_result",
    "show",
]

#: Where each lazily imported name lives.
_HOMES = {
    "Scene": "ptlab.scene",
    "load_scene": "ptlab.scene_file",
    "load_dict": "ptlab.scene_file",
    "inspect_pixel": "ptlab.inspector",
    "RenderResult": "ptlab.rendering.api",
    "render": "ptlab.rendering.api",
    "render_result": "ptlab.rendering.api",
    "RenderOptions": "ptlab.rendering.options",
    "show": "ptlab.rendering.display",
}


def __getattr__(name: str):
    if name in _HOMES:
        import importlib

        return getattr(importlib.import_module(_HOMES[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    # The public API only: not this file's machinery (TYPE_CHECKING, annotations, _HOMES),
    # which tab completion in a notebook would otherwise offer beside it.
    return sorted(__all__)
