"""Running a render: the ``ptlab.render`` API and the machinery behind it.

This package is everything that turns a scene and an integrator into an image, but is not
itself a concept of light transport:

* ``api``: ``render`` and ``render_result``, which the names below are;
* ``options``: ``RenderOptions``, every option of a render with its default, choices, help
  and check, from which the API, the command line, image headers and checkpoints are made;
* ``sizes``: how big a job is (``TILE_SIZE``, ``SPP_PER_PASS``);
* ``jobs``: the image cut into tiles and the samples into passes; one job = one tile, one pass;
* ``scheduler`` and ``executors``: where jobs run (this process, worker processes, Dask);
* ``film``: the float64 sums the jobs add into, in an order that keeps images bit-identical;
* ``checkpoint``, ``progress``: saving and resuming a render, the progress bar;
* ``settings``: the checks of the options, with one clear error for an absurd value;
* ``memory``: the allocator tuning that keeps NumPy's temporaries cheap.

The API is imported when first used (a module ``__getattr__``, PEP 562), not with the
package: ``ptlab render`` starts its worker processes' server (``executors``) before it
imports NumPy, so that the two imports run at once.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ptlab.rendering.sizes import SPP_PER_PASS, TILE_SIZE

if TYPE_CHECKING:
    from ptlab.rendering.api import (
        DEFAULT_RES,
        RenderOptions,
        RenderResult,
        pass_schedule,
        render,
        render_result,
        resolution,
    )

__all__ = [
    "DEFAULT_RES",
    "SPP_PER_PASS",
    "TILE_SIZE",
    "RenderOptions",
    "RenderResult",
    "pass_schedule",
    "render",
    "render_result",
    "resolution",
]
#: The names that ``api`` holds.
_API = __all__[2:]


def __getattr__(name: str):
    if name in _API:
        from ptlab.rendering import api

        return getattr(api, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_API))
