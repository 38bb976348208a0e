# %% [markdown]
# # What a denoiser buys and what it costs
#
# A path-traced image at a few samples per pixel is noisy; the renderers used in production
# hand it to a denoiser, a neural network that guesses the clean image. ptlab uses the one
# most CPU renderers use, Intel Open Image Denoise (OIDN): `render_result(scene, ...,
# denoise=True)` returns the denoised `image`, the `noisy` one it started from, and the
# `features` the network was guided by (each pixel's albedo and normal, and the light seen
# directly, which is kept out of the denoiser). This notebook measures what that buys on the
# Cornell box, at what cost in time, and where it goes wrong; the page is
# `docs/denoising.md`.

# %%
"""What a denoiser buys and what it costs: Intel Open Image Denoise on ptlab's renders.

Renders the Cornell box at 1, 4, 16 and 64 spp (powers of 4 up to ``--spp``), plain and
denoised, and measures each against a reference, the denoiser's time counted; then the
scenes where the denoiser fails: the small bright lights of ``veach-mis`` (denoised with the
light seen directly kept out, and not), and the glass sphere and checkerboard of
``games101-hw5``; and beside each denoised image's true error, what the render estimates
it to be.

    python docs/tutorials/denoising.py    # denoising-cornell-box.png, denoising-error-time.png,
                                          # denoising-veach-mis.png, denoising-games101-hw5.png
    python docs/tutorials/denoising.py --res 64 --spp 16 --out /tmp/t
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import ptlab
from ptlab.course.tutorial import show_pictures, tutorial_options
from ptlab.denoise.oidn import denoise_colour
from ptlab.image import encode_srgb8
from ptlab.measure.charts import convergence_chart
from ptlab.measure.converge import Measurement, default_cache_dir, reference_image, time_to_reach
from ptlab.measure.metrics import RELMSE_EPSILON, relative_squared_error, relmse, rmse
from ptlab.rendering.api import RenderResult

#: The seed of every render measured here (the references have their own).
SEED = 0

# %% [markdown]
# ## The true error, when the reference is noisy too
#
# The error of an image is measured against a reference, a render with many more samples.
# The reference has noise of its own, which the usual relMSE, the mean of
# (I - R)^2 / (R + 0.01)^2, adds to every figure (the tutorial prints how much: on the
# Cornell box at 128x128, about as much as a denoised 64-spp image's own error). So we
# render **two** independent references A and B and average (I - A)(I - B) instead: their
# noises are independent of each other and of the image, so they average out of the
# product, whose mean is the true squared error.


# %%
def references(scene, size: tuple[int, int], spp: int) -> tuple[np.ndarray, np.ndarray]:
    """Two independent ``spp``-sample renders of ``scene`` (``path:mis``, seeds 0 and 1),
    each (H, W, 3), cached on disk (``ptlab.measure.converge.reference_image``)."""
    a, b = (reference_image(scene, size, spp, seed, default_cache_dir(), quiet=True) for seed in (0, 1))
    return a, b


def true_error_map(image: np.ndarray, refs: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """(H, W) each pixel's relative squared error as (I - A)(I - B) / (R + 0.01)^2, R the
    references' mean: an unbiased estimate of (I - truth)^2 / (R + 0.01)^2 (one pixel's may
    be negative; their mean is the image's true relMSE)."""
    a, b = refs
    image = np.asarray(image, np.float64)
    return ((image - a) * (image - b) / ((a + b) / 2 + RELMSE_EPSILON) ** 2).mean(axis=-1)


def true_relmse(image: np.ndarray, refs: tuple[np.ndarray, np.ndarray]) -> float:
    """The image's relMSE against the true image (``true_error_map``'s mean)."""
    return float(true_error_map(image, refs).mean())


