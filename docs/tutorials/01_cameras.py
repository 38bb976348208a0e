# %% [markdown]
# # Chapter 1 tutorial: what a pinhole camera sees
#
# A pinhole camera sits at the eye and looks along the unit vector `forward`. Put an image
# plane at distance 1 in front of the eye: with a vertical field of view `fov_y`, it spans
# `tan(fov_y / 2)` above and below its centre, and the aspect ratio times that to the left
# and right. A pixel's ray goes from the eye through its point on that plane. Chapter 1's
# exercise is `generate_rays`, which makes those rays for a whole batch of pixels at once
# (the chapter's page: `ptlab exercise docs 1`).
#
# This tutorial looks at the Cornell box's camera, shoots a ray through the middle of the
# image, then renders the box's surface normals through the library's `generate_rays` and
# through a camera that gets its rows upside down, the chapter's typical mistake.

# %%
"""Chapter 1 tutorial: what a pinhole camera sees.

As a script (in a notebook, the options come from PTLAB_TUTORIAL_ARGS):

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

args, out = tutorial_options(__doc__, res=256, spp=4)

# %% [markdown]
# ## The camera
#
# The scene file gives the eye's position, the direction it looks in and the vertical field
# of view in degrees; `tan(fov_y / 2)` is how far the image plane reaches above its centre.

# %%
scene = ptlab.load_scene("cornell-box")
camera = scene.camera
print(f"eye {camera.position}, forward {camera.forward}, fov_y {camera.fov_y} degrees")
print(
    f"the image plane spans tan(fov_y / 2) = {math.tan(math.radians(camera.fov_y) / 2):.3f} "
    f"above and below the centre, at distance 1"
)

# %% [markdown]
# `generate_rays(camera, width, height, pixel_x, pixel_y, u)` takes arrays: the column and
# the row of every ray's pixel, and for each ray two numbers `u` in [0, 1) that place it
# inside its pixel (a random `u` per sample is what antialiases edges). Column and row
# `res // 2` with `u = (0, 0)` is the corner at the very middle of the image, so its ray
# goes straight along `forward`.

# %%
_, centre = generate_rays(
    camera,
    args.res,
    args.res,
    np.array([args.res // 2]),
    np.array([args.res // 2]),
    np.zeros((1, 2), np.float32),
)
print(f"ray through the centre pixel's corner: {np.round(centre[0], 4)}")


# %% [markdown]
# ## Rows go down, y goes up
#
# Pixel row 0 is the *top* of the image, while `y` on the image plane grows upward; the
# chapter's typical mistake takes the rows as going up, like `y`. Here it is, written as the
# library's rays for the mirrored row.


# %%
def upside_down_rays(camera, width, height, pixel_x, pixel_y, u):
    """The classic mistake: pixel rows taken as going up, like y."""
    return generate_rays(camera, width, height, pixel_x, height - 1 - pixel_y, u)


# %% [markdown]
# ## The two pictures
#
# The `normals` integrator colours each camera ray's first hit by its surface normal (x red,
# y green, z blue): the floor, whose normal points up, is pale green. A render is made of
# pieces, the library's unless told otherwise; `Pieces(generate_rays=...)` hands it another
# camera's rays. Both renders run in this process (`workers=1`): the wrong camera is this
# file's function, which worker processes may not have. In the second picture the floor
# is at the top.

# %%
options = dict(spp=args.spp, res=args.res, integrator="normals", workers=1)
write_image(out / "cameras.png", ptlab.render(scene, **options))
upside_down = Pieces(generate_rays=upside_down_rays)
write_image(out / "cameras-wrong.png", ptlab.render(scene, **options, pieces=upside_down))
print(f"wrote {out / 'cameras.png'} and {out / 'cameras-wrong.png'}")
show_pictures(out)
