"""The ``ptlab`` command.

    ptlab render cornell-box --spp 16 --res 512 --out cornell.exr
    ptlab inspect cornell-box --res 64 --spp 4 --pixel 32,20 --plot paths.png
    ptlab compare cornell.exr reference.exr --diff diff.png
    ptlab bench
    ptlab converge cornell-box --integrators path:bsdf,path:nee,path:mis --budget 30
    ptlab grade my_material.py:MyMaterial
    ptlab scenes

User errors (a bad scene, an absurd option) print one line and exit with code 2.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
import time
import warnings
from pathlib import Path
from typing import Any

from ptlab.errors import PtlabError

# NumPy and the rest of ptlab are imported where a command needs them, after ``main`` has
# started the worker processes' server (``_start_workers_early``).


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (and still exit code 2)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


class _CommandParser(_Parser):
    """A command's parser (``ptlab render``, ``ptlab exercise check``, ...), which says itself
    that an option is unknown, so that the line points at the command's own ``--help``
    (argparse would leave it to the top parser: "see ptlab --help")."""

    def parse_known_args(self, args=None, namespace=None):
        namespace, extras = super().parse_known_args(args, namespace)
        if extras:  # (everything after a command is its own: no parent parser takes it)
            self.error(f"unrecognized arguments: {' '.join(extras)}")
        return namespace, extras


#: The commands, as ``main`` finds the one it is given.
COMMANDS = ("render", "inspect", "compare", "bench", "converge", "grade", "exercise", "scenes")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``ptlab`` command's parser; with ``command``, only that command's graders' options
    are built (``None``: all of them, as ``--help`` shows)."""
    from ptlab import __version__

    parser = _Parser(prog="ptlab", description="A physically based path tracer in NumPy.")
    parser.add_argument("--version", action="version", version=f"ptlab {__version__}")
    # (A command's own subcommands, exercise's, get the same class: argparse's default.)
    commands = parser.add_subparsers(dest="command", required=True, parser_class=_CommandParser)
    _add_render(commands, _shared_arguments())
    _add_inspect(commands)
    _add_compare(commands)
    _add_bench(commands)
    _add_converge(commands, _shared_arguments())
    grade = commands.add_parser(
        "grade",
        help="check a material's sample / eval / pdf statistically",
        description="Load a material (anything with eval, pdf and sample) from a Python file "
        "in a process of its own and run every check of ptlab.grading on it; exit 0 "
        "only if all pass (1 if any fails, 2 if the file cannot be loaded).",
    )
    exercise = commands.add_parser(
        "exercise",
        help="the step-by-step exercises: start, check, list, grade-all",
        description="Exercises from Whitted ray tracing to path tracing: `start NN` copies a "
        "chapter's file, `check NN FILE` grades it, `list` shows your progress, "
        "`grade-all NN DIR` grades a whole class.",
    )
    # The graders' own arguments are added only for their command: importing ptlab.grading
    # and ptlab.course costs every other command a tenth of a second of start-up.
    if command in (None, "grade"):
        from ptlab.course.grade_command import add_grade_arguments

        add_grade_arguments(grade)
    if command in (None, "exercise"):
        from ptlab.course.cli import add_exercise_arguments

        add_exercise_arguments(exercise)
    commands.add_parser("scenes", help="list the built-in scenes")
    return parser


def _add_option(parser: argparse.ArgumentParser, name: str, help: str | None = None, **overrides) -> None:
    """Add ``--NAME``, the render option ``name`` (a field of ``RenderOptions``): its choices,
    default, help and type, but for ``help`` and argparse's keywords in ``overrides``."""
    from ptlab.rendering.options import RenderOptions, with_default

    about = RenderOptions.about(name)
    default = RenderOptions.default(name)
    keywords: dict[str, Any]
    if default is False:  # (an on/off option: a flag)
        keywords = dict(action="store_true", default=default)
    else:
        keywords = dict(choices=about.choices, default=default, type=about.parse, metavar=about.metavar)
    keywords.update(overrides)
    if keywords.get("action") == "append":  # (a list of its own: no default to add to)
        keywords["default"] = None
    # (A flag's default is its absence: "(default False)" would say nothing.)
    shown = None if keywords.get("action") == "store_true" else keywords["default"]
    parser.add_argument(
        "--" + name.replace("_", "-"), **keywords, help=with_default(help or about.help, shown)
    )


def _shared_arguments() -> argparse.ArgumentParser:
    """The options ``render`` and ``converge`` share (a parent of their parsers; one each, as
    ``render`` changes their defaults)."""
    shared = argparse.ArgumentParser(add_help=False)
    for name in ("seed", "backend", "workers"):
        _add_option(shared, name)
    shared.add_argument("--quiet", action="store_true", help="print nothing but warnings and errors")
    return shared


