"""The inspector: one pixel's paths, vertex by vertex, as the renderer traced them.

Every random number of a render is a function of (seed, pixel, sample, dimension)
(``ptlab.samplers``), so any sample of any pixel can be traced again, exactly. The inspector
runs the render's own jobs for one pixel (``ptlab.rendering.jobs.run_job_group``, one job
per sample so that each sample's radiance comes back on its own) with the integrators
reporting each step to a recorder (``ptlab.inspector.records``): the value it gives is the
rendered pixel's, and what it prints is what the renderer computed. pbrt-v4 can re-run one
pixel sample (``--debugstart``) in a debugger; this explains it.

    >>> import ptlab
    >>> found = ptlab.inspect_pixel("cornell-box", (256, 400), spp=4, res=512)
    >>> found.value                         # the pixel ``ptlab.render`` gives, (r, g, b)
    >>> found.samples[0].vertices[0].bsdf   # dataclasses (``ptlab.inspector.records``)
    >>> print(found.table())                # what ``ptlab inspect`` prints
"""

from __future__ import annotations

import inspect
import json
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ptlab.errors import PtlabError
from ptlab.inspector.records import BsdfSample, LightSample, Recorder, Roulette, Sample, Vertex
from ptlab.rendering.options import RenderOptions, takes_options
from ptlab.rendering.pieces import Pieces
from ptlab.scene import Scene

__all__ = [
    "BsdfSample",
    "LightSample",
    "PixelInspection",
    "Roulette",
    "Sample",
    "Vertex",
    "inspect_pixel",
    "parse_pixel",
]


@dataclass
class PixelInspection:
    """One pixel's samples, vertex by vertex.

    Attributes:
        scene: the scene's name.
        pixel: (x, y), x from the left and y from the top.
        value: the pixel's value (r, g, b): the mean of the samples' contributions, equal to
            the pixel ``ptlab.render`` writes with the same options.
        samples: every sample of the pixel, in order.
        options: the render options (``RenderOptions.record``).
    """

    scene: str
    pixel: tuple[int, int]
    value: list[float]
    samples: list[Sample]
    options: dict[str, Any] = field(default_factory=dict)

    def as_dict(self) -> dict:
        """The inspection as plain data (``--json``)."""
        return asdict(self)

    def write_json(self, path: str | Path) -> None:
        """Write ``as_dict`` to ``path``."""
        Path(path).write_text(json.dumps(self.as_dict(), indent=1) + "\n", encoding="utf-8")

    def table(self, sample: int | None = None) -> str:
        """What ``ptlab inspect`` prints: every sample's vertices (or sample ``sample``'s),
        its contribution, and the pixel's value."""
        from ptlab.inspector.report import table

        return table(self, sample)

    def plot(
        self, path: str | Path, scene: Scene | str | None = None, image: np.ndarray | None = None
    ) -> None:
        """Draw the paths in ``scene`` (default: the scene of that name) from above and from
        the side, beside ``image`` with the pixel marked if given, into ``path`` (a .png;
        ``ptlab.inspector.plot``)."""
        from ptlab.inspector.plot import plot
        from ptlab.scene_file import load_scene

        if not isinstance(scene, Scene):
            scene = load_scene(scene or self.scene)
        plot(self, path, scene, image)


def parse_pixel(text: str) -> tuple[int, int]:
    """``--pixel X,Y`` as (x, y)."""
    parts = text.replace(" ", "").split(",")
    if len(parts) != 2 or not all(p.isdigit() for p in parts):
        raise PtlabError(f"--pixel {text!r}: give X,Y, two whole numbers (x from the left, y from the top)")
    return int(parts[0]), int(parts[1])


def _pixel_after_scene(function: Callable) -> Callable:
    """``takes_options`` shows the scene and then the options: put ``pixel`` back between them."""
    signature = inspect.signature(function)
    scene, *options = signature.parameters.values()
    pixel = inspect.Parameter("pixel", inspect.Parameter.POSITIONAL_OR_KEYWORD, annotation="tuple[int, int]")
    function.__signature__ = signature.replace(parameters=[scene, pixel, *options])  # type: ignore[attr-defined]
    return function


@_pixel_after_scene
@takes_options
def inspect_pixel(
    scene: Scene | str,
    pixel: tuple[int, int],
    *args,
    options: RenderOptions | None = None,
    pieces: Pieces | None = None,
    **keywords: Any,
) -> PixelInspection:
    """Trace every sample of one pixel as ``ptlab.render`` does, recording each vertex.

    Args:
        scene: a ``Scene``, a built-in scene name or a scene file.
        pixel: (x, y): x counts from the left, y from the top.
        options: the render's options (``RenderOptions``, or its fields by name): the same
            options give the same pixel as the render.
        pieces: the functions the render is made of, if not the library's
            (``ptlab.rendering.pieces``): the same pieces give the same pixel.
    """
    from ptlab.accel import make_accelerator
    from ptlab.integrators.wavefront import recording
    from ptlab.rendering.api import pass_schedule, render_setup
    from ptlab.rendering.jobs import Job, Tile, run_job_group
    from ptlab.scene_file import load_scene

    options = RenderOptions.of(args, options, keywords)
    if isinstance(scene, str | Path):
        scene = load_scene(scene)
    if options.target_error is not None:
        raise PtlabError(
            "inspect traces a render of a fixed spp; a render to a target error gives each "
            "pixel samples of its own (see its --spp-map): give that pixel's --spp instead"
        )
    options = options.for_scene(scene)
    width, height = options.size
    x, y = pixel
    if not (0 <= x < width and 0 <= y < height):
        raise PtlabError(f"pixel ({x}, {y}) is outside the {width}x{height} image")
    setup = render_setup(scene, options, pieces)
    scene = setup.scene
    passes = pass_schedule(options.spp, options.spp_per_pass)
    pass_of = np.repeat(np.arange(len(passes)), passes)
    tile = Tile(0, x, y, x + 1, y + 1)
    # A job per sample: each sample's radiance comes back on its own (a render's job adds
    # the samples of a pass in this same order, so the sums below are the film's).
    jobs = [Job(tile, int(pass_of[k]), 1, k) for k in range(options.spp)]
    recorder = Recorder()
    with recording(recorder):
        results = run_job_group(
            setup, jobs, make_accelerator(scene.triangles, options.backend, setup.pieces.bvh)
        )
    contributions = [result.sums[0, 0] for result in results]
    return PixelInspection(
        scene=scene.name,
        pixel=(x, y),
        value=pixel_value(contributions, passes),
        samples=[
            Sample(
                k, [float(c) for c in contribution], recorder.vertices_of.get(k, []), recorder.sky_of.get(k)
            )
            for k, contribution in enumerate(contributions)
        ],
        options=dict(options.record(), scene=scene.name),
    )


def pixel_value(contributions: list[np.ndarray], passes: list[int]) -> list[float]:
    """The pixel as the film makes it of its samples' radiance: each pass's samples summed
    in order (``CameraSamples.sums``), the passes added up (``Film.add``), over the spp, in
    float32 (``Film.image``)."""
    total = np.zeros(3)
    start = 0
    for size in passes:
        pass_sum = contributions[start].copy()
        for contribution in contributions[start + 1 : start + size]:
            pass_sum += contribution
        total += pass_sum
        start += size
    return [float(v) for v in (total / max(start, 1)).astype(np.float32)]
