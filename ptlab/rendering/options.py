"""The options of a render, each defined once: its default, its choices, its help, its check.

``RenderOptions`` is what ``ptlab.render`` and ``ptlab.render_result`` take (their arguments
are its fields), what ``ptlab render``'s options are made from (``ptlab.cli`` reads the
choices, defaults and help below) and what an image's header and a checkpoint record
(``RenderOptions.record``). As pbrt-v4 reads each parameter inside the ``Create`` of what it
configures, each option's choices come from the module that owns them: samplers from
``ptlab.samplers``, diffuse samplings from ``ptlab.materials.diffuse``, strategies and
heuristics from the path integrator (whose ``PathSettings`` hold its defaults), backends
from ``ptlab.accel`` and integrators from their registry, ``ptlab.integrators``.

An option whose default is None leaves the choice to the scene, the integrator or the
machine; ``RenderOptions.for_scene`` makes it.
"""

from __future__ import annotations

import inspect
import textwrap
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass, field, fields, replace
from typing import Any

from ptlab.accel import BACKENDS, resolve_backend
from ptlab.errors import PtlabError, is_integer
from ptlab.integrators import INTEGRATORS
from ptlab.integrators.path import HEURISTICS, STRATEGIES, PathSettings
from ptlab.materials.diffuse import SAMPLINGS
from ptlab.rendering.settings import (
    MAX_SPP,
    MAX_WORKERS,
    check_choice,
    check_flag,
    check_integer,
    check_positive_number,
    check_roulette,
    parse_resolution,
)
from ptlab.rendering.sizes import DEFAULT_SPP, SPP_PER_PASS, TILE_SIZE
from ptlab.samplers import DEFAULT_SAMPLER, SAMPLERS
from ptlab.scene import Scene

#: The most samples a pixel gets in a render to a target error that gives no ``max_spp``.
DEFAULT_MAX_SPP = 4096

#: The resolution of a render that gives none, of a scene whose file has no ``[render] res``.
DEFAULT_RES = (512, 512)


@dataclass(frozen=True)
class About:
    """What an option is, beside its default (each field's ``metadata["about"]``).

    Attributes:
        help: what it sets, in a phrase (``RenderOptions.describe`` adds the default).
        check: (label, value) -> the value checked and made plain, or ``PtlabError``.
        label: how an error message names it (default: the field's name, in words).
        choices: the names it may take, or None.
        parse: a word of the command line -> the value (argparse's ``type``).
        metavar: how ``--help`` names its value, or None for argparse's choice.
    """

    help: str
    check: Callable[[str, Any], Any]
    label: str | None = None
    choices: tuple[str, ...] | None = None
    parse: Callable[[str], Any] = str
    metavar: str | None = None


def option(default: Any, help: str, check: Callable[[str, Any], Any], **about) -> Any:
    """A field of ``RenderOptions``: its default and what it is (``About``)."""
    return field(default=default, metadata={"about": About(help, check, **about)})


def choice(default: str, choices: Iterable[str], help: str) -> Any:
    """An option that is one of the names ``choices``."""
    choices = tuple(choices)
    return option(default, help, lambda label, value: check_choice(label, value, choices), choices=choices)


def integer(default: int | None, help: str, low: int, high: int | None = None, **about) -> Any:
    """An option that is an integer from ``low`` to ``high`` (None: no upper bound)."""
    return option(
        default, help, lambda label, value: check_integer(label, value, low, high), parse=int, **about
    )


def _number_or_word(text: str) -> float | str:
    """A word of the command line as a float if it is a number (the roulette's P), else as
    it is (``'throughput'``, or a word its check rejects)."""
    try:
        return float(text)
    except ValueError:
        return text