def _add_render(commands, shared: argparse.ArgumentParser) -> None:
    render = commands.add_parser(
        "render",
        parents=[shared],
        help="render a scene to an image",
        description="Render a scene (a built-in name such as cornell-box, or a scene file) "
        "and write .png or .jpg (8-bit sRGB), or .exr, .hdr, .pfm or .tif (linear float).",
    )
    render.add_argument(
        "scene",
        nargs="?",
        help="built-in scene name or path to a scene .toml (with --resume: the checkpoint's)",
    )
    for name in _RENDER_OPTIONS[3:]:  # (the first three come from the shared parent)
        _add_option(render, name)
    render.add_argument(
        "--out", help="output image: .png, .jpg, .exr, .hdr, .pfm or .tif (default SCENE.png here)"
    )
    render.add_argument(
        "--exposure",
        type=float,
        default=0.0,
        metavar="STOPS",
        help="brighten (or, below 0, darken) an 8-bit image by 2^STOPS (default 0; "
        "the float formats keep the values)",
    )
    render.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="render on the Dask cluster whose scheduler is at ADDRESS (needs the dask extra)",
    )
    render.add_argument(
        "--checkpoint", metavar="FILE", help="save the render's state to FILE after every pass"
    )
    render.add_argument(
        "--resume",
        metavar="FILE",
        help="continue the render saved in checkpoint FILE, with its scene, options and output "
        "(options given must agree with it; --spp may raise its samples)",
    )
    render.add_argument(
        "--spp-map",
        metavar="FILE",
        help="also write the samples each pixel got: a heat map (.png) or the counts (.exr)",
    )
    render.add_argument(
        "--preview-every",
        type=float,
        metavar="SECONDS",
        help="after a pass, rewrite the output image if SECONDS have passed (denoised, with --denoise)",
    )
    render.add_argument(
        "--aov",
        action="store_true",
        help="also write the denoiser's feature images into the .exr output, as layers beside R, G, "
        "B: albedo.R/G/B, normal.X/Y/Z and direct.R/G/B (the emission seen directly), and, "
        "with --denoise, noisy.R/G/B (the image before denoising)",
    )
    # An option left out is None here (its --help still names the default), so that a
    # resumed render can tell it from one given: it takes the checkpoint's (``_resumed``).
    render.set_defaults(**dict.fromkeys(_RENDER_OPTIONS), layout={})


#: The render options (fields of ``RenderOptions``) that ``ptlab render`` takes.
_RENDER_OPTIONS = (
    "seed",
    "backend",
    "workers",
    "spp",
    "res",
    "integrator",
    "strategy",
    "heuristic",
    "sampler",
    "sampling",
    "rr",
    "rr_depth",
    "max_depth",
    "target_error",
    "max_spp",
    "time_limit",
    "denoise",
    "crop",
)


def _add_inspect(commands) -> None:
    inspect = commands.add_parser(
        "inspect",
        help="one pixel's paths, vertex by vertex, as render traces them",
        description="Trace every sample of one pixel exactly as 'ptlab render' does with the "
        "same options, and print each sample's vertices (the hit, the light sample, Russian "
        "roulette, the BSDF sample, the throughput), its contribution, and the pixel's value.",
    )
    inspect.add_argument("scene", help="built-in scene name or path to a scene .toml")
    inspect.add_argument(
        "--pixel", required=True, metavar="X,Y", help="the pixel: X from the left, Y from the top"
    )
    inspect.add_argument("--sample", type=int, metavar="K", help="print only sample K (0, 1, ...)")
    inspect.add_argument("--json", metavar="FILE", help="also write everything to FILE as JSON")
    inspect.add_argument(
        "--plot", metavar="FILE.png", help="draw the paths from above and from the side (matplotlib)"
    )
    for name in _INSPECT_OPTIONS:
        _add_option(inspect, name)


#: The render options that ``ptlab inspect`` takes: ``render``'s that change the pixel.
#: (A render to a target error gives each pixel its own samples: inspect has a fixed spp.)
_INSPECT_OPTIONS = tuple(
    name
    for name in _RENDER_OPTIONS
    if name not in ("workers", "target_error", "max_spp", "time_limit", "crop")  # (--pixel is the image's)
)


def _inspect(args) -> int:
    from ptlab.atomic import check_writable_file
    from ptlab.inspector import inspect_pixel, parse_pixel
    from ptlab.rendering import RenderOptions
    from ptlab.scene_file import load_scene

    pixel = parse_pixel(args.pixel)
    options = RenderOptions(**{name: getattr(args, name) for name in _INSPECT_OPTIONS}, workers=1)
    if args.plot is not None and Path(args.plot).suffix.lower() != ".png":
        raise PtlabError(f"--plot {args.plot}: give a .png file")
    for out in (args.json, args.plot):
        if out is not None:
            check_writable_file(out)  # (before the work, as render's --out)
    scene = load_scene(args.scene)
    found = inspect_pixel(scene, pixel, options=options)
    print(found.table(args.sample))
    if args.json is not None:
        found.write_json(args.json)
        print(f"wrote {Path(args.json).resolve()}")
    if args.plot is not None:
        from dataclasses import replace

        from ptlab.rendering import render

        # The picture beside the paths: the image, with a few samples (it only shows where).
        preview = render(scene, options=replace(options, spp=min(options.spp, 4), workers=None))
        found.plot(args.plot, scene, preview)
        print(f"wrote {Path(args.plot).resolve()}")
    return 0


