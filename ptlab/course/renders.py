"""Comparing a render made with a student's code with the library's, up to noise.

The chapters whose code changes what the renderer computes (the rays, the intersection,
the materials, the path loop) end with a render check: the same scene, the same seed,
rendered once with the library's code and once with the student's functions as the
render's pieces (``ptlab.rendering.pieces``).
``pass_images`` keeps every pass of a render as an independent estimate, and
``compare_renders`` compares the two renders' passes region by region: the student's must
not be NaN, not noisier than a right answer's may be, nor far less noisy (``noise_test``),
and not differ from the library's in the mean beyond the noise (a paired t-test per region
and colour).
``check_render_through`` is the whole check of the chapters whose functions are pieces of
the renderer (1, 2, 4 and 5): the Cornell box through the library's code, then through the
student's, compared. ``replace_materials`` swaps a scene's materials for a student's.

Every threshold comes from the library's passes, never from the student's alone (the
grading contract, docs/DESIGN.md): a render whose noise set its own standard error could
pass by adding noise (a loop that traces nothing and adds huge zero-mean noise to the film
would be "within a few standard errors" of anything).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Required, TypedDict

import numpy as np

from ptlab.accel.numpy_bvh import BVHPieces
from ptlab.course.chapter import CheckFailed, active_grading_seed, grading_seed_for
from ptlab.course.finite import at_pixel, channel_name, require_finite
from ptlab.course.messages import aside, text
from ptlab.rendering.pieces import Pieces

#: The chance that a right answer fails the mean test of a render comparison, at most
#: (Bonferroni over every region and colour, and over the two standard errors each is
#: tested with, see ``mean_verdict``), for passes that are normal; the false alarms of the
#: whole comparison (with ``NOISE_FALSE_ALARM``) were measured with right answers that
#: sample differently from the library: see ``NOISE_RATIO``.
FALSE_ALARM = 1e-3
#: A region must also differ by at least this fraction of its value (plus a tenth of the
#: image's mean) to count: rounding differences between two correct answers that draw the
#: same random numbers are systematic but tiny, and no mistake worth a point is that small.
MIN_RELATIVE_DIFFERENCE = 0.02
#: A right answer's passes may be at most NOISE_RATIO times as noisy (in variance, per
#: region and colour) as the library's at the same sample count: right answers that sample
#: otherwise than the library are noisier. Measured (``python scripts/render_false_alarm.py
#: --variance-ratios``, 40 seeds: 320-640 passes of each), the largest ratio over the regions
#: and colours: 1.92 for chapter 6's uniform hemisphere sampling against the library's
#: cosine sampling (2.23 for the squared ratio of the median absolute deviations), 1.17 for
#: a float32 Lambertian with a frame of its own, 1.71 (1.35) for chapter 9's Walter sampling
#: against visible normals, 1.13 for chapter 7's loop with random numbers of its own in the
#: Cornell box, 1.24 for a roulette that keeps u >= 1 - p_rr, 1.5 (median absolute
#: deviations; the variances are a firefly's) for the own-random loop in the furnace. The
#: factor 4 is twice the largest. Over 1400 seeds (runs of 500, 300 and 600), the half-th
#: largest ratio over the regions (``noise_test``'s, chance included) was at most 3.9 in the
#: furnace, 2.2 in the patterned furnace (``ch07_path_tracing.patterned_furnace_scene``),
#: neither failing the noise test once.
NOISE_RATIO = 4.0
#: A right answer's passes may be at most CLEAN_RATIO times less noisy (in variance, per
#: region and colour) than the library's at the same sample count: a render of these
#: samples cannot be much cleaner than the library's render of as many. A loop that adds a
#: stored, converged picture (or a furnace's analytic value) instead of its samples' light
#: is. Measured (``python scripts/render_false_alarm.py --seeds 40 --variance-ratios
#: --constant``: 40 fresh grading seeds), the smallest ratio of a right answer's, chance
#: included, was 0.49 (chapter 7's loop with random numbers of its own, in the furnace),
#: 0.56 to 1.03 in the other render checks; the factor 4 leaves twice that room, and a
#: converged picture was caught as too clean in all 40 x 7 trials. Over 1400 seeds: 0.23 in
#: the furnace, 0.51 in the patterned furnace, a converged picture caught in all 1400 x 2.
#: A wrong answer may be far less noisy honestly (a wider highlight is found by more light
#: samples): ``NoiseTest.verdict`` says "not a render of these samples" only of a picture
#: that is right in the mean.
CLEAN_RATIO = 4.0
#: The chance that a right answer (noise at most NOISE_RATIO times the library's, and at
#: least 1 / CLEAN_RATIO times) fails each side of the noise test (``noise_test``), at
#: most, for passes that are normal.
NOISE_FALSE_ALARM = 1e-4
#: The image is cut into GRID x GRID regions for the comparison.
GRID = 4

#: The picture of ``check_render_through`` without passes: the Cornell box's normals. The
#: normals view is deterministic: the same closest hits give the same picture. Its seed (the
#: pixels' jitter) is stream NORMALS_STREAM of the grading seed.
NORMALS_VIEW = dict(spp=2, res=(48, 36), integrator="normals")
NORMALS_STREAM = 3
#: The mean absolute difference from the library's normals view that a student's may have.
NORMALS_TOLERANCE = 1e-3
#: The share of the picture that a student's normals view may leave black where the
#: library's sees a wall, where the check looks for missing walls (``missing_hint``).
MISSING_TOLERANCE = 0.01


#: The library's pictures made in this process, by (grading seed, what was rendered)
#: (``library_render``); the oldest go first beyond ``LIBRARY_RENDERS_KEPT``.
_LIBRARY_RENDERS: dict[tuple, np.ndarray] = {}
LIBRARY_RENDERS_KEPT = 32


def library_render(what: tuple, render: Callable[[], np.ndarray]) -> np.ndarray:
    """``render()``, a picture made with the library's code alone, kept read-only for later
    gradings in this process with the same grading seed: ``what`` names the picture and
    everything it depends on beside the grading seed (the chapter's render, its seed, its
    settings). Its scene and settings come from the grading seed, so one seed makes one
    picture: gradings that share a seed (``--grading-seed``, the tests' fixed seeds) render
    it once. Never for a render that runs any of the student's code."""
    seed = active_grading_seed()
    if seed is None:  # (outside a grading: nothing to key it by)
        return render()
    key = (seed, *what)
    if key not in _LIBRARY_RENDERS:
        picture = np.asarray(render())
        picture.flags.writeable = False  # (shared by every grading that asks again)
        _LIBRARY_RENDERS[key] = picture
        while len(_LIBRARY_RENDERS) > LIBRARY_RENDERS_KEPT:
            del _LIBRARY_RENDERS[next(iter(_LIBRARY_RENDERS))]
    return _LIBRARY_RENDERS[key]


def check_render_through(
    yours: str,
    pieces: Pieces,
    *,
    passes: dict | None = None,
    hint: str = "",
    nan_hint: str = "",
    missing_hint: str = "",
) -> str:
    """The Cornell box rendered with the library's code, then with ``pieces``, the student's
    functions in the library's place: the same picture? -> a note saying how close, or
    ``CheckFailed``.

    Args:
        yours: the student's code in the messages: "your rays", "your BVH" (in the active
            language: ``ptlab.course.messages.text``).
        passes: None for the normals view (``NORMALS_VIEW``), compared pixel by pixel: it
            must be finite and differ from the library's by at most ``NORMALS_TOLERANCE``
            on average. Else the ``pass_images`` settings of a path-traced render (res,
            passes, spp_per_pass, seed, ...), compared up to noise by ``compare_renders``.
        hint: what a difference may mean, added to the failure of the comparison.
        nan_hint: what may cause NaN in the normals view, added to that failure.
        missing_hint: if given, the normals view must also see a wall wherever the
            library's does (black there in at most ``MISSING_TOLERANCE`` of the picture);
            this says what may have lost them.

    The library's picture is rendered first, before any of the student's code runs. The
    pieces of the NumPy BVH are seen only through its tree: the student's render runs on
    the NumPy backend (which walks its tree for a scene as small as the Cornell box when
    given pieces of its own: ``NumpyBVH``). The library's normals view comes from the same
    backend as the student's (compared pixel by pixel), its passes from the fastest
    (compared up to noise).
    """
    import ptlab

    backend = backend_for(pieces)
    scene = ptlab.load_scene("cornell-box")
    if passes is not None:
        library = library_render(
            ("cornell-box passes", *sorted(passes.items())),
            lambda: pass_images(scene, backend="auto", **passes),
        )
        student = pass_images(scene, backend=backend, pieces=pieces, **passes)
        return compare_renders(
            student, library, text("render.path_traced", yours=yours), hint, passes["spp_per_pass"]
        )
    options = dict(NORMALS_VIEW, seed=grading_seed_for(NORMALS_STREAM), workers=1, backend=backend)
    library = library_render(
        ("cornell-box normals", *sorted(options.items())), lambda: ptlab.render(scene, **options)
    )
    student = ptlab.render(scene, **options, pieces=pieces)
    what = text("render.normals", yours=yours)
    require_finite(student, what, at_pixel, hint=nan_hint)
    missing = (student.max(axis=2) == 0) & (library.max(axis=2) > 0)
    if missing_hint and missing.mean() > MISSING_TOLERANCE:
        raise CheckFailed(text("render.missing", yours=yours, share=missing.mean(), hint=missing_hint))
    difference = np.abs(student - library).mean()
    if not difference <= NORMALS_TOLERANCE:
        raise CheckFailed(text("render.normals_differ", what=what, difference=difference) + aside(hint))
    return text("render.normals_match", yours=yours)


def backend_for(pieces: Pieces, backend: str = "auto") -> str:
    """``backend``, or the NumPy BVH where ``pieces`` has BVH pieces of a student's (Embree
    has none to swap)."""
    return "numpy" if pieces.bvh != BVHPieces() else backend


def replace_materials(scene, replace: Callable):
    """The scene with every material ``m`` for which ``replace(m)`` is not None replaced by it.

    The replacement (anything with ``eval``, ``pdf`` and ``sample``, made a full material by
    ``ptlab.grading.material.as_material``) keeps ``m``'s emission, so a light stays a light.
    Materials are looked up per triangle through ``scene.materials`` (and the
    ``material_table`` built from it), so a new ``Scene`` over the same triangles is all it
    takes.
    """
    from ptlab.course.sandbox.remote_material import as_student_material

    materials = []
    for material in scene.materials:
        new = replace(material)
        if new is None:
            new = material
        else:
            new = as_student_material(new)
            new.emission = material.emission
        materials.append(new)
    return scene.with_materials(materials)


class PassSettings(TypedDict, total=False):
    """A render check's render, as ``pass_images`` takes it (beyond the scene, the seed and
    the pieces): ``passes`` passes of ``spp_per_pass`` samples per pixel of a ``res`` x
    ``res`` image, and the path tracer's options it sets (``ptlab.render``'s keywords)."""

    res: Required[int]
    passes: Required[int]
    spp_per_pass: Required[int]
    max_depth: int
    rr: float


def pass_images(
    scene, res: int, passes: int, spp_per_pass: int, seed: int = 0, pieces: Pieces | None = None, **options
) -> np.ndarray:
    """(passes, res, res, 3) float64: the image of each pass of one render, on its own.

    Raises ``CheckFailed`` if any sample was NaN or infinite (``add_to_film`` leaves them
    out of the image, counted, in the student's process too), naming the first.

    The render takes independent samples (``sampler="independent"``), so the passes are
    independent estimates of the same picture and their spread gives the standard error.
    (Stratified and sobol samples would make the passes of one pixel correlated, parts of
    one pattern.) The render runs in this process (``workers=1``), where the student's
    ``pieces`` (if given) are, with the render's own tiles (``TILE_SIZE``): its calls are a
    render's batches, not sizes of the grader's own.
    """
    from ptlab.rendering import render_result

    images = []
    done = np.zeros((res, res, 3))

    def keep(film) -> None:
        images.append((film.sums - done) / spp_per_pass)
        done[...] = film.sums

    result = render_result(
        scene,
        spp=passes * spp_per_pass,
        res=res,
        seed=seed,
        workers=1,
        spp_per_pass=spp_per_pass,
        on_pass=keep,
        pieces=pieces,
        **dict(dict(sampler="independent"), **options),
    )
    if result.nonfinite:  # (left out of the image, which therefore looks fine: say so)
        x, y, depth = result.first_nonfinite or (-1, -1, -1)
        raise CheckFailed(text("render.nonfinite", count=result.nonfinite, x=x, y=y, depth=depth))
    return np.stack(images)


def compare_renders(
    student: np.ndarray,
    library: np.ndarray,
    what: str,
    hint: str | Callable[[], str] = "",
    spp: int | None = None,
    false_alarm: float = FALSE_ALARM,
) -> str:
    """Is the student's render the library's picture, up to noise? -> a note saying how
    close it is, or ``CheckFailed`` with "``what``: how it differs (``hint``)".

    Both are ``pass_images`` of one scene with the same seed and settings. The student's
    must be finite (the failure names the pass and the pixel), no noisier than
    ``NOISE_RATIO`` times the library's and no less noisy than 1 / ``CLEAN_RATIO`` times
    (``noise_test``, on the regions' sums of the three colours), and equal to the library's
    in the mean of every region and colour (``mean_verdict``). ``hint`` (what a brighter or
    darker picture means; a function that finds it, called only then) is added to a
    failure of the mean; ``spp`` (the samples per pixel
    of a pass) to a failure of the noise. ``false_alarm``: the mean test's (a check that
    looks for large differences only may take a smaller one than ``FALSE_ALARM``).

    A picture that differs in the mean leads with that difference: a wrong material or loop
    renders other light, whose noise differs too (a wider highlight is found by more light
    samples, and is less noisy), so its noise is then said as a fact, not as evidence that
    the picture was not rendered from its samples (``NoiseTest.verdict``).
    """
    require_finite(student, text("render.yours", what=what), at_pixel)
    student_regions, library_regions = regions_of(student), regions_of(library)
    difference = mean_verdict(student_regions, library_regions, false_alarm)
    noise = noise_test(student_regions.sum(axis=-1), library_regions.sum(axis=-1))
    said = noise.verdict(spp, differs=difference is not None)
    if said is None and difference is None:
        overall = student_regions.mean() / max(library_regions.mean(), 1e-12)
        threshold = mean_threshold(len(library), student_regions[0].size, false_alarm)
        return text("render.matches", what=what, threshold=threshold, overall=overall)
    if difference is None:
        raise CheckFailed(text("render.differs", what=what, difference=said))
    then: str | None  # (said second, the noise may have nothing to say)
    if said is not None and not noise.too_clean:  # (too noisy first: added noise moves the mean too)
        first, then = said, difference
    else:  # (the difference first; a picture of other light, less noisy, after it)
        first, then = difference, said
    also = text("render.and", difference=then) if then else ""
    said = hint() if callable(hint) else hint
    raise CheckFailed(text("render.differs", what=what, difference=first) + also + aside(said))


def mean_threshold(passes: int, tests: int, false_alarm: float = FALSE_ALARM) -> float:
    """The t above which a region and colour differs, for ``passes`` pairs of passes:
    Student's t with passes - 1 degrees of freedom, two-sided, Bonferroni over ``tests``
    regions and colours times the two standard errors of ``mean_t``, for ``false_alarm``
    in all."""
    from scipy.special import stdtrit

    return float(stdtrit(passes - 1, 1 - false_alarm / (2 * 2 * tests)))


def mean_t(student: np.ndarray, library: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(t, mean difference) per region and colour of (passes, ...) region values.

    The differences between the two renders' passes are independent, so their mean m over
    their standard error s_d / sqrt(P) is Student-t distributed with P - 1 degrees of
    freedom when both are right (a paired test: valid whether or not the two draw alike
    random numbers, and very sharp when they do). But the student's noise must not widen
    the test: a right answer's differences have a standard deviation of at most
    (1 + sqrt(NOISE_RATIO)) sigma_L (sigma_S <= sqrt(NOISE_RATIO) sigma_L, however the two
    are correlated), so the standard error is never taken above that bound, with the
    library's s_L for sigma_L; m over the bound is then at most a Student-t as well (m, s_L
    and s_d are independent for normal passes). ``mean_threshold`` takes the union bound
    over the two.
    """
    passes = len(library)
    difference = student - library
    mean = difference.mean(axis=0)
    paired = difference.std(axis=0, ddof=1) / math.sqrt(passes)
    bound = (1 + math.sqrt(NOISE_RATIO)) * library.std(axis=0, ddof=1) / math.sqrt(passes)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(mean == 0, 0.0, np.abs(mean) / np.minimum(paired, bound))
    return t, mean


def without_the_most_extreme_pass(student: np.ndarray, library: np.ndarray) -> tuple:
    """(student, library) with, per region and colour, the pass whose difference lies
    farthest from the median difference left out: (passes - 1, ...) each."""
    difference = student - library
    farthest = np.abs(difference - np.median(difference, axis=0)).argsort(axis=0)
    kept = farthest[:-1]
    return np.take_along_axis(student, kept, axis=0), np.take_along_axis(library, kept, axis=0)


def mean_verdict(student: np.ndarray, library: np.ndarray, false_alarm: float = FALSE_ALARM) -> str | None:
    """None if the student's regions agree with the library's in the mean, else how they
    differ. ``student``, ``library``: (passes, GRID, GRID, 3) regions of the two renders.

    A region and colour fails when its t (``mean_t``) is above ``mean_threshold``, its
    difference is at least ``MIN_RELATIVE_DIFFERENCE`` of its value, *and* its t with its
    most extreme pass left out is above the threshold for one pass fewer too. A path
    tracer's rare firefly (a light sample through a glossy highlight: chapter 9's passes
    have an excess kurtosis up to 500) moves one pass of a region by many standard
    deviations, and the standard error bound of ``mean_t`` would take that for a
    difference when only the student's render has it; a wrong answer differs in every
    pass. Since a region fails only if both tests say so, a right answer fails with
    probability at most ``false_alarm`` (the first test's), for normal passes.
    """
    t, mean = mean_t(student, library)
    t_without, _ = mean_t(*without_the_most_extreme_pass(student, library))
    passes, expected = len(library), library.mean(axis=0)
    threshold = mean_threshold(passes, mean.size, false_alarm)
    floor = MIN_RELATIVE_DIFFERENCE * (np.abs(expected) + 0.1 * np.abs(expected).mean())
    without = mean_threshold(passes - 1, mean.size, false_alarm)
    wrong = (t > threshold) & (t_without > without) & (np.abs(mean) > floor)
    if not wrong.any():
        return None
    score = np.where(wrong, np.abs(mean) / np.maximum(floor, 1e-12), 0)
    worst = np.unravel_index(np.argmax(score), score.shape)
    ratio = student.mean(axis=0)[worst] / max(expected[worst], 1e-12)
    overall = student.mean() / max(library.mean(), 1e-12)
    return text(
        "render.mean_brighter" if mean[worst] > 0 else "render.mean_darker",
        wrong=int(wrong.sum()),
        tests=mean.size,
        region=describe_region(*map(int, worst)),
        ratio=ratio,
        t=min(t[worst], 999),
        threshold=threshold,
        overall=overall,
    )


@dataclass(frozen=True)
class NoiseTest:
    """The student's passes' noise against the library's at the same samples per pixel
    (``noise_test``): the variance ratios of the regions, and the bounds a right answer's
    stay within.

    Attributes:
        high: the half-th largest variance ratio (student / library) over the regions.
        low: the half-th smallest.
        total: the ratio of the two variances summed over the regions.
        regions: the number of regions.
        passes: the number of passes of each render.
        chance: how far from 1 chance takes the half-th ratio with probability
            ``NOISE_FALSE_ALARM`` (``noise_test``).
    """

    high: float
    low: float
    total: float
    regions: int
    passes: int
    chance: float

    @property
    def too_noisy(self) -> bool:
        return self.high > NOISE_RATIO * self.chance

    @property
    def too_clean(self) -> bool:
        return self.low < 1 / (CLEAN_RATIO * self.chance)

    def verdict(self, spp: int | None = None, differs: bool = False) -> str | None:
        """None if the noise is a right answer's, else how it is not: "too noisy: ...", or
        for passes far less noisy than a render of their samples can be, "too clean for N
        samples per pixel: this is not a render of these samples" where the picture is the
        library's in the mean (``differs`` False: a converged picture, or an analytic value,
        added in place of the samples' light), and a plain statement of how much less noisy
        where it is not (``differs``: a wrong answer renders other light, with noise of its
        own). ``spp``: the samples per pixel of a pass: the messages say what each render
        drew, its passes and their samples per pixel."""
        drawn = (
            text("render.drawn", passes=self.passes, spp=spp)
            if spp
            else text("render.passes", passes=self.passes)
        )
        numbers = dict(regions=self.regions, total=self.total, false_alarm=NOISE_FALSE_ALARM, drawn=drawn)
        if self.too_clean:
            clean = dict(low=self.low, clean_ratio=CLEAN_RATIO, bound=1 / (CLEAN_RATIO * self.chance))
            samples = spp or text("render.its")
            return text(
                "render.less_noisy" if differs else "render.too_clean", spp=samples, **clean, **numbers
            )
        if self.too_noisy:
            return text(
                "render.too_noisy",
                median=self.high,
                noise_ratio=NOISE_RATIO,
                bound=NOISE_RATIO * self.chance,
                **numbers,
            )
        return None


def noise_test(student: np.ndarray, library: np.ndarray) -> NoiseTest:
    """How the student's passes' noise compares with the library's (``NoiseTest``; its
    ``verdict`` says whether a right answer's could be so). ``student``, ``library``:
    (passes, GRID, GRID): a value per pass of each region (their pixels take independent
    samples, so the regions are independent).

    Per region k the ratio of the two sample variances over the passes is r_k F(P - 1,
    P - 1) for normal passes, r_k the true ratio. The test looks at the median region: it
    fails when at least half of the K regions have a ratio above NOISE_RATIO * x, with x
    such that K independent F(P - 1, P - 1) put half of theirs above x with probability
    NOISE_FALSE_ALARM (a binomial tail: p = F's tail at x is beta's NOISE_FALSE_ALARM
    quantile). If every r_k <= NOISE_RATIO, a right answer fails with probability at most
    NOISE_FALSE_ALARM. Half the regions, not one: a path tracer's rare fireflies (a light
    sample through a glossy bounce, in chapter 9) make a region's variance a hundred times
    the library's now and then, but in a few regions at a time, while noise added to a
    picture is everywhere. Variances below (1e-4 of the picture's mean)^2, rounding's,
    count as that much.

    The other side alike: F(P - 1, P - 1) is 1 / F(P - 1, P - 1) in distribution, so when
    at least half of the regions have a ratio below 1 / (CLEAN_RATIO * x), the passes are
    too clean for their samples; if every r_k >= 1 / CLEAN_RATIO, a right answer fails so
    with probability at most NOISE_FALSE_ALARM.
    """
    from scipy.stats import beta, f

    passes, regions = len(library), library[0].size
    floor = (1e-4 * max(float(np.abs(library).mean()), 1e-12)) ** 2
    student_variance = np.maximum(student.var(axis=0, ddof=1), floor)
    library_variance = np.maximum(library.var(axis=0, ddof=1), floor)
    ordered = np.sort(student_variance / library_variance, axis=None)
    half = (regions + 1) // 2
    return NoiseTest(
        high=float(ordered[-half]),  # the half-th largest
        low=float(ordered[half - 1]),  # the half-th smallest
        total=float(student_variance.sum() / library_variance.sum()),
        regions=regions,
        passes=passes,
        chance=float(f.isf(beta.ppf(NOISE_FALSE_ALARM, half, regions - half + 1), passes - 1, passes - 1)),
    )


def describe_region(row: int, column: int, channel: int) -> str:
    """Region (row, column) of the GRID x GRID cut, in words: "the red of the top left region"."""
    return text("region.channel", channel=channel_name(channel), region=region_name(row, column))


def region_name(row: int, column: int) -> str:
    """Region (row, column) of the GRID x GRID cut, in words: "the top left region"."""
    return text(f"region.{row}.{column}")


def regions_of(image: np.ndarray) -> np.ndarray:
    """(..., GRID, GRID, 3): the mean of each region of (..., H, W, 3) images."""
    *batch, height, width, _ = image.shape
    cut = image[..., : height - height % GRID, : width - width % GRID, :]
    shape = (*batch, GRID, height // GRID, GRID, width // GRID, 3)
    return cut.reshape(shape).mean(axis=(-4, -2))
