"""ptlab: a physically based path tracer in NumPy, for learning, teaching and grading.

    >>> import ptlab
    >>> scene = ptlab.load_scene("cornell-box")
    >>> image = ptlab.render(scene, spp=16, res=(512, 512), seed=0)   # (512, 512, 3) float32

The concepts of light transport are the top-level modules and the folders ``materials``,
``accel`` and ``integrators``; running a render is ``ptlab.rendering`` (whose API is
re-exported here), measuring it ``ptlab.measure``, grading ``ptlab.grading`` and
``ptlab.exercises`` (docs/architecture.md draws the layers).
"""

from ptlab.rendering import RenderResult, render, render_result
from ptlab.scene import Scene, load_scene

__version__ = "0.1.0"

__all__ = ["Scene", "RenderResult", "load_scene", "render", "render_result", "__version__"]