def _add_compare(commands) -> None:
    from ptlab.image import LINEAR_FORMATS

    compare = commands.add_parser(
        "compare",
        help="compare an image with a reference: relMSE, mean ratio, largest difference",
        description="Compare image A with the reference B, as pbrt's 'imgtool diff' does, with "
        "ptlab's metric: print both sizes, the relMSE of A against B (the mean over pixels "
        "and channels of (A - B)^2 / (B + 0.01)^2), the ratio of A's mean to B's per channel "
        "(1 where A is unbiased), the largest absolute difference and its pixel, and the "
        "share of pixels that differ at all. Files are read through OpenImageIO: "
        f"{', '.join(LINEAR_FORMATS)} as linear values, 8- and 16-bit files (.png, .jpg) "
        "decoded from sRGB to linear. A window of an image (ptlab render --crop, as an .exr "
        "or .tif that records its place) is compared with that window of the other. Exit 0; "
        "1 if --tolerance is given and the relMSE is above it; 2 if a file cannot be read, "
        "the sizes differ, or a pixel is NaN or infinite.",
    )
    compare.add_argument("a", metavar="A", help="the image to judge")
    compare.add_argument("b", metavar="B", help="the reference")
    compare.add_argument(
        "--diff",
        metavar="FILE",
        help="also write where they differ: each pixel's relative squared error (A - B)^2 / "
        "(B + 0.01)^2 (the mean over channels, whose mean is the relMSE); as a picture "
        "(.png, .jpg): false colour on a log scale, with the scale beside it, identical "
        "pixels grey; as a linear file (.exr, .hdr, .pfm, .tif): the values themselves, in "
        "each channel",
    )
    compare.add_argument(
        "--tolerance",
        type=float,
        metavar="RELMSE",
        help="exit 1 if the relMSE is above RELMSE (for scripts and CI; 0: any difference)",
    )
    compare.add_argument("--json", action="store_true", help="print the figures as JSON instead")


def _compare(args) -> int:
    import json

    from ptlab.measure.compare import compare_files, write_difference

    if args.tolerance is not None and not 0 <= args.tolerance < float("inf"):
        raise PtlabError(f"--tolerance {args.tolerance}: must be a relMSE, 0 or more")
    if args.diff is not None:
        from ptlab.image import check_output_path

        check_output_path(args.diff)
        for name, image in (("A", args.a), ("B", args.b)):
            if Path(args.diff).resolve() == Path(image).resolve():
                raise PtlabError(f"--diff {args.diff}: is image {name}; write the difference elsewhere")
    comparison = compare_files(args.a, args.b)
    if args.diff is not None:
        write_difference(args.diff, comparison)
    if args.json:
        figures = comparison.figures()
        if args.tolerance is not None:
            figures["tolerance"] = args.tolerance
            figures["within_tolerance"] = comparison.relmse <= args.tolerance
        print(json.dumps(figures, indent=1))
    else:
        print(comparison.report())
        if args.tolerance is not None:
            within = "within" if comparison.relmse <= args.tolerance else "above"
            print(f"relMSE {comparison.relmse:.6g}: {within} the tolerance {args.tolerance:g}")
        if args.diff is not None:
            print(f"wrote {Path(args.diff).resolve()}")
    return 1 if args.tolerance is not None and comparison.relmse > args.tolerance else 0


def _add_bench(commands) -> None:
    from ptlab.accel import BACKENDS
    from ptlab.rendering.options import RenderOptions

    bench = commands.add_parser(
        "bench",
        help="measure rendering speed, or accuracy per second",
        description="Render the Cornell box with each backend, estimator, sampler and worker "
        "count; print wall seconds, samples/s, rays/s, the shares of time in ray "
        "queries and in the sampler, and the parallel speed-up. With --accuracy: "
        "render it with each sampler (alternately, --repeat times with other seeds) "
        "and print relMSE against a cached high-spp reference, seconds, their "
        "product and the sampler's share.",
    )
    bench.add_argument("--res", type=int, help="square resolution (default 512; 256 with --accuracy)")
    bench.add_argument("--spp", type=int, help="samples per pixel (default 16; 64 with --accuracy)")
    _add_option(
        bench,
        "sampler",
        action="append",
        help=f"sampler to measure (repeatable; default {RenderOptions.sampler}, all three with --accuracy)",
    )
    bench.add_argument(
        "--accuracy",
        action="store_true",
        help="compare the samplers' error at equal spp and its product with time",
    )
    bench.add_argument(
        "--repeat",
        type=int,
        default=3,
        help="--accuracy: renders per sampler, alternating, each with another "
        "seed; --against: runs of each program (default 3)",
    )
    bench.add_argument(
        "--reference",
        metavar="REF.exr",
        help="--accuracy: the reference image (linear EXR at --res) instead of a rendered one",
    )
    bench.add_argument(
        "--reference-spp",
        type=int,
        default=4096,
        metavar="N",
        help="--accuracy: spp of the reference (default 4096; cached in "
        "$PTLAB_CACHE or ~/.cache/ptlab/references)",
    )
    _add_option(
        bench,
        "backend",
        action="append",
        choices=[name for name in BACKENDS if name != "auto"],
        help="backend to measure (repeatable; default both)",
    )
    bench.add_argument(
        "--estimator",
        action="append",
        choices=("homework", "default"),
        help="estimator to measure (repeatable; default both)",
    )
    _add_option(
        bench,
        "workers",
        action="append",
        help="worker processes (repeatable; default one per core); one worker is "
        "always measured too, as the baseline of the speed-up",
    )
    bench.add_argument(
        "--against",
        metavar="PATH",
        help="time PATH, a compiled C++ path tracer such as the GAMES101 Homework 7 "
        "build/RayTracing, against ptlab render with the homework's estimator "
        "at its image's size, alternately --repeat times, as whole processes",
    )
    bench.add_argument(
        "--tail",
        action="store_true",
        help="time each bounce of one-worker renders, batches kept full and, alternately "
        "(--repeat times), left to run dry as before path regeneration; print the share "
        "of time in bounces with few live paths, and the ratio of times",
    )
    bench.add_argument(
        "--cpp-args",
        default="{spp}",
        metavar="ARGS",
        help="--against: the C++ program's arguments ({spp} is replaced by --spp; default '{spp}')",
    )