@dataclass(frozen=True)
class RenderOptions:
    """How to render an image; each field says its default, its choices and its help.

    A bad value raises ``PtlabError`` with one line that names it, when the options are made.
    """

    spp: int = integer(DEFAULT_SPP, "samples (camera paths) per pixel", 1, MAX_SPP)
    res: tuple[int, int] | int | str | None = option(
        None,
        f"N (square) or WxH (default: the scene file's [render] res, else {DEFAULT_RES[0]}x{DEFAULT_RES[1]})",
        lambda label, value: parse_resolution(value),
    )
    seed: int = integer(
        0, "random seed; the same seed gives the same image, bit for bit, whatever the number of workers", 0
    )
    workers: int | None = integer(
        None,
        "processes rendering tiles at once (default: one per "
        "core; 1: this process only); the image does not "
        "depend on it",
        1,
        MAX_WORKERS,
    )
    backend: str = choice(
        "auto", BACKENDS, "ray queries by embree, the numpy BVH, or auto: embree if it imports"
    )
    integrator: str = choice(
        "path",
        INTEGRATORS,
        "path tracing; whitted, Homework 5's ray "
        "tracer (mirrors, glass and direct light "
        "only); or a debug view: normals, albedo or "
        "depth",
    )
    sampling: str = choice(
        "cosine", SAMPLINGS, "how diffuse materials sample directions: cosine, or uniform like the homework"
    )
    rr: float | str = option(
        PathSettings.rr,
        "Russian roulette: a survival probability P (the "
        "homework's 0.8), or 'throughput' for pbrt-v4's P "
        "from the path's throughput",
        lambda label, value: check_roulette(value),
        parse=_number_or_word,
        metavar="throughput|P",
    )
    max_depth: int | None = integer(
        None,
        "the most bounces per path (default: the scene file's [render] max_depth, else "
        f"{INTEGRATORS['path'].max_depth}; {INTEGRATORS['whitted'].max_depth} for whitted)",
        0,
    )
    strategy: str = choice(
        PathSettings.strategy,
        STRATEGIES,
        "how direct light is found: nee, by light sampling like the "
        "homework; bsdf, by BSDF sampling only; mis, by both with multiple "
        "importance sampling",
    )
    heuristic: str = choice(
        PathSettings.heuristic, HEURISTICS, "the MIS weights of the strategy mis: power or balance"
    )
    rr_depth: int | None = integer(
        PathSettings.rr_depth,
        "bounces before Russian roulette starts (default 0 with a "
        "fixed P, like the homework; 2 with throughput, like pbrt-v4)",
        0,
        label="russian roulette depth",
        metavar="N",
    )
    sampler: str = choice(
        DEFAULT_SAMPLER,
        SAMPLERS,
        "where the random numbers come from: independent, or stratified and sobol, which spread them evenly",
    )
    tile_size: int = integer(TILE_SIZE, "tile edge in pixels; the image does not depend on it", 8, 4096)
    spp_per_pass: int | None = integer(
        None,
        f"samples per pixel in each pass (default {SPP_PER_PASS}); part of the image's "
        "identity, since each pass's sums are added up on their own",
        1,
    )

    target_error: float | None = option(
        None,
        "render until the image's estimated relMSE falls to this (e.g. 0.01), spending more "
        "samples where the image is noisy; --spp is then the first pass's samples per pixel "
        "(default: --spp everywhere, no estimate)",
        lambda label, value: check_positive_number(label, value),
        parse=float,
        metavar="E",
    )
    max_spp: int | None = integer(
        None,
        f"with a target error: the most samples any pixel gets (default {DEFAULT_MAX_SPP})",
        1,
        MAX_SPP,
        metavar="N",
    )
    time_limit: float | None = option(
        None,
        "with a target error: start no pass that would end after SECONDS (default: no limit); "
        "not part of the image's identity",
        lambda label, value: check_positive_number(label, value),
        parse=float,
        metavar="SECONDS",
    )
    denoise: bool = option(
        False,
        "denoise the image with Intel Open Image Denoise (the denoise extra: pip install "
        "'ptlab[denoise]'), guided by albedo and normal images of the same samples, lights seen "
        "directly kept out of it; each pixel's samples in two halves, each denoised, to estimate "
        "the denoised image's error (an even spp is needed for it); with a target error, the "
        "target is the denoised image's: the render ends on its estimate, on a bound of it, or, "
        "where neither can be trusted, on the noisy image's estimate, and says which",
        lambda label, value: check_flag(label, value),
    )
    crop: tuple[int, int, int, int] | str | None = option(
        None,
        "render only the window X,Y,W,H of the image (in its pixels, from its top-left corner; "
        "the image's size is --res): a W x H image whose pixels are those of the whole image's "
        "render, bit for bit (a target error is the window's, and a denoiser sees the window "
        "alone); an .exr or .tif records where it sits, as its data window (default: the whole "
        "image)",
        lambda label, value: parse_crop(value),
        metavar="X,Y,W,H",
    )

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            if value is None and f.default is None:
                continue  # left to the scene, the integrator or the machine
            about = f.metadata["about"]
            object.__setattr__(self, f.name, about.check(about.label or f.name.replace("_", " "), value))
        if self.target_error is None and (self.max_spp, self.time_limit) != (None, None):
            raise PtlabError("max spp and time limit bound a render to a target error: give target_error too")
        if self.target_error is not None and self.spp % 2:
            raise PtlabError(
                f"spp {self.spp}: with a target error, the first pass's samples per pixel must be even "
                "(half of them measure the other half's error)"
            )
        if self.target_error is not None and self.sampler == "stratified":
            raise PtlabError(
                "sampler 'stratified' lays out a fixed number of samples per pixel; a render to a "
                "target error adds samples as it goes: use sobol or independent"
            )
        if self.denoise and self.integrator != "path":
            raise PtlabError(
                f"denoise: the denoiser is for path-traced images; {self.integrator!r} gathers no "
                "albedo and normal images for it"
            )
        if self.integrator != "path" and (self.strategy, self.heuristic) != (
            PathSettings.strategy,
            PathSettings.heuristic,
        ):
            raise PtlabError(
                f"strategy {self.strategy!r} / heuristic {self.heuristic!r}: these "
                f"choose how the path integrator finds light; {self.integrator!r} "
                f"has no such choice"
            )

    @staticmethod
    def about(name: str) -> About:
        """What option ``name`` is (its help, choices, ...)."""
        return _FIELDS[name].metadata["about"]

    @staticmethod
    def default(name: str) -> Any:
        """Option ``name``'s default."""
        return _FIELDS[name].default

    @staticmethod
    def describe(name: str) -> str:
        """Option ``name``'s help, with its default."""
        return with_default(RenderOptions.about(name).help, RenderOptions.default(name))

    @classmethod
    def of(cls, args: tuple, options: RenderOptions | None, keywords: dict) -> RenderOptions:
        """The options of a call of ``render``: the fields given in order (``args``) and by
        name (``keywords``), or ``options`` with ``keywords`` in place of some of its fields."""
        if options is None:
            return cls(*args, **keywords)
        if args:
            raise TypeError("give the options in order or as options=RenderOptions(...), not both")
        return replace(options, **keywords)

    def for_scene(self, scene: Scene) -> RenderOptions:
        """These options with what they leave open decided for ``scene``: ``res`` and
        ``max_depth`` by its file's ``[render]`` table, else ``DEFAULT_RES`` and the
        integrator's max depth; the backend ``"auto"`` by what imports; ``spp_per_pass`` by
        ``SPP_PER_PASS``, never more than ``spp``. (``workers`` stays: the machine's.)"""
        max_depth = self.max_depth
        if max_depth is None:
            max_depth = scene.defaults.max_depth
        if max_depth is None:
            max_depth = INTEGRATORS[self.integrator].max_depth
        res = resolution(scene, self.res)
        if self.crop is not None:
            check_crop_inside(parse_crop(self.crop), res)
        return replace(
            self,
            res=res,
            max_depth=max_depth,
            backend=resolve_backend(self.backend),
            spp_per_pass=min(self.spp, self.spp_per_pass or SPP_PER_PASS),
        )

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) of the whole image: ``res`` checked (of options ``for_scene``,
        which decided it)."""
        return parse_resolution(self.res)

    @property
    def window(self) -> tuple[int, int, int, int]:
        """(x, y, width, height) of the pixels rendered: the ``crop`` (checked inside the image
        by ``for_scene``), else the whole image (of options ``for_scene``)."""
        return parse_crop(self.crop) if self.crop is not None else (0, 0, *self.size)

    def path_settings(self) -> PathSettings:
        """How the integrators trace paths (of options ``for_scene``)."""
        assert self.max_depth is not None, "path_settings() is for options decided by for_scene()"
        return PathSettings(
            rr=self.rr,
            max_depth=self.max_depth,
            strategy=self.strategy,
            heuristic=self.heuristic,
            rr_depth=self.rr_depth,
        )

    def record(self) -> dict[str, Any]:
        """The options as an image's header and a checkpoint keep them (of options
        ``for_scene``): ``res`` as ``width`` and ``height``, the roulette as text."""
        record = asdict(self)
        record["width"], record["height"] = record.pop("res")
        record["rr"] = str(self.rr)
        record["crop"] = None if self.crop is None else ",".join(map(str, parse_crop(self.crop)))
        return record


_FIELDS = {f.name: f for f in fields(RenderOptions)}


def with_default(help: str, default: Any) -> str:
    """``help`` and the default, where that is a value (None's meaning is the help's to say)."""
    return help if default is None else f"{help} (default {default})"


def parse_crop(crop: object) -> tuple[int, int, int, int]:
    """``"X,Y,W,H"`` or a sequence of four whole numbers -> (x, y, width, height), a window of
    at least one pixel with its top-left corner in the image's quadrant (``check_crop_inside``
    checks the rest, once the image's size is known)."""
    numbers: object = crop
    if isinstance(crop, str):
        try:
            numbers = [int(part) for part in crop.split(",")]
        except ValueError:
            numbers = None
    if not (isinstance(numbers, tuple | list) and len(numbers) == 4 and all(map(is_integer, numbers))):
        raise PtlabError(
            f"crop {crop!r}: expected X,Y,W,H, four whole numbers (a window of the image in "
            "pixels, from its top-left corner)"
        )
    x, y, width, height = (int(n) for n in numbers)
    if width < 1 or height < 1:
        raise PtlabError(f"crop {x},{y},{width},{height}: the window is empty (W and H must be 1 or more)")
    if x < 0 or y < 0:
        raise PtlabError(f"crop {x},{y},{width},{height}: X and Y must be 0 or more (from the top left)")
    return x, y, width, height