def estimate_says(result: RenderResult, true: float) -> str:
    """What the denoised render says of its own error, beside the true error."""
    if result.relmse_estimate is None:
        said = f"refused: {result.estimate_refused}"
        bound = result.settings.get("relmse_bound")  # (what the error is below, where known)
        if bound is not None:
            said += f"; below {bound:.4f}, which " + ("holds" if true <= bound else "does not hold")
        return said
    estimate = result.relmse_estimate
    if true <= 0:  # (the true error's estimate can be 0 or below where it is tiny)
        return f"{estimate:.4f}"
    return f"{estimate:.4f} ({estimate / true:.2f}x the true error)"


# %% [markdown]
# ## Pictures side by side
#
# Each picture is a grid of panels (8-bit sRGB, as PNGs show them) with thin white gaps; a
# crop is given as fractions of the image's height and width, magnified (each pixel drawn
# as a square) to about ``width`` pixels, so that the noise shows.


# %%
def panel(image: np.ndarray, crop: tuple = ((0.0, 1.0), (0.0, 1.0)), width: int = 0) -> np.ndarray:
    """(h, w, 3) uint8: ``crop`` (rows, columns) of the linear (H, W, 3) image in sRGB (or of
    a uint8 picture as it is), magnified to about ``width`` pixels (0: as it is)."""
    (top, bottom), (left, right) = crop
    height, image_width = image.shape[:2]
    part = image[int(top * height) : int(bottom * height), int(left * image_width) : int(right * image_width)]
    encoded = part if part.dtype == np.uint8 else encode_srgb8(part)
    zoom = max(1, round(width / encoded.shape[1]))
    return encoded.repeat(zoom, axis=0).repeat(zoom, axis=1)


def heat(values: np.ndarray, top: float) -> np.ndarray:
    """(H, W, 3) uint8: ``values`` from 0 to ``top`` as colours (matplotlib's inferno)."""
    import matplotlib

    colours = matplotlib.colormaps["inferno"](np.clip(values / top, 0.0, 1.0))
    return np.round(colours[..., :3] * 255).astype(np.uint8)


def write_grid(path: Path, rows: list[list[np.ndarray]], gap: int = 2) -> None:
    """Write the panels (rows of uint8 (h, w, 3), all of one size) as one RGB PNG."""
    from PIL import Image

    def joined(parts: list[np.ndarray], axis: int) -> np.ndarray:
        white = np.full_like(parts[0].take(range(gap), axis=axis), 255)
        return np.concatenate([p for part in parts for p in (white, part)][1:], axis=axis)

    Image.fromarray(joined([joined(row, axis=1) for row in rows], axis=0)).save(path, optimize=True)
    print(f"wrote {path}")


# %% [markdown]
# ## What it buys: the Cornell box at 1, 4, 16 and 64 spp
#
# Each spp is rendered plain and with `denoise=True`, alternately, three times (the same
# seed gives the same image each time: the repeats only time it; the median is kept). A
# denoised render's time is all of it: the feature images gathered in the camera bounce,
# each pixel's samples kept in two halves (for the error estimate), and OIDN itself, which
# runs once, in the main process, after the last pass (`settings["denoise_seconds"]`).
# The chart puts both lines on the axes of `ptlab converge`, error against time; the same
# comparison at any size is `ptlab converge cornell-box --integrators path:nee,path:nee+denoise`.

# %%
#: How many times each render is timed (alternately plain and denoised; the median is kept).
REPEATS = 3
#: Where the Cornell box's side-by-side picture looks: the red wall, the tall box's foot and
#: its shadow (rows, columns, as fractions of the image).
CORNELL_CROP = ((0.45, 0.95), (0.05, 0.55))