def _add_converge(commands, shared: argparse.ArgumentParser) -> None:
    converge = commands.add_parser(
        "converge",
        parents=[shared],
        help="chart error against time for several estimators",
        description="Render the scene with each estimator at 1, 2, 4, ... spp until its time "
        "budget is spent, compare every render with a reference, and write "
        "convergence.csv (integrator, spp, seconds, rmse, relmse), a log-log chart "
        "convergence.png, an equal-time strip equal-time.png with error heat maps, "
        "and the reference.exr. Prints the time each needs to reach --target.",
    )
    converge.add_argument("scene", help="built-in scene name or path to a scene .toml")
    converge.add_argument(
        "--integrators",
        default="path:bsdf,path:nee,path:mis",
        metavar="LIST",
        help="comma-separated estimators: path:bsdf, path:nee, path:mis, "
        "whitted, each optionally @SAMPLER, e.g. path:nee@independent, +adaptive to "
        "render to a ladder of target errors, e.g. path:nee+adaptive, and +denoise to denoise "
        "each render (the denoise extra), e.g. path:nee+denoise "
        "(default path:bsdf,path:nee,path:mis)",
    )
    _add_option(converge, "sampler", help="the sampler of estimators without @SAMPLER")
    source = converge.add_mutually_exclusive_group()
    source.add_argument(
        "--reference", metavar="REF.exr", help="the reference image (linear EXR at the same resolution)"
    )
    source.add_argument(
        "--reference-spp",
        type=int,
        default=1024,
        metavar="N",
        help="without --reference: render one with path:mis at N spp (default "
        "1024), cached in $PTLAB_CACHE or ~/.cache/ptlab/references",
    )
    source.add_argument(
        "--estimated",
        action="store_true",
        help="no reference: chart each render's own estimate of its error (adaptive "
        "estimators only, e.g. --integrators path:nee+adaptive,path:mis+adaptive)",
    )
    converge.add_argument(
        "--budget", type=float, default=30.0, metavar="SECONDS", help="render time per estimator (default 30)"
    )
    converge.add_argument("--res", default="256", help="N (square) or WxH (default 256)")
    converge.add_argument("--out", metavar="DIR", help="output folder (default converge-SCENE)")
    converge.add_argument(
        "--target", type=float, default=0.01, help="report the time to reach this relMSE (default 0.01)"
    )
    converge.add_argument(
        "--no-cache", action="store_true", help="render the reference even if a cached one exists"
    )


def _render(args) -> int:
    from ptlab.atomic import check_writable_file
    from ptlab.image import check_output_path
    from ptlab.rendering import RenderOptions, pass_schedule, render_result
    from ptlab.rendering.display import write_spp_map
    from ptlab.rendering.executors import dask_executor
    from ptlab.rendering.progress import ProgressBar
    from ptlab.scene_file import load_scene

    if args.resume is not None:
        args = _resumed(args)
    if args.scene is None:
        raise PtlabError("give the scene: a built-in name (ptlab scenes) or a scene file, or --resume FILE")
    given = {name: getattr(args, name) for name in _RENDER_OPTIONS if getattr(args, name) is not None}
    options = RenderOptions(**given, **args.layout)
    scene = load_scene(args.scene)
    decided = options.for_scene(scene)  # (a crop outside the image fails here, in one line)
    out = check_output_path(args.out or f"{scene.name}.png")
    checkpoint = args.checkpoint or args.resume
    if checkpoint is not None:
        check_writable_file(checkpoint)
    spp_map = _check_render_request(args, options, out)
    _, _, width, height = decided.window
    progress = ProgressBar(
        width * height * options.spp,
        len(pass_schedule(options.spp)),
        quiet=args.quiet,
        target=options.target_error,
    )
    run = dict(
        options=options,
        checkpoint=checkpoint,
        resume=args.resume,
        progress=progress,
        on_pass=_Preview(out, args.preview_every, args.exposure, options.denoise, _window(decided)),
        command=dict(scene=_scene_argument(args.scene), out=str(out.resolve())),
        features=args.aov,
    )
    with _StopOnSignal(args.whole_process) as signals, warnings.catch_warnings():
        # (A render stopped before its first pass: _interrupted says so in its own words.)
        warnings.filterwarnings("ignore", "the render stopped before any tile", RuntimeWarning)
        stop = signals.requested.is_set
        try:
            if args.scheduler:
                with dask_executor(args.scheduler) as executor:
                    result = render_result(scene, executor=executor, stop=stop, **run)
            else:
                result = render_result(scene, stop=stop, **run)
        finally:
            progress.close()
        # The render is over; writing what it has must not be cut short (a KeyboardInterrupt
        # inside OpenImageIO's import aborts the process): a signal now only waits.
        signals.holding = True
        if result.nonfinite:  # (a bug in a material or an integrator: said even with --quiet)
            print(f"ptlab: {result.nonfinite_message()}", file=sys.stderr)
        if not result.complete:
            return _interrupted(result, out, checkpoint, signals.exit_code, args.exposure, args.aov)
        _write(out, result, args.exposure, layers=args.aov)
        if spp_map is not None:
            write_spp_map(spp_map, result.counts, result.window)
    _said_of_a_render(args, decided, options, result, out, spp_map)
    return 0