def check_crop_inside(crop: tuple[int, int, int, int], size: tuple[int, int]) -> None:
    """``PtlabError`` in one line unless the window ``crop`` lies inside an image of ``size``
    (width, height)."""
    x, y, width, height = crop
    if x + width > size[0] or y + height > size[1]:
        raise PtlabError(
            f"crop {x},{y},{width},{height}: the window (columns {x}-{x + width - 1}, rows "
            f"{y}-{y + height - 1}) is not inside the {size[0]}x{size[1]} image"
        )


def resolution(scene: Scene, res=None) -> tuple[int, int]:
    """(width, height) of a render of ``scene``: ``res`` if given (checked), else the scene
    file's ``[render] res``, else ``DEFAULT_RES``."""
    if res is None:
        res = scene.defaults.res or DEFAULT_RES
    return parse_resolution(res)


def takes_options(function: Callable) -> Callable:
    """Show ``RenderOptions``' fields as ``function``'s own parameters, to ``help()``, notebooks
    and ``inspect``.

    ``function(scene, *args, <keyword-only arguments>, **keywords)`` makes its options with
    ``RenderOptions.of``; its signature then reads ``function(scene, spp=16, res=None, ...,
    <keyword-only arguments>)``, and its docstring ends with every option's help.
    """
    signature = inspect.signature(function)
    scene, *rest = signature.parameters.values()
    options = [
        inspect.Parameter(
            f.name, inspect.Parameter.POSITIONAL_OR_KEYWORD, default=f.default, annotation=f.type
        )
        for f in fields(RenderOptions)
    ]
    keyword_only = [p for p in rest if p.kind is inspect.Parameter.KEYWORD_ONLY]
    new_signature = signature.replace(parameters=[scene, *options, *keyword_only])
    function.__signature__ = new_signature  # type: ignore[attr-defined]
    lines = [
        textwrap.fill(
            f"{name}: {RenderOptions.describe(name)}.", 92, initial_indent=" " * 8, subsequent_indent=" " * 12
        )
        for name in _FIELDS
    ]
    function.__doc__ = (
        (function.__doc__ or "") + "\n    Options (``RenderOptions``):\n" + "\n".join(lines) + "\n"
    )
    return function
