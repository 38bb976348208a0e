"""Race ptlab against Mitsuba 3 on the same scene: seconds, error, and whether they agree.

Not run in CI, and Mitsuba is not a dependency of ptlab: install it beside ptlab first (the
``llvm_ad_rgb`` variant needs a libLLVM recent enough for Dr.Jit, e.g. Debian's ``libllvm19``;
the script says so, in one line with exit code 2, if Mitsuba cannot render here).

    pip install mitsuba
    python scripts/against_mitsuba.py --workers 2                  # cornell-box, 256x256, 64 spp
    python scripts/against_mitsuba.py --ptlab-reference ref.exr --ptlab-reference-spp 8192
    # to a clean image: ptlab --denoise against Mitsuba + OIDN, ptlab's target Mitsuba's
    # error at 256 spp, whole processes only
    python scripts/against_mitsuba.py --denoise --target-from-mitsuba-spp 256 --spp 16 --processes-only

Exit codes: 0 when it ran (and, with --ptlab-reference, the references agree), 1 when a
renderer failed or the references differ by more than noise, 2 for an option, a scene or a
Mitsuba that cannot work. How it measures is ``ptlab.measure.against_mitsuba``'s (below);
how it writes Mitsuba's scene, ``ptlab.measure.mitsuba_export``'s.
"""

from __future__ import annotations

import argparse
import sys
from typing import NoReturn

from ptlab.errors import PtlabError
from ptlab.integrators.path import STRATEGIES
from ptlab.measure import against_mitsuba
from ptlab.measure.against_mitsuba import MITSUBA_SAMPLERS, ComparisonOptions, RenderError, compare
from ptlab.rendering.settings import parse_resolution
from ptlab.samplers import SAMPLERS

PROG = "against_mitsuba.py"
DEFAULTS = ComparisonOptions()


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (and still exit code 2)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """The command's options; their defaults are ``ComparisonOptions``'."""
    width, height = DEFAULTS.res
    parser = _Parser(
        prog=PROG,
        description=f"{__doc__}\n{against_mitsuba.__doc__}",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--scene",
        default=DEFAULTS.scene,
        help=f"built-in scene name or scene file, diffuse materials only (default {DEFAULTS.scene})",
    )
    res = str(width) if width == height else f"{width}x{height}"
    parser.add_argument("--res", default=res, help=f"N (square) or WxH (default {res})")
    parser.add_argument(
        "--spp", type=int, default=DEFAULTS.spp, help=f"samples per pixel (default {DEFAULTS.spp})"
    )
    parser.add_argument(
        "--repeat",
        type=int,
        default=DEFAULTS.repeat,
        help=f"rounds, each with its own seed (default {DEFAULTS.repeat})",
    )
    parser.add_argument(
        "--seed", type=int, default=DEFAULTS.seed, help=f"the first round's seed (default {DEFAULTS.seed})"
    )
    parser.add_argument(
        "--samplers",
        default=",".join(DEFAULTS.samplers),
        help=f"Mitsuba's samplers, of {', '.join(MITSUBA_SAMPLERS)} (default all)",
    )
    depths = ",".join(map(str, DEFAULTS.rr_depths))
    parser.add_argument(
        "--rr-depth",
        default=depths,
        help=f"Mitsuba's Russian roulette depths (default {depths}: Mitsuba's "
        "default, the one that matches ptlab's default, and 2)",
    )
    parser.add_argument(
        "--ptlab-samplers",
        default=",".join(DEFAULTS.ptlab_samplers),
        help=f"ptlab's samplers (default {','.join(DEFAULTS.ptlab_samplers)})",
    )
    parser.add_argument(
        "--ptlab-target-error",
        type=float,
        metavar="E",
        help="also time the whole process 'ptlab render --target-error E' (e.g. the relMSE "
        "of Mitsuba's multijitter render at --spp, from a first run: the time ptlab needs "
        "to reach its error)",
    )
    parser.add_argument(
        "--target-from-mitsuba-spp",
        type=int,
        metavar="N",
        help="time the whole process 'ptlab render --target-error E_m', E_m the true relMSE of "
        "Mitsuba's whole process at N spp (the median of --repeat renders made first, with seeds "
        "of their own), and compare every process's seconds x relMSE with Mitsuba's at N spp",
    )
    parser.add_argument(
        "--denoise",
        action="store_true",
        help="denoise ptlab's renders (ptlab render --denoise; the denoise extra), and race "
        "Mitsuba denoised by the same Intel Open Image Denoise as whole processes, at --spp "
        "and at --mitsuba-denoise-spp",
    )
    parser.add_argument(
        "--mitsuba-denoise-spp",
        type=int,
        metavar="N",
        default=DEFAULTS.mitsuba_denoise_spp,
        help="with --denoise, the spp of the Mitsuba + OIDN process that every process's seconds "
        f"x relMSE is compared with (default {DEFAULTS.mitsuba_denoise_spp})",
    )
    parser.add_argument(
        "--process-sampler",
        choices=MITSUBA_SAMPLERS,
        default=DEFAULTS.process_sampler,
        help=f"Mitsuba's sampler in its whole processes (default {DEFAULTS.process_sampler}, "
        "its scene file's)",
    )
    parser.add_argument(
        "--ptlab-strategy",
        choices=STRATEGIES,
        default=DEFAULTS.ptlab_strategy,
        help="ptlab's path tracer: light sampling (nee, its default) or MIS (mis, as Mitsuba's path tracer)",
    )
    parser.add_argument(
        "--workers",
        type=int,
        help="ptlab's worker processes (default one per core); Mitsuba uses Dr.Jit's default thread count",
    )
    parser.add_argument(
        "--variant",
        default=DEFAULTS.variant,
        help=f"Mitsuba's variant, an RGB one (default {DEFAULTS.variant})",
    )
    parser.add_argument(
        "--reference",
        metavar="FILE.exr",
        help="the reference, a linear EXR of the same resolution "
        "(default: a Mitsuba render of --reference-spp samples, cached)",
    )
    parser.add_argument(
        "--reference-spp",
        type=int,
        default=DEFAULTS.reference_spp,
        help=f"samples per pixel of the Mitsuba reference (default {DEFAULTS.reference_spp})",
    )
    parser.add_argument(
        "--ptlab-reference", metavar="FILE.exr", help="a high-spp ptlab render to check against the reference"
    )
    parser.add_argument(
        "--ptlab-reference-spp",
        type=int,
        help="its samples per pixel, for the noise estimate (default: from its metadata)",
    )
    parser.add_argument(
        "--no-process", action="store_true", help="skip the whole-process runs of ptlab render and mitsuba"
    )
    parser.add_argument(
        "--processes-only",
        action="store_true",
        help="time the whole processes only, not the renders in this process",
    )
    parser.add_argument(
        "--csv", metavar="FILE", help="also write every run (label, round, seed, seconds, errors)"
    )
    return parser