def _said_of_a_render(args, decided, options, result, out: Path, spp_map: Path | None) -> None:
    """What ``ptlab render`` says of a render it wrote: a black image, always (a warning);
    unless ``--quiet``, its size, samples and speed, the denoiser's and the target's lines,
    and the files written."""
    from ptlab.image import WINDOW_FORMATS

    rendered = result.noisy if result.noisy is not None else result.image  # (a denoiser's haze is no light)
    if not (rendered > 0).any() and options.integrator in ("path", "whitted"):
        # (A window may see only what is unlit, in a lit image: say nothing of the lights.)
        said = (
            "the window is black: no camera ray in it saw or received any light"
            if options.crop is not None
            else "the image is black: no camera ray saw or received any light (do the lights face the scene?)"
        )
        print(f"ptlab: warning: {said}", file=sys.stderr)
    if args.quiet:
        return
    print(f"{_size_said(decided)}, {_spp_said(result)}, {result.seconds:.2f} s, " + _how(result, options))
    if options.denoise:
        print(_denoised_said(result))
    if options.target_error is not None:
        print(_target_said(result, options))
    print(f"wrote {out.resolve()}" + (f" and {spp_map.resolve()}" if spp_map is not None else ""))
    if options.crop is not None and out.suffix.lower() not in WINDOW_FORMATS:
        print(f"(a {out.suffix} file does not record the window's place: .exr or .tif keep it)")


def _check_render_request(args, options, out: Path) -> Path | None:
    """Check, before the scene's work, what ``ptlab render`` asks beyond the options (a bad
    one fails at once, in one line); return the spp map's path, if one is asked for."""
    from ptlab.image import check_output_path
    from ptlab.rendering.settings import check_workers

    if args.preview_every is not None and not args.preview_every >= 0:  # (NaN too)
        raise PtlabError("--preview-every must be zero or more seconds")
    check_workers(options.workers)
    if args.aov and out.suffix.lower() != ".exr":
        raise PtlabError(
            f"--aov: the feature images go into an .exr output as its layers, not {out.suffix or out.name}"
        )
    return check_output_path(args.spp_map) if args.spp_map else None


def _size_said(options) -> str:
    """``64x64``, or for a crop, ``16x8 window at (8, 4) of 64x64`` (options ``for_scene``)."""
    x, y, width, height = options.window
    if options.crop is None:
        return f"{width}x{height}"
    return f"{width}x{height} window at ({x}, {y}) of {options.size[0]}x{options.size[1]}"


def _window(options):
    """Where a crop's image sits in the whole image, for its file (``ptlab.image.Window``),
    or None for the whole image (options ``for_scene``)."""
    from ptlab.image import Window

    return None if options.crop is None else Window(*options.window[:2], *options.size)


def _spp_said(result) -> str:
    """``16 spp``, or where pixels differ, ``16-837 spp (mean 92.2)``."""
    if result.spp == result.spp_max:
        return f"{result.spp} spp"
    return f"{result.spp}-{result.spp_max} spp (mean {result.spp_mean:.1f})"


def _denoised_said(result) -> str:
    """The line after a denoised render: with what, in how long, and its error's estimate,
    or why there is none (an estimate that cannot be trusted is not printed)."""
    settings = result.settings
    if not result.denoised:
        return "not denoised: no pixel had a sample"
    said = f"denoised by {settings['denoised']} in {settings['denoise_seconds']:.2f} s"
    if result.relmse_estimate is not None:
        return said + f", estimated relMSE {result.relmse_estimate:.4g}"
    said += f"; its error is not estimated: {result.estimate_refused}"
    if (bound := settings.get("relmse_bound")) is not None:
        said += f"; its relMSE is below {bound:.4g}"
    return said


def _target_said(result, options) -> str:
    """The line after a render to a target error: the estimate, and why it stopped."""
    estimate = result.relmse_estimate
    bound = result.settings.get("relmse_bound")
    if estimate is None and bound is not None:  # (a denoised render's refused estimate)
        said = f"relMSE below {bound:.4g} (not estimated closer), target {options.target_error:g}"
    elif estimate is None:  # (then the noisy image's estimate decided: ``render_result``)
        noisy = result.settings.get("noisy_relmse_estimate")
        if noisy is None:
            return f"target {options.target_error:g}: not reached (the denoised image's error is not known)"
        reached = "reached" if noisy <= options.target_error else "not reached"
        return (
            f"target {options.target_error:g} {reached} by the noisy image's estimated relMSE "
            f"({noisy:.4g}); the denoised image's error is not known"
        )
    else:
        said = f"estimated relMSE {estimate:.4g}, target {options.target_error:g}"
    if result.target_reached:
        return said + ": reached"
    if result.settings.get("target_end") == "time limit":
        return said + f": not reached within the time limit, {options.time_limit:g} s (--time-limit)"
    return said + f": not reached with at most {result.settings['max_spp']} spp per pixel (--max-spp)"


