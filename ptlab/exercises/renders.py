"""Comparing a render made with a student's code with the library's, up to noise.

The chapters whose code changes what the renderer computes (the intersection, the
materials, the path loop, the MIS weights) end with a render check: the same scene, the
same seed, rendered once with the library's code and once with the student's plugged in.
``pass_images`` keeps every pass of a render as an independent estimate, and
``compare_renders`` runs a paired t-test per image region and colour on them, with a
Bonferroni threshold for a stated false-alarm rate. ``replace_materials`` swaps a scene's
materials for a student's.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

#: The chance that a right answer fails a render comparison, at most (Bonferroni over every
#: region and channel of a paired t-test). Measured over seeds 0-299 with right answers that
#: sample differently from the library (so that their noise differs): 0 failures for chapter
#: 6 (uniform against cosine hemisphere sampling) and 0 for chapter 9 (Walter's sampling of
#: D(h) cos(theta_h) against visible normals).
FALSE_ALARM = 1e-3
#: A region must also differ by at least this fraction of its value (plus a tenth of the
#: image's mean) to count: rounding differences between two correct answers that draw the
#: same random numbers are systematic but tiny, and no mistake worth a point is that small.
MIN_RELATIVE_DIFFERENCE = 0.02
#: The image is cut into GRID x GRID regions for the comparison.
GRID = 4

ROWS = ("top", "upper middle", "lower middle", "bottom")
COLUMNS = ("left", "centre left", "centre right", "right")
CHANNELS = ("red", "green", "blue")


def replace_materials(scene, replace: Callable):
    """The scene with every material ``m`` for which ``replace(m)`` is not None replaced by it.

    The replacement (anything with ``eval``, ``pdf`` and ``sample``, made a full material by
    ``ptlab.grading.material.as_material``) keeps ``m``'s emission, so a light stays a light.
    Materials are looked up per triangle through ``scene.materials`` (and the
    ``material_table`` built from it), so a new ``Scene`` over the same triangles is all it
    takes.
    """
    from ptlab.grading.material import as_material
    from ptlab.scene import Scene

    materials = []
    for material in scene.materials:
        new = replace(material)
        if new is None:
            new = material
        else:
            new = as_material(new)
            new.emission = material.emission
        materials.append(new)
    return Scene(scene.triangles, scene.material_ids, materials, scene.camera, scene.name,
                 scene.material_names, scene.point_lights, scene.sky, scene.uvs, scene.defaults)


def pass_images(scene, res: int, passes: int, spp_per_pass: int, seed: int = 0,
                **options) -> np.ndarray:
    """(passes, res, res, 3) float64: the image of each pass of one render, on its own.

    The render takes independent samples (``sampler="independent"``), so the passes are
    independent estimates of the same picture and their spread gives the standard error.
    (Stratified and sobol samples would make the passes of one pixel correlated, parts of
    one pattern.) The render runs in this process (``workers=1``), where ``plugged``
    functions are seen.
    """
    from ptlab.rendering import render_result

    images = []
    done = np.zeros((res, res, 3))

    def keep(film) -> None:
        images.append((film.sums - done) / spp_per_pass)
        done[...] = film.sums

    render_result(scene, spp=passes * spp_per_pass, res=res, seed=seed, workers=1,
                  tile_size=res, spp_per_pass=spp_per_pass, on_pass=keep,
                  **dict(dict(sampler="independent"), **options))
    return np.stack(images)


def compare_renders(student: np.ndarray, library: np.ndarray) -> tuple[bool, str]:
    """Is the student's render the library's picture, up to noise? -> (passed, explanation).

    Both are ``pass_images`` of one scene with the same seed. Per region of a GRID x GRID
    cut and per channel, the differences of the region's mean between the two renders'
    passes are independent, so their mean over the passes divided by its standard error
    is Student-t distributed with passes - 1 degrees of freedom when both are right (a
    paired test: valid whether or not the two draw alike random numbers, and very sharp
    when they do). A region fails when that t exceeds the Bonferroni threshold for
    ``FALSE_ALARM`` over all regions and channels *and* the difference is at least
    ``MIN_RELATIVE_DIFFERENCE`` of the region's value.
    """
    from scipy.special import stdtrit

    passes = len(library)
    student_regions, library_regions = regions_of(student), regions_of(library)
    difference = student_regions - library_regions
    mean = difference.mean(axis=0)
    standard_error = difference.std(axis=0, ddof=1) / math.sqrt(passes)
    expected = library_regions.mean(axis=0)
    tests = mean.size
    threshold = float(stdtrit(passes - 1, 1 - FALSE_ALARM / (2 * tests)))
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(mean == 0, 0.0, np.abs(mean) / standard_error)
    floor = MIN_RELATIVE_DIFFERENCE * (np.abs(expected) + 0.1 * np.abs(expected).mean())
    wrong = (t > threshold) & (np.abs(mean) > floor)
    overall = student_regions.mean() / max(library_regions.mean(), 1e-12)
    if not wrong.any():
        return True, (f"every region within {threshold:.1f} standard errors of the library's "
                      f"(whole image {overall:.3f}x as bright)")
    score = np.where(wrong, np.abs(mean) / np.maximum(floor, 1e-12), 0)
    worst = np.unravel_index(np.argmax(score), score.shape)
    ratio = student_regions.mean(axis=0)[worst] / max(expected[worst], 1e-12)
    return False, (f"{int(wrong.sum())} of {tests} regions and colours differ from the library's "
                   f"picture beyond the noise; the worst, {describe_region(*worst)}, is "
                   f"{'brighter' if mean[worst] > 0 else 'darker'} ({ratio:.2f}x, "
                   f"{min(t[worst], 999):.0f} standard errors off; a right answer stays within "
                   f"{threshold:.1f}); the whole image is {overall:.2f}x as bright")


def describe_region(row: int, column: int, channel: int) -> str:
    """Region (row, column) of the GRID x GRID cut, in words: "the red of the top left region"."""
    return f"the {CHANNELS[channel]} of the {ROWS[row]} {COLUMNS[column]} region"


def regions_of(image: np.ndarray) -> np.ndarray:
    """(..., GRID, GRID, 3): the mean of each region of (..., H, W, 3) images."""
    *batch, height, width, _ = image.shape
    cut = image[..., :height - height % GRID, :width - width % GRID, :]
    shape = (*batch, GRID, height // GRID, GRID, width // GRID, 3)
    return cut.reshape(shape).mean(axis=(-4, -2))