def _names(text: str, allowed: tuple[str, ...], option: str) -> tuple[str, ...]:
    """The comma-separated names in ``text``, each once, all of them ``allowed``."""
    names = [name.strip() for name in text.split(",") if name.strip()]
    wrong = [name for name in names if name not in allowed]
    if wrong or not names:
        raise PtlabError(f"{option} {text!r}: give a comma-separated list of {', '.join(allowed)}")
    return tuple(dict.fromkeys(names))


def _depths(text: str) -> tuple[int, ...]:
    """The comma-separated non-negative integers in ``text``, each once."""
    try:
        depths = [int(part) for part in text.split(",")]
    except ValueError:
        depths = []
    if not depths or min(depths) < 0:
        raise PtlabError(f"--rr-depth {text!r}: give non-negative integers, e.g. 5,3")
    return tuple(dict.fromkeys(depths))


def options_from(args: argparse.Namespace) -> ComparisonOptions:
    """The parsed command line as ``ComparisonOptions``; ``PtlabError`` for a list or a
    resolution that does not parse."""
    return ComparisonOptions(
        scene=args.scene,
        samplers=_names(args.samplers, MITSUBA_SAMPLERS, "--samplers"),
        ptlab_samplers=_names(args.ptlab_samplers, SAMPLERS, "--ptlab-samplers"),
        rr_depths=_depths(args.rr_depth),
        res=parse_resolution(args.res),
        spp=args.spp,
        repeat=args.repeat,
        seed=args.seed,
        ptlab_target_error=args.ptlab_target_error,
        target_from_mitsuba_spp=args.target_from_mitsuba_spp,
        denoise=args.denoise,
        mitsuba_denoise_spp=args.mitsuba_denoise_spp,
        process_sampler=args.process_sampler,
        ptlab_strategy=args.ptlab_strategy,
        workers=args.workers,
        variant=args.variant,
        reference=args.reference,
        reference_spp=args.reference_spp,
        ptlab_reference=args.ptlab_reference,
        ptlab_reference_spp=args.ptlab_reference_spp,
        time_processes=not args.no_process,
        in_process=not args.processes_only,
        csv=args.csv,
    )


def main(argv: list[str] | None = None) -> int:
    """Run the comparison; the exit code (see the module's docstring)."""
    args = build_parser().parse_args(argv)
    try:
        agree = compare(options_from(args), lambda line: print(line, flush=True))
    except PtlabError as error:
        print(f"{PROG}: error: {error}", file=sys.stderr)
        return 2
    except RenderError as error:
        print(f"{PROG}: error: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
    return 0 if agree else 1


if __name__ == "__main__":
    sys.exit(main())