def _how(result, options) -> str:
    """The speed and the settings that made it, as the summary line after a render says them:
    the sampling and roulette only where the integrator uses them, and the workers it had."""
    parts = [result.settings["backend"], f"{options.sampler} sampler"]
    if options.integrator == "path":
        parts += [f"{options.sampling} sampling", f"rr {options.rr}"]
    else:
        parts.append(options.integrator)
    workers = result.settings["workers"]
    parts.append("dask" if workers == "executor" else f"{workers} worker{'s' if workers != 1 else ''}")
    return f"{result.samples_per_second / 1e6:.3f} M samples/s ({', '.join(parts)})"


def _resumed(args):
    """``args`` completed from the checkpoint ``args.resume``: its scene, output and each
    option not given. Options given are kept: the checkpoint refuses those that contradict
    it, but for a larger ``--spp`` (``ptlab.rendering.checkpoint``)."""
    from ptlab.rendering import RenderOptions
    from ptlab.rendering.checkpoint import read_checkpoint

    saved, command, _ = read_checkpoint(args.resume)
    if "width" in saved and "height" in saved:
        saved = dict(saved, res=f"{saved['width']}x{saved['height']}")
    for name in _RENDER_OPTIONS:
        value = saved.get(name)
        if getattr(args, name) is None and value is not None and name != "workers":  # (the machine's)
            parse = RenderOptions.about(name).parse
            setattr(args, name, parse(value) if isinstance(value, str) and parse is not None else value)
    if args.scene is None:
        args.scene = command.get("scene")
        if args.scene is None:
            raise PtlabError(f"{args.resume}: this checkpoint does not record its scene: give the scene too")
    if args.out is None:
        args.out = command.get("out")
    if saved.get("features") is True and not saved.get("denoise"):  # (it was asked for: --aov)
        args.aov = True
    # How the image is cut into jobs, which the command line does not set (the API does).
    args.layout = {name: saved[name] for name in ("tile_size", "spp_per_pass") if name in saved}
    return args


def _scene_argument(scene: str) -> str:
    """A scene as a checkpoint records it: a file as an absolute path (the render may be
    resumed from another folder), a built-in scene by its name."""
    return str(Path(scene).resolve()) if Path(scene).is_file() else scene


def _write(out: Path, result, exposure: float = 0.0, layers: bool = False) -> None:
    """Write the image with the render's settings, its spp and whether it is complete (and,
    with ``layers``, the feature images and the noisy image as the EXR's layers)."""
    from ptlab import __version__
    from ptlab.image import write_image

    metadata = dict(
        result.settings,
        seconds=round(result.seconds, 3),
        version=__version__,
        complete=int(result.complete),
        nonfinite=result.nonfinite,
    )
    if result.spp_max != result.spp:
        metadata["spp_max"] = result.spp_max
        metadata["spp_mean"] = round(result.spp_mean, 3)
    if result.relmse_estimate is not None:
        metadata["relmse_estimate"] = result.relmse_estimate
    image = result.image
    if result.settings["integrator"] == "depth" and out.suffix.lower() == ".png":
        # Distances do not fit in [0, 1]: scale the farthest to white (the EXR keeps them).
        scale = float(image.max()) or 1.0
        image, metadata["depth_scale"] = image / scale, scale
    extra = None
    if layers and result.features is not None:
        extra = dict(result.features)
        if result.noisy is not None:
            extra["noisy"] = result.noisy
    write_image(out, image, metadata, exposure=exposure, layers=extra, window=result.window)


def _interrupted(
    result, out: Path, checkpoint, exit_code: int, exposure: float = 0.0, layers: bool = False
) -> int:
    """Keep what an interrupted render has (with its layers, if asked for: ``--aov``);
    ``exit_code`` is the signal's (130 for Ctrl-C, 143 for SIGTERM), as a shell reports a
    command that the signal ended."""
    if result.spp_max == 0:
        print("ptlab: interrupted before any tile finished; nothing written", file=sys.stderr)
        return exit_code
    _write(out, result, exposure, layers)
    spread = (
        f"{result.spp} spp"
        if result.spp == result.spp_max
        else (f"{result.spp}-{result.spp_max} spp (tiles differ by a pass)")
    )
    print(f"ptlab: interrupted: wrote {out.resolve()} with {spread}", file=sys.stderr)
    if checkpoint is not None:
        print(f"ptlab: resume with --resume {checkpoint}", file=sys.stderr)
    return exit_code


