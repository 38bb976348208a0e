# %%
"""Chapter 1 tutorial: what a pinhole camera sees.

Renders the Cornell box's surface normals (each ray's first hit, coloured by the normal's
direction) through the library's ``generate_rays``, and the same picture through a camera
that gets its rows upside down, the chapter's typical mistake.

    python docs/tutorials/01_cameras.py                 # writes cameras.png, cameras-wrong.png
    python docs/tutorials/01_cameras.py --res 64 --out /tmp/t
"""

from __future__ import annotations

import math

import numpy as np

import ptlab
from ptlab.camera import generate_rays
from ptlab.course.tutorial import show_pictures, tutorial_options
from ptlab.image import write_image
from ptlab.rendering.pieces import Pieces


def upside_down_rays(camera, width, height, pixel_x, pixel_y, u):
    """The classic mistake: pixel rows taken as going up, like y."""
    return generate_rays(camera, width, height, pixel_x, height - 1 - pixel_y, u)


# %%
def main() -> None:
    args, out = tutorial_options(__doc__, res=256, spp=4)

    scene = ptlab.load_scene("cornell-box")
    camera = scene.camera
    print(f"eye {camera.position}, forward {camera.forward}, fov_y {camera.fov_y} degrees")
    print(
        f"the image plane spans tan(fov_y / 2) = {math.tan(math.radians(camera.fov_y) / 2):.3f} "
        f"above and below the centre, at distance 1"
    )

    # One ray through the centre of the image goes straight along forward.
    _, centre = generate_rays(
        camera,
        args.res,
        args.res,
        np.array([args.res // 2]),
        np.array([args.res // 2]),
        np.zeros((1, 2), np.float32),
    )
    print(f"ray through the centre pixel's corner: {np.round(centre[0], 4)}")

    options = dict(spp=args.spp, res=args.res, integrator="normals", workers=1)
    write_image(out / "cameras.png", ptlab.render(scene, **options))
    # A render is made of pieces (the library's by default): give it the wrong camera's rays.
    upside_down = Pieces(generate_rays=upside_down_rays)
    write_image(out / "cameras-wrong.png", ptlab.render(scene, **options, pieces=upside_down))
    print(f"wrote {out / 'cameras.png'} and {out / 'cameras-wrong.png'}")
    show_pictures(out)


# %%
if __name__ == "__main__":
    main()