def ladder(scene, res: int, spps: list[int], refs) -> tuple[list[Measurement], list[Measurement], dict]:
    """The plain and the denoised renders at each of ``spps``, as ``Measurement`` s (the
    median time, the error against the true image), and the denoised results by spp."""
    reference = (refs[0] + refs[1]) / 2
    # (OIDN makes its device and filters once per process: not inside the first rung's time.)
    denoise_colour(np.zeros((8, 8, 3), np.float32))
    plain: list[Measurement] = []
    denoised: list[Measurement] = []
    results: dict[tuple[int, bool], RenderResult] = {}
    for spp in spps:
        seconds: dict[bool, list[float]] = {False: [], True: []}
        for _ in range(REPEATS):
            for denoise in (False, True):
                result = ptlab.render_result(scene, spp=spp, res=res, seed=SEED, denoise=denoise)
                seconds[denoise].append(result.seconds)
                results[spp, denoise] = result
        for denoise, line, label in ((False, plain, "path:nee"), (True, denoised, "path:nee+denoise")):
            image = results[spp, denoise].image
            error = true_relmse(image, refs)
            line.append(
                Measurement(
                    label, spp, float(np.median(seconds[denoise])), rmse(image, reference), error, image
                )
            )
    return plain, denoised, {spp: results[spp, True] for spp in spps}


def cornell_box(out: Path, res: int, most_spp: int, reference_spp: int) -> list[tuple[str, int, float, str]]:
    """The ladder's table, ``denoising-error-time.png`` and ``denoising-cornell-box.png``
    (noisy, denoised, reference at each spp); returns its rows for the estimates' table
    (scene, spp, true relMSE of the denoised image, what its estimate says)."""
    scene = ptlab.load_scene("cornell-box")
    refs = references(scene, (res, res), reference_spp)
    print(f"the references' own relMSE, which one reference of {2 * reference_spp} spp would add to")
    print(f"every figure below: {relmse(refs[0], refs[1]) / 4:.5f}")
    spps = [4**k for k in range(8) if 4**k <= most_spp]
    plain, denoised, results = ladder(scene, res, spps, refs)

    print(
        f"Cornell box, {res}x{res}: relMSE against the true image; median seconds of {REPEATS}, all included"
    )
    print("  spp   plain: s   relMSE   denoised: s   of it OIDN   relMSE   plain renders reach it in")
    for noisy, clean in zip(plain, denoised, strict=True):
        reached = time_to_reach(plain, clean.relmse)
        need = "(beyond the ladder)" if reached is None else f"{reached[0]:.2f} s"
        if reached is not None and reached[1]:
            need += " (extrapolated, slope -1)"
        oidn = results[clean.spp].settings["denoise_seconds"]
        print(
            f"  {noisy.spp:3d}   {noisy.seconds:8.2f}   {noisy.relmse:6.4f}   {clean.seconds:11.2f}"
            f"   {oidn:10.2f}   {clean.relmse:6.4f}   {need}"
        )
    chart = out / "denoising-error-time.png"
    convergence_chart([plain, denoised], chart, f"Cornell box, {res}x{res}: plain and denoised")
    print(f"wrote {chart}")

    reference = (refs[0] + refs[1]) / 2
    write_grid(
        out / "denoising-cornell-box.png",
        [
            [panel(image, CORNELL_CROP, 128) for image in (results[spp].noisy, results[spp].image, reference)]
            for spp in spps
        ],
    )
    print(f"  (rows: {', '.join(map(str, spps))} spp; columns: noisy, denoised, reference)")
    return [("cornell-box", m.spp, m.relmse, estimate_says(results[m.spp], m.relmse)) for m in denoised]


# %% [markdown]
# ## Where it fails (1): small, very bright lights
#
# `veach-mis`'s lights are small spheres of radiance up to 900 beside plates that reflect
# them and a backdrop a thousand times darker. The network has learnt that a lone pixel far
# brighter than its neighbours is noise, and spreads it over them: a halo of light in pixels
# that should be dark, an error far larger than the noise it removed. Renderers that denoise
# keep the light seen directly (by the camera, or through mirrors and glass) out of the
# denoiser and add it back; ptlab's `features["direct"]` is that light, which
# `render_result(..., denoise=True)` keeps out in the same way as the second of these calls.