class _StopOnSignal:
    """Turns the first Ctrl-C (SIGINT) or SIGTERM into a polite stop request.

    The render then ends the jobs in flight and keeps the passes done; a second Ctrl-C
    interrupts it at once, but once ``holding`` (the render over) it waits for the image to be
    written. ``exit_code`` is then 128 + the first signal's number. If ``whole_process`` (the
    command is this process), a stopped command leaves these signals ignored: only its exit
    is left, which a later one would cut short (a traceback from an exit hook, or death by
    the signal once Python has reset its handlers).
    """

    def __init__(self, whole_process: bool = False):
        self.whole_process = whole_process

    def __enter__(self) -> _StopOnSignal:
        self.requested = threading.Event()
        self.holding = False  # (True: a signal is noted, never raised)
        self.exit_code = 128 + signal.SIGINT
        self.previous: dict[int, Any] = {}
        if threading.current_thread() is threading.main_thread():
            for signum in (signal.SIGINT, signal.SIGTERM):
                self.previous[signum] = signal.signal(signum, self._handle)
        return self

    def _handle(self, signum, frame) -> None:
        if self.requested.is_set() and not self.holding:
            raise KeyboardInterrupt
        self.exit_code = 128 + signum
        self.requested.set()

    def __exit__(self, *exc) -> None:
        ignore = self.whole_process and self.requested.is_set()
        for signum, handler in self.previous.items():
            signal.signal(signum, signal.SIG_IGN if ignore else handler)


class _Preview:
    """After a pass, rewrites the output image if ``every`` seconds have passed (denoised, for
    a denoised render: what it will look like)."""

    def __init__(
        self, out: Path, every: float | None, exposure: float = 0.0, denoise: bool = False, window=None
    ):
        self.out, self.every, self.exposure, self.denoise = out, every, exposure, denoise
        self.window = window  # (a crop's place in the image: ``ptlab.image.Window``)
        self.last = time.monotonic()

    def __call__(self, film) -> None:
        if self.every is None or time.monotonic() - self.last < self.every:
            return
        from ptlab.image import write_image
        from ptlab.rendering.denoising import preview

        image, denoised_by = preview(film, self.denoise)
        metadata: dict[str, Any] = dict(spp=film.spp, complete=0, preview=1)
        if denoised_by:
            metadata["denoised"] = denoised_by
        write_image(self.out, image, metadata, exposure=self.exposure, window=self.window)
        self.last = time.monotonic()


def _converge(args) -> int:
    from ptlab.atomic import check_writable_folder
    from ptlab.measure.converge import default_cache_dir, parse_estimators, run_converge
    from ptlab.rendering.settings import MAX_SPP, check_seed, check_workers, parse_resolution
    from ptlab.scene_file import load_scene

    estimators = parse_estimators(args.integrators, args.sampler)
    check_seed(args.seed)
    scene = load_scene(args.scene)
    res = parse_resolution(args.res)
    if not 1 <= args.reference_spp <= MAX_SPP:
        raise PtlabError(f"--reference-spp {args.reference_spp}: must be from 1 to {MAX_SPP}")
    if not 0 < args.target < float("inf"):
        raise PtlabError(f"--target {args.target}: must be a positive relMSE")
    out_dir = check_writable_folder(args.out or f"converge-{scene.name}")
    cache_dir = None
    if not args.no_cache and args.reference is None and not args.estimated:
        try:
            cache_dir = check_writable_folder(default_cache_dir())
        except PtlabError as error:
            raise PtlabError(f"reference cache {error} (set PTLAB_CACHE, or give --no-cache)") from None
    echo = (lambda text: None) if args.quiet else print
    run_converge(
        scene,
        estimators,
        out_dir,
        res,
        args.budget,
        seed=args.seed,
        reference=args.reference,
        reference_spp=args.reference_spp,
        cache_dir=cache_dir,
        target=args.target,
        echo=echo,
        quiet=args.quiet,
        estimated=args.estimated,
        workers=check_workers(args.workers),
        backend=args.backend,
    )
    return 0


def _bench(args) -> int:
    from ptlab.measure.bench import ESTIMATOR_OPTIONS, run_accuracy, run_bench
    from ptlab.measure.converge import default_cache_dir
    from ptlab.rendering import RenderOptions
    from ptlab.rendering.executors import default_workers
    from ptlab.rendering.settings import MAX_SPP, check_workers
    from ptlab.samplers import SAMPLERS

    if args.against is not None:
        from ptlab.measure.against import reject_options, run_against

        reject_options(
            {
                "--accuracy": args.accuracy,
                "--res": args.res,
                "--backend": args.backend,
                "--estimator": args.estimator,
                "--sampler": args.sampler,
                "a second --workers": (args.workers or [])[1:],
            }
        )
        run_against(
            args.against,
            args.cpp_args,
            spp=16 if args.spp is None else args.spp,
            repeat=args.repeat,
            workers=(args.workers or [None])[0],
        )
        return 0
    res = args.res if args.res is not None else (256 if args.accuracy else 512)
    spp = args.spp if args.spp is not None else (64 if args.accuracy else 16)
    if res <= 0 or spp <= 0:
        raise PtlabError("--res and --spp must be positive")
    if args.tail:
        from ptlab.measure.tail import run_tail
        from ptlab.scene_file import load_scene

        if not 1 <= args.repeat <= 100:
            raise PtlabError(f"--repeat {args.repeat}: must be from 1 to 100")
        scene = load_scene("cornell-box")
        for estimator in args.estimator or ["homework", "default"]:
            print(f"{scene.summary()}; {res}x{res}, {spp} spp, {estimator} estimator, 1 worker")
            run_tail(
                scene,
                ESTIMATOR_OPTIONS[estimator],
                res,
                spp,
                args.repeat,
                (args.backend or [RenderOptions.backend])[0],
            )
        return 0
    if args.accuracy:
        if not 1 <= args.repeat <= 100:
            raise PtlabError(f"--repeat {args.repeat}: must be from 1 to 100")
        if not 1 <= args.reference_spp <= MAX_SPP:
            raise PtlabError(f"--reference-spp {args.reference_spp}: must be from 1 to {MAX_SPP}")
        workers = check_workers(args.workers[0]) if args.workers else 1
        run_accuracy(
            args.sampler or list(SAMPLERS),
            res=res,
            spp=spp,
            repeat=args.repeat,
            reference=args.reference,
            reference_spp=args.reference_spp,
            workers=workers,
            cache_dir=default_cache_dir(),
            backend=(args.backend or [RenderOptions.backend])[0],
            **ESTIMATOR_OPTIONS[(args.estimator or ["default"])[0]],
        )
        return 0
    # One worker always runs too: the speed-up is measured against it, in the same run.
    worker_counts = sorted({1} | {check_workers(w) for w in args.workers or [default_workers()]})
    run_bench(
        args.backend or ["embree", "numpy"],
        args.estimator or ["homework", "default"],
        worker_counts,
        res=res,
        spp=spp,
        samplers=tuple(args.sampler or [RenderOptions.sampler]),
    )
    return 0


