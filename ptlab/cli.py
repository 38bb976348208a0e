"""The ``ptlab`` command.

    ptlab render cornell-box --spp 16 --res 512 --out cornell.exr
    ptlab bench
    ptlab scenes

User errors (a bad scene, an absurd option) print one line and exit with code 2.
"""

from __future__ import annotations

import argparse
import sys

from ptlab.errors import PtlabError


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (and still exit code 2)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _rr(value: str) -> str | float:
    if value == "throughput":
        return value
    try:
        return float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{value!r} is neither 'throughput' nor a probability") from None


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="ptlab", description="A physically based path tracer in NumPy.")
    from ptlab import __version__
    parser.add_argument("--version", action="version", version=f"ptlab {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    render = commands.add_parser(
        "render", help="render a scene to an image",
        description="Render a scene (a built-in name such as cornell-box, or a scene file) "
                    "and write .png (8-bit sRGB) or .exr (linear float).")
    render.add_argument("scene", help="built-in scene name or path to a scene .toml")
    render.add_argument("--spp", type=int, default=16, help="samples per pixel (default 16)")
    render.add_argument("--res", default="512", help="N (square) or WxH (default 512)")
    render.add_argument("--out", help="output image, .png or .exr (default SCENE.png here)")
    render.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    render.add_argument("--backend", choices=("auto", "embree", "numpy"), default="auto",
                        help="ray queries: embree, the numpy BVH, or auto (embree if available)")
    render.add_argument("--sampling", choices=("cosine", "uniform"), default="cosine",
                        help="diffuse sampling (default cosine; uniform is the homework's)")
    render.add_argument("--rr", type=_rr, default="throughput", metavar="throughput|P",
                        help="Russian roulette: survival probability P (the homework's 0.8) "
                             "or 'throughput' (default)")
    render.add_argument("--max-depth", type=int, default=100, help="most bounces per path")
    render.add_argument("--workers", type=int, default=None,
                        help="threads rendering tiles at once (default: one per core); "
                             "the image does not depend on it")
    render.add_argument("--quiet", action="store_true", help="print nothing but errors")

    bench = commands.add_parser(
        "bench", help="measure rendering speed",
        description="Render the Cornell box in one process with each backend and estimator; "
                    "print seconds, samples/s, rays/s and the share of time in ray queries.")
    bench.add_argument("--res", type=int, default=512, help="square resolution (default 512)")
    bench.add_argument("--spp", type=int, default=16, help="samples per pixel (default 16)")
    bench.add_argument("--backend", action="append", choices=("embree", "numpy"),
                       help="backend to measure (repeatable; default both)")
    bench.add_argument("--estimator", action="append", choices=("homework", "default"),
                       help="estimator to measure (repeatable; default both)")
    bench.add_argument("--workers", action="append", type=int,
                       help="threads in the one process (repeatable; default 1 and every core)")

    commands.add_parser("scenes", help="list the built-in scenes")
    return parser


def _render(args) -> int:
    from ptlab import __version__
    from ptlab.image import check_output_path, write_image
    from ptlab.render import parse_resolution, render_result
    from ptlab.scene import load_scene

    scene = load_scene(args.scene)
    width, height = parse_resolution(args.res)
    out = check_output_path(args.out or f"{scene.name}.png")
    progress = _ProgressLine(args.quiet)
    try:
        result = render_result(scene, spp=args.spp, res=(width, height), seed=args.seed,
                               backend=args.backend, sampling=args.sampling, rr=args.rr,
                               max_depth=args.max_depth, workers=args.workers,
                               progress=progress)
    finally:
        progress.close()
    metadata = dict(result.settings, seconds=round(result.seconds, 3), version=__version__)
    write_image(out, result.image, metadata)
    if not args.quiet:
        print(f"{width}x{height}, {result.spp} spp, {result.seconds:.2f} s, "
              f"{result.samples_per_second / 1e6:.3f} M samples/s "
              f"({result.settings['backend']}, {args.sampling} sampling, rr {args.rr}, "
              f"{result.settings['workers']} workers)")
        print(f"wrote {out.resolve()}")
    return 0


class _ProgressLine:
    """A one-line progress display on stderr when it is a terminal; silent otherwise."""

    def __init__(self, quiet: bool):
        self.enabled = not quiet and sys.stderr.isatty()

    def __call__(self, fraction: float) -> None:
        if self.enabled:
            sys.stderr.write(f"\rrendering {fraction:6.1%}")
            sys.stderr.flush()

    def close(self) -> None:
        if self.enabled:
            sys.stderr.write("\r" + " " * 20 + "\r")


def _bench(args) -> int:
    from ptlab.bench import run_bench
    if args.res <= 0 or args.spp <= 0:
        raise PtlabError("--res and --spp must be positive")
    from ptlab.render import check_workers, default_workers
    workers = sorted({check_workers(w) for w in args.workers or [1, default_workers()]})
    run_bench(args.backend or ["embree", "numpy"], args.estimator or ["homework", "default"],
              workers, res=args.res, spp=args.spp)
    return 0


def _scenes(args) -> int:
    from ptlab.scene import builtin_scene_names
    for name in builtin_scene_names():
        print(name)
    return 0


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    handler = {"render": _render, "bench": _bench, "scenes": _scenes}[args.command]
    try:
        return handler(args)
    except PtlabError as error:
        print(f"ptlab: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("ptlab: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
