"""Mitsuba 3 denoised by Intel Open Image Denoise, as a program of its own: the contender that
``against_mitsuba`` times from start to exit beside ``ptlab render --denoise``.

    python -m ptlab.measure.mitsuba_denoised SCENE.xml OUT.exr --spp 16 --seed 0

What a Mitsuba user does to denoise: Mitsuba's ``aov`` integrator (Mitsuba 3 documentation,
plugin reference, integrators, ``aov``) renders the ``albedo`` and the shading
normal (``sh_normal``) of the first surface each camera ray hits, OIDN's two auxiliary images
(OIDN's documentation, "RT" filter). Noisy, like ptlab's, they are prefiltered
(``ptlab.denoise.oidn.denoise_colour``), with the same OIDN and settings as ptlab's renders.
Unlike ``ptlab render --denoise``, the lights seen directly are denoised with the rest:
Mitsuba's film has no image of them apart.

The colour and the features are two renders with the same sampler, seed and spp, so the same
camera rays: the same pixels as the scene's integrator nested in the ``aov`` one gives (bit
for bit, with Mitsuba 3.9), in less time: nested, the render took twice the path tracer's
time, while the ``aov`` pass alone, one ray per sample, costs a few percent of it.

The scene file is one that ``mitsuba_export`` wrote (it takes ``$spp``, ``$seed``, ``$sampler``
and ``$rr_depth``). With ``--aov`` the EXR also holds the inputs, as layers beside R, G, B
(``ptlab render --aov``'s names): ``noisy.R/G/B``, ``albedo.R/G/B`` and ``normal.X/Y/Z``.
Exit codes: 0 written, 2 a bad option or a Mitsuba that cannot be imported, in one line.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from types import ModuleType
from typing import NoReturn

import numpy as np

from ptlab.errors import PtlabError
from ptlab.measure.mitsuba_export import MITSUBA_RR_DEPTH, SCENE_XML

#: Mitsuba's ``aov`` integrator's list: "name:kind" pairs, in the order of its film's channels.
AOVS = "albedo:albedo,normal:sh_normal"


def render_denoised(
    scene_xml: Path,
    spp: int,
    seed: int,
    variant: str,
    sampler: str = "independent",
    rr_depth: int = MITSUBA_RR_DEPTH,
) -> dict[str, np.ndarray]:
    """Render ``scene_xml`` with Mitsuba at ``spp`` samples per pixel and denoise it.

    Returns (H, W, 3) float32 images: ``"image"`` (denoised), ``"noisy"`` (Mitsuba's colour),
    ``"albedo"`` and ``"normal"`` (the aov integrator's, as given to the denoiser).
    Raises ``PtlabError`` (one line) if Mitsuba is missing or lacks ``variant``.
    """
    from ptlab.denoise.oidn import denoise_colour

    mi = _mitsuba(variant)
    scene = mi.load_file(str(scene_xml), spp=spp, seed=seed, sampler=sampler, rr_depth=rr_depth)
    colour = np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float32)
    aov = mi.load_dict({"type": "aov", "aovs": AOVS})
    features = np.array(mi.render(scene, integrator=aov, spp=spp, seed=seed), dtype=np.float32)
    if colour.shape[-1] != 3 or features.shape != (*colour.shape[:-1], 6):
        raise PtlabError(
            f"{scene_xml}: Mitsuba's films are {colour.shape} and {features.shape}, not RGB and {AOVS}"
        )
    # (a box filter has no negative lobe; a scene file with another filter could, and OIDN's
    # HDR colour must not be negative)
    noisy = np.maximum(colour, 0.0)
    albedo, normal = np.clip(features[..., 0:3], 0.0, 1.0), features[..., 3:6]
    image = denoise_colour(noisy, albedo, normal, features="prefilter")
    return {"image": image, "noisy": noisy, "albedo": albedo, "normal": normal}


def _mitsuba(variant: str) -> ModuleType:
    """``mitsuba`` with ``variant`` set, or ``PtlabError``."""
    try:
        import mitsuba as mi
    except ImportError as error:
        raise PtlabError(f"cannot import mitsuba ({error}): pip install mitsuba") from None
    if variant not in mi.variants():
        raise PtlabError(
            f"mitsuba {mi.__version__} has no variant {variant!r} (it has {', '.join(mi.variants())})"
        )
    mi.set_variant(variant)
    return mi


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (and still exit code 2)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    """The program's options."""
    parser = _Parser(prog="python -m ptlab.measure.mitsuba_denoised", description=__doc__.split("\n")[0])
    parser.add_argument(
        "scene_xml", type=Path, help=f"a Mitsuba scene file from mitsuba_export ({SCENE_XML})"
    )
    parser.add_argument("out", type=Path, help="the EXR to write")
    parser.add_argument("--spp", type=int, required=True, help="samples per pixel")
    parser.add_argument("--seed", type=int, default=0, help="Mitsuba's sampler seed (default 0)")
    parser.add_argument(
        "--variant", default="llvm_ad_rgb", help="Mitsuba's variant, an RGB one (default llvm_ad_rgb)"
    )
    parser.add_argument("--sampler", default="independent", help="Mitsuba's sampler (default independent)")
    parser.add_argument(
        "--rr-depth",
        type=int,
        default=MITSUBA_RR_DEPTH,
        help=f"Russian roulette depth (default {MITSUBA_RR_DEPTH})",
    )
    parser.add_argument("--aov", action="store_true", help="also write the denoiser's inputs as layers")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Render, denoise and write; the exit code (the module's docstring)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    start = time.perf_counter()
    try:
        if args.spp < 1:
            raise PtlabError(f"--spp {args.spp}: must be at least 1")
        if "_rgb" not in args.variant:
            raise PtlabError(f"--variant {args.variant}: use an RGB variant such as llvm_ad_rgb")
        if not args.scene_xml.is_file():
            raise PtlabError(f"{args.scene_xml}: no such scene file")
        if args.out.suffix.lower() != ".exr":
            raise PtlabError(f"{args.out}: the output is an .exr file")
        images = render_denoised(
            args.scene_xml, args.spp, args.seed, args.variant, args.sampler, args.rr_depth
        )
        _write(args, images, time.perf_counter() - start)
    except PtlabError as error:
        print(f"{parser.prog}: error: {error}", file=sys.stderr)
        return 2
    return 0


def _write(args: argparse.Namespace, images: dict[str, np.ndarray], seconds: float) -> None:
    """The denoised image, its header (what rendered and denoised it), and with ``--aov`` the
    denoiser's inputs."""
    import mitsuba as mi

    from ptlab.denoise.oidn import oidn_version
    from ptlab.image import write_image

    metadata = dict(
        renderer=f"mitsuba {mi.__version__}",
        variant=args.variant,
        sampler=args.sampler,
        spp=args.spp,
        seed=args.seed,
        denoised=f"Intel Open Image Denoise {oidn_version()}",
        seconds=round(seconds, 3),
    )
    layers = {name: images[name] for name in ("noisy", "albedo", "normal")} if args.aov else None
    write_image(args.out, images["image"], metadata, layers=layers)


if __name__ == "__main__":
    sys.exit(main())