def _scenes(args) -> int:
    from ptlab.scene_file import builtin_scene_description, builtin_scene_names

    names = builtin_scene_names()
    width = max(map(len, names), default=0) + 2
    for name in names:
        print(f"{name:<{width}}{builtin_scene_description(name)}".rstrip())
    return 0


class _Glance(argparse.ArgumentParser):
    """A parser that says nothing of a bad option (it raises ValueError): the real one will."""

    def error(self, message: str):
        raise ValueError(message)


def _start_workers_early(argv: list[str]) -> None:
    """For a ``render`` on worker processes, start their fork server before this process
    imports NumPy: the server's imports then run alongside ours instead of after them
    (docs/performance.md).

    Not for a render of one job (one tile, one pass), which runs in this process: there the
    server's imports would only compete with ours. This is only
    a glance at the options: a wrong guess costs nothing but that time, and the real parser
    checks them afterwards.
    """
    from ptlab.rendering.sizes import DEFAULT_SPP, SPP_PER_PASS, TILE_SIZE

    glance = _Glance(add_help=False, allow_abbrev=False)
    glance.add_argument("--workers", type=int)
    glance.add_argument("--res")
    glance.add_argument("--spp", type=int, default=DEFAULT_SPP)
    glance.add_argument("--scheduler")
    glance.add_argument("-h", "--help", action="store_true")
    try:
        options, _ = glance.parse_known_args(argv)
    except ValueError:  # (an unreadable number: the real parser says so)
        return
    size = [int(n) for n in (options.res or "").lower().split("x") if n.isdigit()]
    one_tile = bool(size) and max(size) <= TILE_SIZE
    if options.help or options.scheduler is not None or (one_tile and options.spp <= SPP_PER_PASS):
        return
    from ptlab.rendering.executors import default_workers, start_worker_server

    if (default_workers() if options.workers is None else options.workers) > 1:
        start_worker_server()


def _warning_line(message, category, filename, lineno, file=None, line=None) -> None:
    """A warning as the command's own line on stderr (``ptlab: warning: ...``), not Python's
    two lines naming the file and line of ptlab's code that warned."""
    print(f"ptlab: warning: {message}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    whole_process = argv is None
    if whole_process and signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        # (Started with SIGINT ignored, as a shell's background job is: the command stops on
        # it all the same, from now, not only once a render runs; rendering/scheduler.py,
        # ``interruptible``.)
        signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        return _run(sys.argv[1:] if argv is None else argv, whole_process)
    except BrokenPipeError:  # the reader (head, a pager) stopped reading: not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except PtlabError as error:
        from ptlab.course.sandbox.shown import shown_line  # (it may quote a student's file name)

        print(f"ptlab: error: {shown_line(error)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # (before a render's own handler, or in another command)
        print("ptlab: interrupted", file=sys.stderr)
        return 130


def _run(argv: list[str], whole_process: bool) -> int:
    """The command ``argv`` asks for (``main``, which turns its errors into lines)."""
    command = next((word for word in argv if not word.startswith("-")), None)
    if command == "render":
        _start_workers_early(argv)
    args = build_parser(command if command in COMMANDS else None).parse_args(argv)
    args.whole_process = whole_process  # (not a caller's, such as a test's, in its process)
    if args.command == "grade":
        from ptlab.course.grade_command import run_grade as handler
    elif args.command == "exercise":
        from ptlab.course.cli import run_exercise as handler
    else:
        handler = {
            "render": _render,
            "inspect": _inspect,
            "compare": _compare,
            "bench": _bench,
            "converge": _converge,
            "scenes": _scenes,
        }[args.command]
    with warnings.catch_warnings():
        warnings.showwarning = _warning_line
        code = handler(args)
    sys.stdout.flush()
    return code


if __name__ == "__main__":
    sys.exit(main())