# %%
def small_lights(out: Path, res: int, spp: int, reference_spp: int) -> list[tuple[str, int, float, str]]:
    """``veach-mis`` denoised with everything through OIDN and with the direct light kept
    out; ``denoising-veach-mis.png`` (noisy, everything, direct kept out, reference)."""
    scene = ptlab.load_scene("veach-mis")
    result = ptlab.render_result(scene, spp=spp, res=res, seed=SEED, strategy="mis", denoise=True)
    refs = references(scene, (res, res), reference_spp)
    albedo, normal, direct = (result.features[name] for name in ("albedo", "normal", "direct"))
    everything = denoise_colour(result.noisy, albedo, normal)
    # (max: the direct light is a part of each pixel's samples, but float32 rounding may leave -1e-7)
    kept_out = denoise_colour(np.maximum(result.noisy - direct, 0.0), albedo, normal) + direct

    print(f"veach-mis (strategy mis), {res}x{res}, {spp} spp: relMSE against the true image")
    print("                                     relMSE   share of it in the worst 1% of pixels")
    for label, image in (
        ("noisy", result.noisy),
        ("denoised, direct light in", everything),
        ("denoised, direct light kept out", kept_out),
    ):
        errors = np.sort(true_error_map(image, refs).ravel())[::-1]
        worst = errors[: max(1, errors.size // 100)].sum() / errors.sum()
        print(f"  {label:33s} {errors.mean():8.4f}   {worst:6.1%}")
    write_grid(
        out / "denoising-veach-mis.png",
        [[panel(result.noisy), panel(everything), panel(kept_out), panel((refs[0] + refs[1]) / 2)]],
    )
    print("  (noisy; denoised with the direct light in; with it kept out; reference)")
    true = true_relmse(result.image, refs)
    return [("veach-mis", spp, true, estimate_says(result, true))]


# %% [markdown]
# ## Where it fails (2): light through glass, and the checkerboard's edges
#
# `games101-hw5` has a glass sphere over a checkerboard. What the camera sees *through* the
# sphere is noisy: at each of the glass's surfaces a path chooses at random between
# reflection and refraction, and sees the floor or the sky. The features there, taken at the
# first surface after the glass, are an average of those that tells the network little.
# (The floor in the sphere's shadow gets the sky's light through the glass, a caustic that
# only a bounce that happens to head into the sphere finds; here it is faint. The point
# lights' caustic is in no image at all: no path from the camera can find a point light
# through glass.) The checkerboard is the opposite case: its edges are in the albedo image,
# which tells the network where not to blur; but the albedo comes from the same few samples
# as the colour, so where an edge crosses a pixel both carry the same error in how much of
# the pixel each square covers, and the network, trusting the albedo, keeps it. The edges
# are found in the albedo image, where it changes from one pixel to the next; the error is
# compared there and on the rest of the surfaces (the sky, kept out of the denoiser, is
# left out). The homework's scene is small in its frame: it is rendered at twice `--res`,
# 4:3 as the homework's image.


# %%
#: Where the picture of games101-hw5 looks: the spheres and the floor under them.
HW5_CROP = ((0.36, 0.78), (0.28, 0.72))


def albedo_edges(albedo: np.ndarray, step: float = 0.1) -> np.ndarray:
    """(H, W) bool: the pixels whose albedo differs from a neighbour's (left, right, above or
    below) by more than ``step`` in a channel."""
    across = np.abs(np.diff(albedo, axis=1)).max(axis=-1) > step
    down = np.abs(np.diff(albedo, axis=0)).max(axis=-1) > step
    edges = np.zeros(albedo.shape[:2], dtype=bool)
    edges[:, 1:] |= across
    edges[:, :-1] |= across
    edges[1:] |= down
    edges[:-1] |= down
    return edges


def glass_and_edges(out: Path, res: int, spp: int, reference_spp: int) -> list[tuple[str, int, float, str]]:
    """``games101-hw5`` noisy and denoised, and its error on the edges and elsewhere;
    ``denoising-games101-hw5.png``: the middle of the picture, noisy, denoised and reference
    above, and below the relative error of the first two (one colour scale) and the edges."""
    scene = ptlab.load_scene("games101-hw5")
    size = (2 * res, 2 * res * 3 // 4)
    result = ptlab.render_result(scene, spp=spp, res=size, seed=SEED, denoise=True)
    refs = references(scene, size, reference_spp)
    albedo = result.features["albedo"]
    edges = albedo_edges(albedo)
    surfaces = albedo.max(axis=-1) > 0  # (0: the path escaped to the sky, through glass or not)

    errors = [true_error_map(image, refs) for image in (result.noisy, result.image)]
    print(f"games101-hw5, {size[0]}x{size[1]}, {spp} spp: relMSE against the true image")
    print("                                          noisy   denoised")
    for region, where in (
        ("the whole image", np.ones_like(edges)),
        (f"the edges ({edges.mean():.1%} of the pixels)", edges),
        (f"the other surfaces ({(surfaces & ~edges).mean():.1%})", surfaces & ~edges),
    ):
        print(f"  {region:36s} {errors[0][where].mean():7.4f}   {errors[1][where].mean():8.5f}")

    reference = (refs[0] + refs[1]) / 2
    relative = [np.sqrt(relative_squared_error(image, reference)) for image in (result.noisy, result.image)]
    top = float(np.quantile(relative[0], 0.99)) or 1.0
    edge_picture = np.repeat(edges[..., None] * np.uint8(255), 3, axis=-1)
    write_grid(
        out / "denoising-games101-hw5.png",
        [
            [panel(image, HW5_CROP, 224) for image in (result.noisy, result.image, reference)],
            [panel(heat(error, top), HW5_CROP, 224) for error in relative]
            + [panel(edge_picture, HW5_CROP, 224)],
        ],
    )
    print("  (above: noisy, denoised, reference; below: the relative error |I - R| / (R + 0.01) of")
    print("  the noisy and the denoised image, on one scale, and the edges)")
    true = true_relmse(result.image, refs)
    return [("games101-hw5", spp, true, estimate_says(result, true))]


# %% [markdown]
# ## What the estimate says
#
# A plain render to a target error estimates its relMSE from each pixel's two halves
# (`docs/noise-target.md`). That estimate is of the *noisy* image's error; a denoised image
# has an error of another kind, part of it bias (the halos, the kept edge errors), which no
# comparison of two noisy halves sees. So a denoised render reports an estimate of its own,
# or none, with the reason (`result.estimate_refused`) and, where it can, what the error is
# below (`settings["relmse_bound"]`): never the noisy image's estimate.


# %%
def main() -> None:
    args, out = tutorial_options(
        __doc__,
        res=128,
        spp=64,
        spp_help="the most samples per pixel on the Cornell box (a quarter elsewhere)",
    )
    res, most_spp = args.res, max(args.spp, 1)
    # (at least 2: a denoised image's error is estimated from each pixel's two halves)
    failure_spp = max(2, most_spp // 4)
    reference_spp = 4 * max(most_spp, 16)  # (two of them: 8x the ladder's most)
    rows = cornell_box(out, res, most_spp, reference_spp)
    rows += small_lights(out, res, failure_spp, reference_spp)
    rows += glass_and_edges(out, res, failure_spp, reference_spp)
    print("what each denoised render estimates of its error, beside the true error:")
    print("  scene          spp   true relMSE   estimated")
    for scene, spp, true, says in rows:
        print(f"  {scene:13s} {spp:4d}   {true:11.4f}   {says}")
    show_pictures(out)


# %%
if __name__ == "__main__":
    main()
