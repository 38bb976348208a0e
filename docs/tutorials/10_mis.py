# %%
"""Chapter 10 tutorial: multiple importance sampling on Veach's scene.

Prints the two strategies' MIS weights for a few pairs of densities, then renders
``veach-mis`` (four glossy plates, from smooth at the top to rough at the bottom, lit by
four lights of equal power, small on the left, big on the right) with light sampling only,
BSDF sampling only, MIS with the power heuristic (all the library's), and with the chapter's
typical mistake: both strategies weighted 1, which counts light twice.

    python docs/tutorials/10_mis.py              # mis-nee.png, mis-bsdf.png, mis.png, mis-wrong.png
    python docs/tutorials/10_mis.py --res 64 --spp 4 --out /tmp/t
"""

from __future__ import annotations

import numpy as np

import ptlab
from ptlab.course.tutorial import show_pictures, tutorial_options
from ptlab.image import write_image
from ptlab.integrators.path import mis_weight
from ptlab.rendering.pieces import PathPieces, Pieces


def weight_one(pdf, other, heuristic="power"):
    """The classic mistake: every sample of both strategies counted fully."""
    return np.ones_like(pdf)


# %%
def main() -> None:
    args, out = tutorial_options(__doc__, res=128, spp=32)

    pdf_light = np.array([0.1, 1.0, 5.0, 400.0], dtype=np.float32)
    pdf_bsdf = np.array([40.0, 1.0, 1.0, 2.0], dtype=np.float32)
    print("  pdf_light  pdf_bsdf   power: w_light  w_bsdf   balance: w_light  w_bsdf")
    for light, bsdf, *w in zip(
        pdf_light,
        pdf_bsdf,
        mis_weight(pdf_light, pdf_bsdf),
        mis_weight(pdf_bsdf, pdf_light),
        mis_weight(pdf_light, pdf_bsdf, "balance"),
        mis_weight(pdf_bsdf, pdf_light, "balance"),
        strict=True,
    ):
        print(f"  {light:9g} {bsdf:9g}   {w[0]:13.4f} {w[1]:7.4f}   {w[2]:15.4f} {w[3]:7.4f}")
    print("each pair of weights adds up to 1: every light path is counted once in all")

    scene = ptlab.load_scene("veach-mis")
    options = dict(spp=args.spp, res=args.res, seed=0)
    for strategy, name in (("nee", "mis-nee.png"), ("bsdf", "mis-bsdf.png"), ("mis", "mis.png")):
        result = ptlab.render_result(scene, strategy=strategy, **options)
        write_image(out / name, result.image)
        print(
            f"wrote {out / name}: strategy {strategy!r}, {result.seconds:.1f} s, "
            f"mean brightness {result.image.mean():.4f}"
        )
    # The MIS weight is one of the path tracer's pieces; a render in this process (workers=1)
    # can be given this script's own.
    weights_of_one = Pieces(path=PathPieces(mis_weight=weight_one))
    image = ptlab.render(scene, strategy="mis", workers=1, **options, pieces=weights_of_one)
    write_image(out / "mis-wrong.png", image)
    print(
        f"wrote {out / 'mis-wrong.png'}: both strategies weighted 1, mean brightness "
        f"{image.mean():.4f} (too bright: double counting)"
    )
    show_pictures(out)


# %%
if __name__ == "__main__":
    main()
