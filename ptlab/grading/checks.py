"""The checks of a (non-delta) material's ``eval``, ``pdf``, ``sample`` and ``sample_weight``.

Every check is deterministic for a given seed. The statistical ones are tuned to a
documented false-alarm rate (the chance that a correct material fails), the others are
exact up to floating point (rate 0). ``check_material`` in ``ptlab.grading`` runs them all.

For each ``wo`` (by default at 0 and about 45 and 80 degrees from the normal: each but the
head-on one moved by up to 5 degrees per seed, ``lobe_angles``), ``measure`` draws N = 10^6
directions from ``sample``, evaluates ``pdf`` and ``eval`` at them, and integrates ``pdf``
and ``eval`` |cos theta_i| over every cell of an equal-area grid on the sphere (64 x 128
cells for 10^6 samples; ``SphereGrid.integrate``). The calls look like a render's
(``ptlab.grading.probes``): a render's sizes (``render_calls``), the rows of the wo's
interleaved, every row on one of a few walls (one normal and one tangent frame on many
rows, as a room's walls are), each row's wo turned about the normal by an angle of its
own. The samples are turned back into the grid's frame to test each wo, and into their
wall's frame to test each wall. From these:

* **chi-square**: per wo, the samples' histogram against the expected counts N
  integral(pdf) per cell, plus one category for failed samples (where ``pdf`` is 0, or
  ``sample`` gave NaN) expecting N (1 - integral of pdf over the sphere); cells expecting
  fewer than 5 are pooled. Per wall (``WALLS`` of them), its samples in its own frame
  against an even spread in azimuth within each band of cos theta (``wall_chi_square``):
  a sampler whose azimuth is uneven in a tangent frame of its own (phi = 2 pi u^2) passes
  every wo's test, where each row is turned back by its own twist and the skew spreads out,
  and fails its walls', as a render of a wall shows it. The statistics are computed
  directly and their p-values are those of ``scipy.stats.chi2.sf``; the Sidak correction
  over the K wo's and the W walls fails the check when a p-value is below
  1 - (1 - 1e-3)^(1/(K + W)). False-alarm rate 1e-3.
* **pdf normalisation**: the integral of ``pdf`` over the sphere equals the fraction of
  samples that did not fail (so it is 1 for a sampler that never fails, at most 1 always),
  within 4.1 binomial standard errors (Sidak over the wo's at 1e-4) plus the quadrature's
  error. False-alarm rate 1e-4.
* **energy**: the integral of f_r |cos theta_i| (each colour channel) is at most
  1 + 1e-3 + the quadrature's error. Deterministic (rate 0). Give white parameters
  (albedo 1, F0 1) to test energy conservation at its limit.
* **estimator agreement**: the importance-sampled estimate mean(f cos / pdf) over the
  samples equals the integral of f |cos| computed by the quadrature (a stratified
  uniform-sphere estimate without noise), within 4.4 standard errors (Sidak over the wo's
  and channels at 1e-4) plus the quadrature's error and 8 float32 ulps of the value (the
  material's own rounding). False-alarm rate 1e-4.
* **sample_weight**: ``sample_weight`` returns the direction ``sample`` returns for the same
  ``u`` and the weight f cos / pdf (0 where pdf is 0), to a relative 1e-5, on the first
  rows of measure's calls, 10^5 per wo (the wo's mixed). Deterministic.
* **reciprocity**: eval(wo, wi) == eval(wi, wo) to a relative 1e-5 (1e-3 for an eval that
  returns float32: rounding in float32 arithmetic) on 20 000 random pairs above the surface,
  grazing ones included. Deterministic.
* **consistency**: at special directions (grazing, exactly tangent, wi = +-n, wi = +-wo,
  the mirror direction, below the surface) and edge values of u: nothing NaN or infinite,
  eval >= 0, pdf >= 0, both 0 below the surface, sample gives unit vectors, sample_weight
  0 where wo is below. Deterministic. (That pdf > 0 where sample lands is the chi-square's
  failed-sample category: a sample may fail, as VNDF sampling does, only as often as
  1 - integral of pdf admits.)
* **float32**: the renderer passes float32 arrays stored column by column: the results
  must agree with float64 ones (relative 1e-2) and be finite; a float64 result is a
  warning (it works, slowly). Deterministic.
* **row independence**: the first 32 rows of the first large calls of ``sample``, ``pdf``,
  ``eval`` and (if the material has its own) ``sample_weight``, in float64 and in float32,
  asked again one row at a time, as one shuffled batch, and at random places among other
  rows (a curved surface's: a normal per row) inside batches of other sizes: a render's
  batch (2^18 rows, ``RENDER_BATCH``) and ``RANDOM_BATCHES`` sizes up to 2^19 drawn per run
  from fresh entropy (``batch_sizes``), give the batch's answers to a relative 1e-3
  (``ROW_RTOL``): a material whose answer for a row depends on the other rows (their
  number, order, mean, how many normals they hold) could tell a probe from a render. Where
  a row differs, its batching is asked again with every input moved by up to 16 ulps
  (``Kept.nudged``, ``NUDGES`` times): a row whose answer then moves beyond the tolerance
  too is ill-conditioned, and its difference is rounding (Heitz's visible normals as
  published pick their tangent from rounding noise at wo = n, which NumPy's einsum rounds
  otherwise for a column-major batch than for one row); a material whose answer follows the
  other rows keeps it under such a nudge, and fails. Deterministic for an honest material
  (rounding only; the measured rates are at the end). ``ptlab grade`` of chapter 6's
  float32 right answer, in its own process, takes 3.6 s in all at 10^6 samples per wo.
* **reflectance**: ``sample`` fails (pdf 0 or not finite) on at most ``MAX_FAILED_SHARE``
  (90%) of the samples of every wo, else FAIL ("sample returns no direction with a positive
  pdf"); an integral of f |cos| of 0 at every wo is a warning ("reflects nothing"), which
  does not fail the report. Deterministic.

All together a correct material fails with probability at most about 1.2e-3 by chance;
``scripts/false_alarm_rate.py`` measures it, per check (docs/06-diffuse.md has the table).
With the walls, render-sized calls and nudged rows: at ``ptlab grade``'s seed 0, 0 of its 14
correct materials fail (``--harness-seed 0``, 10^6 samples per wo); over 600 fresh grading
seeds (twice ``--seeds 300 --samples 200000``), 2 failures (0.33%, 95%: 0.04% to 1.2%), both
the chi-square (p 8.4e-5 and 4.4e-5 against 9.1e-5) of one material, copper with a diffuse
layer, whose p-values otherwise keep their level; the chi-square's smallest p came within
10x of its threshold in 9 of 516 runs (about 1% expected). Every other check: 0 of 516 to
600. Heitz's visible normals as published (``tests/wrong_materials.py``): 0 failures in 120
gradings. (Before the walls, 0 in 1000 runs at 10^6 samples per wo.)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np

from ptlab.grading.material import derives_sample_weight
from ptlab.grading.probes import Kept, Probe, Walls, rows_of
from ptlab.grading.report import Check, verdict
from ptlab.grading.sphere import SphereGrid, along
from ptlab.rendering.sizes import SPP_PER_PASS, TILE_SIZE
from ptlab.samplers import ONE_MINUS_EPSILON, largest_below_one
from ptlab.sampling import to_world
from ptlab.vectors import dot, normalize, vec3

ALPHA_CHI_SQUARE = 1e-3
ALPHA_NORMALISATION = 1e-4
ALPHA_ESTIMATOR = 1e-4
MIN_EXPECTED = 5.0
ENERGY_SLACK = 1e-3
#: Reciprocity holds to this relative difference (float32 constants in float64 arithmetic
#: differ by a few float32 ulps, 1.2e-7 each, between the two orders), or for a material
#: whose eval returns float32 to RECIPROCITY_RTOL_FLOAT32: measured up to 4e-5 for the
#: library's microfacet computing in float32 (the Fresnel term at h . wo against h . wi,
#: rounded apart). A non-reciprocal term from a mistake differs by a percent or more.
RECIPROCITY_RTOL = 1e-5
RECIPROCITY_RTOL_FLOAT32 = 1e-3
SAMPLE_WEIGHT_RTOL = 1e-5
POINTWISE_ROWS = 100_000
#: Rows of a large call that ``check_row_independence`` asks again, per call kept.
ROW_INDEPENDENCE_ROWS = 32
#: Answers for a row asked alone (or in another order) agree with the batch's to this relative
#: difference (plus ROW_ATOL): the same elementwise arithmetic on the same numbers gives the
#: same bits, but NumPy's vector loops (whole arrays) and scalar ones (a tail, a strided
#: view, one row) may round a transcendental function (exp, sin, arctan2, pow) differently
#: in the last ulp, and a narrow lobe amplifies that: GGX with alpha 0.05 in float32 turns
#: 1 ulp of cos theta_h (6e-8) into about 4 / alpha^2 = 1600 ulps of D, 1e-4. A trick that
#: changes a render is percents off.
ROW_RTOL = 1e-3
ROW_ATOL = 1e-9
#: A render's batch: a tile of TILE_SIZE x TILE_SIZE pixels in a pass of SPP_PER_PASS samples
#: per pixel (2^18 paths; ptlab.rendering.sizes), the size of its first bounce's calls.
RENDER_BATCH = TILE_SIZE * TILE_SIZE * SPP_PER_PASS
#: Batch sizes drawn at random per run (``batch_sizes``), up to twice a render's batch.
RANDOM_BATCHES = 3
LARGEST_BATCH = 2 * RENDER_BATCH
#: Values above this negative number count as 0: a cosine rounded to -1e-17 is no mistake.
NEGATIVE_ROUNDING = 1e-12
#: Quadrature tolerance on the integrals of f |cos|: each region's error at most this times
#: (its integral + its share of the sphere), so about 2e-4 over the sphere at worst.
F_TOLERANCE = 1e-4
#: Relative slack of the estimator check for a material's own rounding: 8 float32 ulps. A
#: Lambertian with pi = np.float32(math.pi) integrates to 1 - 2.8e-8; with cosine sampling
#: its f cos / pdf is the same for every sample, so no noise term covers that.
FLOAT32_SLACK = 8 * float(np.finfo(np.float32).eps)


class MaterialError(Exception):
    """A material's method raised or returned something of the wrong shape."""


def call(material, method: str, *arrays: np.ndarray, shapes=None, keep: list | None = None):
    """``material.<method>(*arrays)``, its result checked against the expected shapes.

    With ``keep`` (a list), the first ``ROW_INDEPENDENCE_ROWS`` rows of the arguments and
    the answer are appended to it (``Kept``), for ``check_row_independence`` to ask again.
    """
    try:
        result = getattr(material, method)(*arrays)
    except Exception as error:  # a student's bug: reported as a failed check
        raise MaterialError(f"{method} raised {type(error).__name__}: {error}") from error
    parts = result if isinstance(result, tuple) else (result,)
    parts = tuple(np.asarray(p) for p in parts)
    for part, shape in zip(parts, shapes or (), strict=False):
        if part.shape != shape:
            raise MaterialError(f"{method} returned shape {part.shape}, expected {shape}")
    if keep is not None:
        keep.append(Kept.first_rows(method, arrays, parts, ROW_INDEPENDENCE_ROWS))
    return parts if isinstance(result, tuple) else parts[0]


def batch(v: np.ndarray, rows: int, dtype=np.float64) -> np.ndarray:
    """(rows, 3) copies of the (3,) vector ``v``, column-major like the renderer's arrays."""
    return np.asfortranarray(np.broadcast_to(np.asarray(v, dtype=dtype), (rows, 3)))


def sidak(alpha: float, tests: int) -> float:
    """The per-test level that keeps the chance of any false alarm among ``tests`` at ``alpha``."""
    return 1.0 - (1.0 - alpha) ** (1.0 / tests)


def chi2_sf(statistic: float, dof: int) -> float:
    """P(X >= statistic) for X chi-square with ``dof`` degrees of freedom.

    ``scipy.special.chdtrc`` is the function ``scipy.stats.chi2.sf`` evaluates; calling it
    directly saves the second that importing ``scipy.stats`` takes.
    """
    from scipy.special import chdtrc

    return float(chdtrc(dof, statistic))


def z_two_sided(alpha: float) -> float:
    """The z with P(|Z| > z) = alpha for a standard normal Z."""
    from scipy.special import ndtri

    return float(-ndtri(alpha / 2))


def direction_at(n: np.ndarray, degrees: float, azimuth: float) -> np.ndarray:
    """(3,) the unit vector at ``degrees`` from ``n`` (3,), at ``azimuth`` radians around it."""
    theta = math.radians(degrees)
    local = np.array(
        [[math.sin(theta) * math.cos(azimuth), math.sin(theta) * math.sin(azimuth), math.cos(theta)]]
    )
    return to_world(local, np.asarray(n, dtype=np.float64)[None, :])[0]


# -- measuring the wo's -------------------------------------------------------------------


#: Each wo of the statistical checks lies up to this many degrees from its nominal angle
#: (``lobe_angles``), and never past 0 or the horizon: a material right at the grader's
#: angles only is wrong at the ones it is graded at.
WO_JITTER_DEGREES = 5.0


def lobe_angles(degrees: tuple, rng: np.random.Generator) -> tuple[float, ...]:
    """The angles of the wo's from the normal: each of ``degrees`` moved by a random amount
    of up to ``WO_JITTER_DEGREES`` (and up to half its distance to 0 and to 90, so that 0,
    head-on, stays 0 and 85 stays short of the horizon), to 0.1 degree."""
    moved = []
    for d in degrees:
        reach = min(WO_JITTER_DEGREES, max(d, 0.0) / 2, max(90.0 - d, 0.0) / 2)
        moved.append(round(float(d + rng.uniform(-reach, reach)), 1) if reach > 0 else float(d))
    return tuple(moved)


def render_calls(rng: np.random.Generator, total: int) -> list[int]:
    """The sizes of the calls that send ``total`` rows as a render does: each a material's
    share of a render's first bounce, uniform in [RENDER_BATCH / 4, RENDER_BATCH], the last
    what is left."""
    sizes = []
    while total > 0:
        sizes.append(min(total, int(rng.integers(RENDER_BATCH // 4, RENDER_BATCH + 1))))
        total -= sizes[-1]
    return sizes


@dataclass
class Lobe:
    """What ``measure`` found for one ``wo``: histogram, integrals, estimates."""

    degrees: float
    wo: np.ndarray  # (3,) in the grid's frame
    grid: SphereGrid
    samples: int
    observed: np.ndarray  # (cells,) samples with pdf > 0 in each cell
    failed: int  # samples with pdf == 0 or non-finite
    failed_below: int  # ... of which below the surface
    integrals: np.ndarray  # (cells, 4): integral of pdf, f_rgb |cos| over each cell
    errors: np.ndarray  # (4,) quadrature error bounds of the totals
    estimate: np.ndarray  # (3,) mean of f cos / pdf over the samples
    estimate_sd: np.ndarray  # (3,) standard deviation of f cos / pdf

    @property
    def pdf_integral(self) -> float:
        return float(self.integrals[:, 0].sum())

    @property
    def reflectance(self) -> np.ndarray:
        """(3,) the integral of f |cos| over the sphere."""
        return self.integrals[:, 1:].sum(axis=0)


def measure(
    material,
    grid: SphereGrid,
    degrees: tuple,
    samples: int,
    rng: np.random.Generator,
    kept: list | None = None,
) -> tuple[list[Lobe], dict, WallSamples]:
    """Sample, histogram and integrate a ``wo`` at each of ``degrees`` from ``grid.n``, together.

    Each wo gets ``samples`` rows; the rows of all of them are interleaved (every block of
    len(degrees) rows holds one of each wo, in a random order) and sent in calls of a
    render's sizes (``render_calls``), every row on one of ``WALLS`` walls that every call
    shares (``ptlab.grading.probes``); the directions ``sample`` returns are turned back into
    the grid's frame to be binned per wo, and into their wall's frame to be binned per wall
    (``WallSamples``). The quadrature's calls mix the wo's alike (``_integrals``). ``kept``
    receives the first rows of the first calls.

    Returns:
        one ``Lobe`` per wo, sample_weight beside f cos / pdf on the first
        ``POINTWISE_ROWS`` rows of every wo (``_pointwise``), and the samples per wall.
    """
    count = len(degrees)
    wos = np.array([direction_at(grid.n, d, rng.uniform(0, 2 * math.pi)) for d in degrees])
    lobe_of_row = rng.permuted(np.tile(np.arange(count), (samples, 1)), axis=1).ravel()
    walls = Walls(rng)
    on_walls = WallSamples.for_rows(walls.count, count * samples)
    observed = np.zeros(count * grid.cells, dtype=np.intp)
    failed, failed_below = np.zeros(count, dtype=np.intp), np.zeros(count, dtype=np.intp)
    weights = _Moments(count)
    pointwise: list[dict[str, np.ndarray]] = []
    start = 0
    for rows in render_calls(rng, count * samples):
        lobe = lobe_of_row[start : start + rows]
        probe = Probe(rng, rows, shuffle=False, walls=walls)
        wo, n, u = probe.send(wos[lobe]), probe.send(grid.n), rng.random((rows, 2))
        keep = kept if start == 0 else None
        start += rows
        wi = call(material, "sample", wo, n, u, shapes=[(rows, 3)], keep=keep).astype(np.float64)
        pdf = call(material, "pdf", wo, wi, n, shapes=[(rows,)], keep=keep).astype(np.float64)
        f = call(material, "eval", wo, wi, n, shapes=[(rows, 3)], keep=keep).astype(np.float64)
        with np.errstate(invalid="ignore"):
            ok = np.isfinite(wi).all(axis=1) & np.isfinite(pdf) & (pdf > 0)
        cos_theta_i = dot(wi, n)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            weight = np.where(ok[:, None], f * (np.abs(cos_theta_i) / np.where(ok, pdf, 1.0))[:, None], 0.0)
        weights.add(lobe, weight)
        # (A failed sample is binned as n, which is finite, and then left out.)
        binned = np.where(ok[:, None], wi, n)
        cells = grid.cell_of(probe.receive(binned))
        observed += np.bincount(lobe[ok] * grid.cells + cells[ok], minlength=count * grid.cells)
        failed += np.bincount(lobe[~ok], minlength=count)
        failed_below += np.bincount(lobe[~ok & (cos_theta_i < 0)], minlength=count)
        on_walls.add(probe.rotations.wall[ok], probe.rotations.to_wall(binned)[ok])
        budget = POINTWISE_ROWS * count - sum(len(p["same"]) for p in pointwise)
        if budget > 0:
            pointwise.append(_pointwise(material, wo, n, u, wi, pdf, f, np.abs(cos_theta_i), budget, keep))
    integrals, errors = _integrals(material, grid, wos, samples, rng)
    lobes = [
        Lobe(
            degrees=d,
            wo=wos[k],
            grid=grid,
            samples=samples,
            observed=observed[k * grid.cells : (k + 1) * grid.cells],
            failed=int(failed[k]),
            failed_below=int(failed_below[k]),
            integrals=integrals[k],
            errors=errors[k],
            estimate=weights.mean[k],
            estimate_sd=weights.sd[k],
        )
        for k, d in enumerate(degrees)
    ]
    return lobes, {key: np.concatenate([p[key] for p in pointwise]) for key in pointwise[0]}, on_walls


@dataclass
class WallSamples:
    """The successful samples of ``measure`` on each wall, binned in the wall's own frame
    (+z its normal, its tangents fixed: ``Rotations.to_wall``) over ``grid``.

    On a wall, each row's wo is turned about the normal by a uniformly random angle of its
    own, so the samples of an isotropic material are spread evenly in azimuth about the
    normal, whatever its lobe: in every band of cos theta, each cell of the band expects an
    equal share of the band's samples. A sampler that draws its azimuth unevenly from a
    tangent frame of its own (a function of n, the same on all of a wall's rows) is uneven
    there, in every render of that wall, while the lobes' histograms, each row turned back
    by its own twist, spread the skew out evenly and cannot see it.
    """

    grid: SphereGrid
    observed: np.ndarray  # (walls, cells)

    @classmethod
    def for_rows(cls, walls: int, rows: int) -> WallSamples:
        """Empty histograms on a grid for the ``rows`` / ``walls`` samples of each wall."""
        grid = SphereGrid.for_samples(Z, rows // walls)
        return cls(grid, np.zeros((walls, grid.cells), dtype=np.intp))

    def add(self, wall: np.ndarray, w: np.ndarray) -> None:
        """Bin the (rows, 3) directions ``w`` (in their walls' frames) of the (rows,) ``wall``."""
        walls, cells = self.observed.shape
        slot = wall * cells + self.grid.cell_of(w)
        self.observed += np.bincount(slot, minlength=walls * cells).reshape(walls, cells)


class _Moments:
    """Mean and standard deviation of (rows, K) values by group, added a batch at a time
    (each batch's own two-pass moments, merged as Chan, Golub and LeVeque do: no
    cancellation when the spread is small against the mean)."""

    def __init__(self, groups: int):
        self.groups = groups
        self.count = np.zeros(groups)
        # (groups, K) once the first batch is added, which sets them as they are.
        self.mean: np.ndarray = np.zeros((groups, 0))
        self.m2: np.ndarray = np.zeros((groups, 0))
        self.empty = True

    def add(self, group: np.ndarray, values: np.ndarray) -> None:
        count = np.bincount(group, minlength=self.groups).astype(np.float64)
        columns = range(values.shape[1])
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = (
                np.column_stack(
                    [np.bincount(group, weights=values[:, c], minlength=self.groups) for c in columns]
                )
                / count[:, None]
            )
            deviation = values - mean[group]
            m2 = np.column_stack(
                [np.bincount(group, weights=deviation[:, c] ** 2, minlength=self.groups) for c in columns]
            )
        if self.empty:
            self.count, self.mean, self.m2, self.empty = count, mean, m2, False
            return
        total = self.count + count
        delta = mean - self.mean
        share = (count / total)[:, None]
        self.mean = self.mean + delta * share
        self.m2 = self.m2 + m2 + delta**2 * (self.count * share.T[0])[:, None]
        self.count = total

    @property
    def sd(self) -> np.ndarray:
        """(groups, K) population standard deviations (numpy's std)."""
        return np.sqrt(self.m2 / self.count[:, None])


def _integrals(
    material, grid: SphereGrid, wos: np.ndarray, samples: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """(L, cells, 4) integrals of pdf and f_rgb |cos theta_i| over every cell for each of
    the (L, 3) ``wos``, and their (L, 4) error bounds. ``SphereGrid.integrate_lobes`` interleaves
    the lobes' points itself, so the rows need no shuffling."""

    def integrand(lobe: np.ndarray, w: np.ndarray) -> np.ndarray:
        pdf, f = _ask_for_lobes(material, ("pdf", "eval"), wos, lobe, w, grid.n, rng)
        values = np.column_stack([pdf, f * np.abs(along(w, grid.n))[:, None]])
        return np.nan_to_num(values, nan=0.0, posinf=0.0, neginf=0.0)

    def tolerance(fine: np.ndarray, area: np.ndarray) -> np.ndarray:
        tol = np.empty_like(fine)
        # Expected counts within 0.02 of their standard deviation (+ 0.005 of a sample).
        tol[:, 0] = (0.02 * np.sqrt(samples * np.maximum(fine[:, 0], 0.0)) + 0.005) / samples
        tol[:, 1:] = F_TOLERANCE * (np.abs(fine[:, 1:]) + (area / (4 * math.pi))[:, None])
        return tol

    return grid.integrate_lobes(integrand, tolerance, len(wos))


def _ask_for_lobes(
    material,
    methods: tuple,
    wos: np.ndarray,
    lobe: np.ndarray,
    w: np.ndarray,
    n: np.ndarray,
    rng: np.random.Generator,
) -> list[np.ndarray]:
    """``ask_at`` for the quadrature's points: (P, 3) directions ``w``, each with the wo of its
    (P,) ``lobe`` (``wos`` (L, 3)), in ``SphereGrid.integrate_lobes``' order, which interleaves
    the lobes. When one lobe is left to refine, each point is asked for another lobe too
    (that answer dropped), so that wo . n still varies over the call's rows."""
    if len(wos) > 1 and (lobe == lobe[0]).all():
        other = (lobe + rng.integers(1, len(wos), len(lobe))) % len(wos)
        answers = _ask_for_lobes(
            material, methods, wos, np.column_stack([lobe, other]).ravel(), np.repeat(w, 2, axis=0), n, rng
        )
        return [a[::2] for a in answers]
    return ask_at(material, methods, wos[lobe], w, n, rng, shuffle=False)


def ask_at(
    material,
    methods: tuple,
    wo: np.ndarray,
    wi: np.ndarray,
    n: np.ndarray,
    rng: np.random.Generator,
    exact: np.ndarray | None = None,
    shuffle: bool = True,
) -> list[np.ndarray]:
    """float64 answers of ``material.<method>(wo, wi, n)`` for each of ``methods`` (``"eval"``,
    ``"pdf"``), in the checks' order of the rows.

    ``wi`` is (rows, 3), ``wo`` and ``n`` (rows, 3) or one (3,), all in the checks' frame;
    the rows go out turned and shuffled (one ``Probe``; rotations ``exact`` where the
    (rows,) mask says), in one call per method.
    """
    rows = len(wi)
    probe = Probe(rng, rows, exact, shuffle)
    sent = probe.send(wo), probe.send(wi), probe.send(n)
    shapes = {"eval": (rows, 3), "pdf": (rows,)}
    return [
        probe.receive_rows(
            np.asarray(call(material, method, *sent, shapes=[shapes[method]]), dtype=np.float64)
        )
        for method in methods
    ]


def _pointwise(
    material, wo, n, u, wi, pdf, f, cos_theta_i, most: int, keep: list | None
) -> dict[str, np.ndarray]:
    """sample_weight on the first rows (``most`` at most), next to sample's wi and f cos / pdf there."""
    k = min(len(u), most)
    keep = None if derives_sample_weight(material) else keep
    first = (rows_of(a, slice(0, k)) for a in (wo, n, u))  # (contiguous, as the renderer's)
    wi_w, weight = call(material, "sample_weight", *first, shapes=[(k, 3), (k, 3)], keep=keep)
    wi_w, weight = wi_w.astype(np.float64), weight.astype(np.float64)
    # Reference at sample_weight's own direction (equal to sample's when all is well).
    same = np.isfinite(wi_w).all(axis=1) & (np.abs(wi_w - wi[:k]).max(axis=1) <= 1e-6)
    pdf_w = np.where(same, pdf[:k], np.nan)
    f_w = np.where(same[:, None], f[:k], np.nan)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        ok = np.isfinite(pdf_w) & (pdf_w > 0)
        reference = np.where(ok[:, None], f_w * (cos_theta_i[:k] / np.where(ok, pdf_w, 1.0))[:, None], 0.0)
    return dict(same=same, weight=weight, reference=reference, cos_theta_i=cos_theta_i[:k], pdf=pdf_w)


# -- chi-square ---------------------------------------------------------------------------


def pooled_chi_square(
    observed: np.ndarray, expected: np.ndarray, min_expected: float = MIN_EXPECTED
) -> tuple[float, int]:
    """Pearson's statistic and degrees of freedom after pooling categories expecting < 5.

    Categories expecting nothing and observing nothing are dropped; those expecting fewer
    than ``min_expected`` are pooled into one, which joins the smallest regular category if
    it still expects fewer. The sums of ``observed`` and ``expected`` may differ (a pdf that
    integrates to more than 1): that is part of what is tested.
    """
    observed, expected = np.asarray(observed, float), np.asarray(expected, float)
    keep = (expected > 0) | (observed > 0)
    small = keep & (expected < min_expected)
    o_cells, e_cells = list(observed[keep & ~small]), list(expected[keep & ~small])
    if small.any():
        pool_o, pool_e = observed[small].sum(), expected[small].sum()
        if pool_e >= min_expected or not e_cells:
            o_cells.append(pool_o)
            e_cells.append(pool_e)
        else:
            smallest = int(np.argmin(e_cells))
            o_cells[smallest] += pool_o
            e_cells[smallest] += pool_e
    o, e = np.array(o_cells), np.array(e_cells)
    if (e <= 0).any():
        return math.inf, max(len(e) - 1, 1)
    return float(((o - e) ** 2 / e).sum()), max(len(e) - 1, 1)


def chi_square_p(lobe: Lobe) -> tuple[float, int, float]:
    """The chi-square statistic, dof and p-value of one wo (failed samples a category)."""
    n = lobe.samples
    observed = np.append(lobe.observed, lobe.failed)
    expected = np.append(n * lobe.integrals[:, 0], n * max(0.0, 1.0 - lobe.pdf_integral))
    statistic, dof = pooled_chi_square(observed, expected)
    return statistic, dof, chi2_sf(statistic, dof)


def wall_chi_square(observed: np.ndarray, grid: SphereGrid) -> tuple[float, int, float]:
    """Pearson's statistic, dof and p-value of one wall's samples (``WallSamples``) against
    an even spread in azimuth: in each band of cos theta holding at least ``MIN_EXPECTED``
    samples per cell, every cell expects the band's mean. Given the bands' totals the cells
    of a band are multinomial, so the statistic has (cells per band - 1) degrees of freedom
    per band tested."""
    bands = observed.reshape(grid.n_cos, grid.n_phi).astype(np.float64)
    totals = bands.sum(axis=1)
    tested = totals >= MIN_EXPECTED * grid.n_phi
    if not tested.any():
        return 0.0, 0, 1.0
    expected = totals[tested, None] / grid.n_phi
    statistic = float(((bands[tested] - expected) ** 2 / expected).sum())
    dof = int(tested.sum()) * (grid.n_phi - 1)
    return statistic, dof, chi2_sf(statistic, dof)


def check_chi_square(material, lobes: list[Lobe], walls: WallSamples, rng: np.random.Generator) -> Check:
    """One test per wo (its samples in the grid's frame against pdf's integrals) and one per
    wall (its samples in its own frame, even in azimuth: ``wall_chi_square``), Šidák over
    all of them at ``ALPHA_CHI_SQUARE``."""
    threshold = sidak(ALPHA_CHI_SQUARE, len(lobes) + len(walls.observed))
    results = [chi_square_p(lobe) for lobe in lobes]
    on_walls = [wall_chi_square(observed, walls.grid) for observed in walls.observed]
    worst = int(np.argmin([p for _, _, p in results]))
    statistic, dof, p = results[worst]
    where = f"wo {lobes[worst].degrees:g}°"
    worst_wall = int(np.argmin([p for _, _, p in on_walls]))
    if on_walls[worst_wall][2] < p:
        statistic, dof, p = on_walls[worst_wall]
        where = f"wall {worst_wall + 1} of {len(on_walls)}"
    passed = p >= threshold
    shape = (walls.grid.n_cos, walls.grid.n_phi)
    data = dict(
        p=p,
        threshold=threshold,
        lobes=[
            dict(
                degrees=lobe.degrees,
                observed=lobe.observed,
                expected=lobe.samples * lobe.integrals[:, 0],
                shape=(lobe.grid.n_cos, lobe.grid.n_phi),
                p=r[2],
            )
            for lobe, r in zip(lobes, results, strict=True)
        ],
        walls=[
            dict(
                wall=k + 1,
                observed=observed,
                expected=np.repeat(observed.reshape(shape).mean(axis=1), shape[1]),
                shape=shape,
                p=r[2],
            )
            for k, (observed, r) in enumerate(zip(walls.observed, on_walls, strict=True))
            if r[2] < threshold
        ],
    )
    hint = ""
    if not passed:
        if min(r[2] for r in results) < threshold:
            hint = explain_chi_square(material, lobes, threshold, rng)
        else:
            hint = uneven_azimuth(on_walls[worst_wall][2], len(on_walls))
    return Check(
        "chi-square",
        verdict(passed),
        f"min p = {p:.3g} ({where}: X² = {statistic:.4g}, dof {dof})",
        f"p >= {threshold:.2g} (Šidák, 1e-3 over {len(lobes)} wo and {len(on_walls)} walls)",
        hint,
        data=data,
    )


def uneven_azimuth(p: float, walls: int) -> str:
    """The hint for samples uneven in azimuth about a wall's normal, whose angles to the
    normal (and to wo) follow pdf."""
    return (
        f"on a wall (one normal on many rows, as in a render: {walls} of them, each wo turned "
        f"about n at random), the samples' azimuth about n is uneven (p = {p:.2g}), though their "
        "angles follow pdf: sample draws phi unevenly in its tangent frame, which a render of a "
        "wall keeps fixed (phi = 2 pi u1 is even; a square, a square root or a missing 2 pi "
        "of u1 is not)"
    )


#: Mistake models: the samples follow pdf * g(wi) instead of pdf. Each entry: the model's
#: name and the hint when the samples fit it.
CANDIDATES = {
    "constant": "the samples follow the shape of pdf, but pdf is {factor:.3g}x too {size}: a wrong "
    "constant (1/pi, 1/(2 pi), 1/(4 pi)?)",
    "cos": "pdf misses a factor cos(theta_i) that the sampling has (the samples are cosine-"
    "weighted, the pdf is not): pdf is about 2x too small near the normal. Did you use "
    "1/(2 pi) while sampling cosine-weighted, or forget the cosine in cos(theta)/pi?",
    "1/cos": "pdf has a factor cos(theta_i) that the sampling lacks: a cosine pdf for uniform "
    "sampling? (uniform hemisphere sampling has pdf 1/(2 pi))",
    "jacobian": "pdf is the density of the half vector h, not of wi: it misses the Jacobian "
    "1 / (4 |wo . h|) of the reflection (pdf(wi) = pdf(h) / (4 |wo . h|))",
}


def explain_chi_square(material, lobes: list[Lobe], threshold: float, rng: np.random.Generator) -> str:
    """A hint for a failed chi-square: which mistake the samples' distribution points to.

    In order: most samples failing below the surface (the wrong hemisphere); the samples
    fitting pdf * g for one of the ``CANDIDATES`` (Pearson's test on the successful samples
    against pdf * g normalised to their number); more failed samples than pdf admits; fewer
    (a sample that should have failed was turned into another direction).
    """
    unexplained_failures, missing_failures = [], []
    for lobe in lobes:
        n = lobe.samples
        expected_failed = n * max(0.0, 1.0 - lobe.pdf_integral)
        slack = 5 * math.sqrt(expected_failed + 1) + 0.001 * n
        if (
            lobe.failed > expected_failed + slack and lobe.pdf_integral <= 1.01
        ):  # (a pdf too large says nothing of failures)
            unexplained_failures.append((lobe, expected_failed / n))
        elif lobe.failed < expected_failed - slack:
            missing_failures.append((lobe, expected_failed / n))
    for lobe, expected in unexplained_failures:
        if lobe.failed > 0.5 * lobe.samples and lobe.failed_below > 0.9 * lobe.failed:
            return (
                f"{lobe.failed / lobe.samples:.1%} of the samples at wo {lobe.degrees:g}° land below the "
                f"surface, where pdf is 0 (expected {expected:.1%}): sample returns directions in the "
                "wrong hemisphere (local z not mapped to n, or a flipped sign?)"
            )
    best, best_p = _best_candidate(material, lobes, rng)
    if best_p >= threshold / 10:
        factor = float(
            np.mean([lobe.pdf_integral / max(1e-300, 1 - lobe.failed / lobe.samples) for lobe in lobes])
        )
        if best != "constant":
            return CANDIDATES[best]
        if abs(factor - 1) > 1e-3:
            return CANDIDATES[best].format(
                factor=factor if factor > 1 else 1 / factor, size="large" if factor > 1 else "small"
            )
    if unexplained_failures:
        lobe, expected = unexplained_failures[0]
        return (
            f"{lobe.failed / lobe.samples:.1%} of the samples at wo {lobe.degrees:g}° land where pdf "
            f"is 0 "
            f"(expected {expected:.1%}): pdf returns 0 where sample goes (do pdf's conditions match "
            "the sampler?)"
        )
    if missing_failures:
        lobe, expected = missing_failures[0]
        return fails_too_rarely(lobe.failed / lobe.samples, expected, lobe.degrees)
    return (
        "the samples' histogram does not follow pdf (see --plots): sample and pdf describe "
        "different distributions (a wrong warp, the pdf of another sampling, a missing Jacobian?)"
    )


def _best_candidate(material, lobes: list[Lobe], rng: np.random.Generator) -> tuple[str, float]:
    """The name of the ``CANDIDATES`` mistake that the successful samples fit best, and its
    p-value: the least, over the lobes, of Pearson's test against pdf * g."""
    best, best_p = "", -1.0
    models = _candidate_integrals(material, lobes, rng)
    for name in CANDIDATES:
        p_min = 1.0
        for lobe, model in zip(lobes, models, strict=True):
            m = model[name]
            successes = lobe.samples - lobe.failed
            if successes == 0 or not np.isfinite(m).all() or m.sum() <= 0:
                p_min = 0.0
                break
            statistic, dof = pooled_chi_square(lobe.observed, successes * m / m.sum())
            p_min = min(p_min, chi2_sf(statistic, dof))
        if p_min > best_p:
            best, best_p = name, p_min
    return best, best_p


def _candidate_integrals(material, lobes: list[Lobe], rng: np.random.Generator) -> list[dict]:
    """For each lobe, (cells,) integrals of pdf * g for each mistake model g."""
    grid, samples = lobes[0].grid, lobes[0].samples
    wos = np.array([lobe.wo for lobe in lobes])

    def integrand(lobe: np.ndarray, w: np.ndarray) -> np.ndarray:
        wo = wos[lobe]
        (pdf,) = _ask_for_lobes(material, ("pdf",), wos, lobe, w, grid.n, rng)
        pdf = np.nan_to_num(pdf, nan=0.0, posinf=0.0, neginf=0.0)
        cos_theta_i = np.maximum(np.abs(along(w, grid.n)), 1e-3)
        wo_dot_h = np.maximum(np.abs(dot(normalize(w + wo), wo)), 1e-3)
        return np.column_stack([pdf, pdf * cos_theta_i, pdf / cos_theta_i, pdf / (4 * wo_dot_h)])

    def tolerance(fine, area):
        return (0.05 * np.sqrt(samples * np.maximum(fine, 0)) + 0.01) / samples

    integrals, _ = grid.integrate_lobes(integrand, tolerance, len(lobes), max_levels=5)
    return [dict(zip(CANDIDATES, model.T, strict=True)) for model in integrals]


# -- normalisation, energy, estimator -----------------------------------------------------


def check_normalisation(lobes: list[Lobe]) -> Check:
    z = z_two_sided(sidak(ALPHA_NORMALISATION, len(lobes)))
    worst: Lobe | None = None
    worst_ratio, text = -1.0, ""
    for lobe in lobes:
        success = 1.0 - lobe.failed / lobe.samples
        allowed = z * math.sqrt(success * (1 - success) / lobe.samples) + 2 * lobe.errors[0] + 1e-6
        ratio = abs(lobe.pdf_integral - success) / allowed
        if ratio > worst_ratio:
            worst, worst_ratio = lobe, ratio
            text = (
                f"∫pdf = {lobe.pdf_integral:.5g}, {lobe.failed / lobe.samples:.3%} failed "
                f"(wo {lobe.degrees:g}°)"
            )
    passed = worst_ratio <= 1
    hint = ""
    if not passed and worst is not None:  # (a ratio above 1 set worst)
        integral, success = worst.pdf_integral, 1.0 - worst.failed / worst.samples
        if integral > 1 + 1e-3:
            hint = (
                f"pdf integrates to {integral:.3g} > 1 at wo {worst.degrees:g}°: pdf is too large "
                f"(by {integral:.3g}x if by a constant: check its normalisation; a missing Jacobian?)"
            )
        elif integral < success:
            factor = success / max(integral, 1e-300)
            if any(abs(factor / simple - 1) < 0.02 for simple in SIMPLE_FACTORS):
                hint = (
                    f"pdf integrates to {integral:.3g} but {success:.1%} of the samples succeed: "
                    f"pdf is about {factor:.3g}x too small (e.g. 1/(2 pi) where 1/pi belongs)"
                )
            else:
                hint = (
                    fails_too_rarely(1 - success, 1 - integral, worst.degrees)
                    + f" (or else pdf is {factor:.3g}x too small)"
                )
        else:
            hint = (
                f"sample fails ({1 - success:.1%}) more often than pdf admits "
                f"(1 - ∫pdf = {1 - integral:.1%}): samples land where pdf is 0"
            )
    return Check(
        "pdf normalisation",
        verdict(passed),
        text,
        f"|∫pdf - (1 - failed)| <= {z:.1f} σ + quadrature error",
        hint,
    )


#: Factors by which a pdf written with the wrong constant is off: 2 (hemisphere against
#: sphere, or cos / (2 pi)), pi, 4, 2 pi, 4 pi.
SIMPLE_FACTORS = (2.0, math.pi, 4.0, 2 * math.pi, 4 * math.pi)


def fails_too_rarely(failed: float, expected: float, degrees: float) -> str:
    """The hint for a sampler that fails less often than its pdf admits: it turns a sample
    that should fail into another direction, most often by flipping it back above the
    surface, which gives those directions a density pdf knows nothing of."""
    return (
        f"pdf integrates to {1 - expected:.3g} at wo {degrees:g}°, so {expected:.1%} of the "
        f"samples should fail (land where pdf is 0), but {failed:.1%} do: sample turns a "
        f"failed sample into another direction. Did it flip a wi that landed below the "
        f"surface back up? Let such a sample fail: return it as it is (pdf 0 there)"
    )


def check_energy(lobes: list[Lobe]) -> Check:
    margins = [lobe.reflectance.max() - 1.0 - ENERGY_SLACK - 2 * lobe.errors[1:].max() for lobe in lobes]
    worst = lobes[int(np.argmax(margins))]
    channel = int(np.argmax(worst.reflectance))
    value = float(worst.reflectance[channel])
    passed = max(margins) <= 0
    hint = ""
    if not passed:
        hint = (
            f"∫ f cos = {value:.3g} > 1 at wo {worst.degrees:g}°: the material reflects more light "
            "than it receives: an albedo or F0 above 1, or a factor missing from f_r"
        )
        by_angle = sorted(lobes, key=lambda lobe: lobe.degrees)
        grows = len(lobes) > 1 and worst is by_angle[-1]
        grows &= float(by_angle[-1].reflectance.max()) > 1.05 * float(by_angle[0].reflectance.max())
        if grows:  # (a Lambertian's is the same at every wo)
            hint += (
                " (it grows toward grazing wo: a missing masking term G, a wrong 4 cos cos "
                "denominator, or a Fresnel term above 1?)"
            )
        elif value / math.pi <= 1 + ENERGY_SLACK:
            hint += f" (if the albedo is {value / math.pi:.3g}: f_r = albedo without the 1/pi)"
    return Check(
        "energy",
        verdict(passed),
        f"max ∫ f cos = {value:.4f} (wo {worst.degrees:g}°, {'rgb'[channel]})",
        f"<= 1 + {ENERGY_SLACK:g} + quadrature error",
        hint,
    )


def check_estimator(lobes: list[Lobe]) -> Check:
    z = z_two_sided(sidak(ALPHA_ESTIMATOR, 3 * len(lobes)))
    worst_ratio, worst = -1.0, None
    for lobe in lobes:
        reference = lobe.reflectance
        allowed = (
            z * lobe.estimate_sd / math.sqrt(lobe.samples)
            + 2 * lobe.errors[1:]
            + 1e-9
            + FLOAT32_SLACK * np.abs(reference)
        )
        with np.errstate(invalid="ignore"):
            ratio = np.abs(lobe.estimate - reference) / allowed
        ratio = np.where(np.isfinite(ratio), ratio, np.inf)
        c = int(np.argmax(ratio))
        if ratio[c] > worst_ratio:
            worst_ratio, worst = float(ratio[c]), (lobe, c)
    if worst is None:  # (every wo sets it: its ratios are >= 0)
        raise ValueError("no wo's to check the estimator at")
    lobe, c = worst
    passed = worst_ratio <= 1
    hint = ""
    if not passed:
        estimate, reference = lobe.estimate[c], lobe.reflectance[c]
        unreached = float(lobe.integrals[lobe.integrals[:, 0] <= 0, 1 + c].sum())
        if unreached > 0.01 * max(reference, 1e-12):
            hint = (
                f"eval is nonzero where pdf is 0 ({unreached / reference:.1%} of ∫ f cos at wo "
                f"{lobe.degrees:g}°): sample never goes there, so the estimate misses that light"
            )
        else:
            ratio = estimate / reference if reference else math.inf
            hint = (
                f"the importance-sampled estimate mean(f cos / pdf) = {estimate:.6g} but ∫ f cos = "
                f"{reference:.6g} at wo {lobe.degrees:g}° (ratio {_ratio_text(ratio)}): "
                "sample and pdf disagree (see chi-square)"
            )
    return Check(
        "estimator agreement",
        verdict(passed),
        f"max |IS - ∫| / allowed = {worst_ratio:.3g} (wo {lobe.degrees:g}°, {'rgb'[c]})",
        f"<= 1 (allowed {z:.1f} σ + quadrature error)",
        hint,
    )


#: A (non-delta) material's ``sample`` may fail (pdf 0, or below the surface) on at most this
#: share of its u at any wo: a sampler that fails on (nearly) every u gives the renderer no
#: direction to follow. The largest share of a right sampler measured: 0.50 (GGX alpha 1,
#: reflected half vectors, Walter's sampling or visible normals at wo 0); exact, not a
#: statistic (10^5 samples: a share's standard error is 0.0016).
MAX_FAILED_SHARE = 0.9
#: A material whose integral of f |cos| is at most this (every channel, every wo) reflects
#: nothing.
BLACK = 1e-6


def check_reflectance(lobes: list[Lobe]) -> Check:
    """Does ``sample`` give directions, and does the material reflect anything at all?

    FAIL when ``sample`` fails (pdf 0 or no finite direction) on more than
    ``MAX_FAILED_SHARE`` of the samples of some wo: every other check can hold for a sampler
    that never gives a direction (the chi-square expects every sample to fail, the
    estimator sees 0 = 0). A warning (``warn``, which does not fail the report) when the
    integral of f |cos| is at most ``BLACK`` at every wo: a black material is consistent,
    and a light's or a black body's material may be so, but it is said, not a silent pass.
    Deterministic.
    """
    shares = [lobe.failed / lobe.samples for lobe in lobes]
    worst = int(np.argmax(shares))
    albedo = np.array([lobe.reflectance for lobe in lobes])
    where = f"wo {lobes[worst].degrees:g}°"
    statistic = f"max ∫ f cos = {albedo.max():.4g}, max failed share {shares[worst]:.1%} ({where})"
    threshold = f"failed share <= {MAX_FAILED_SHARE:.0%}, ∫ f cos > {BLACK:g}"
    if shares[worst] > MAX_FAILED_SHARE:
        lobe = lobes[worst]
        where = "below the surface" if lobe.failed_below > 0.5 * lobe.failed else "where pdf is 0"
        hint = (
            f"sample returns no direction with a positive pdf: {shares[worst]:.1%} of the samples at wo "
            f"{lobe.degrees:g}° fail (most {where}); sample must turn u into directions above the "
            "surface that pdf gives a density > 0"
        )
        return Check("reflectance", "FAIL", statistic, threshold, hint)
    if not albedo.max() > BLACK:
        hint = (
            "reflects nothing: albedo 0 for every probe (∫ f cos = 0 at every wo): eval is 0 "
            "everywhere, so the surface is black (consistent, but is that what you meant?)"
        )
        return Check("reflectance", "warn", statistic, threshold, hint)
    return Check("reflectance", "pass", statistic, threshold)


def _ratio_text(ratio: float) -> str:
    """``1.5``, or ``1 - 3.2e-05`` for a ratio too close to 1 to show as a number."""
    if math.isfinite(ratio) and abs(ratio - 1) < 1e-3:
        return f"1 {'+' if ratio >= 1 else '-'} {abs(ratio - 1):.2g}"
    return f"{ratio:.3g}"


# -- sample_weight ------------------------------------------------------------------------


def check_sample_weight(pointwise: dict) -> Check:
    """sample_weight against (sample, f cos / pdf) on the rows ``measure`` compared (``_pointwise``)."""
    same, weight, reference, cos_theta_i = (
        pointwise[key] for key in ("same", "weight", "reference", "cos_theta_i")
    )
    rows = len(same)
    finite = np.isfinite(weight).all(axis=1)
    scale = np.abs(reference[same]).max(initial=0.0) if same.any() else 0.0
    with np.errstate(invalid="ignore"):
        bad = same & ~(
            np.abs(weight - reference) <= SAMPLE_WEIGHT_RTOL * np.abs(reference) + 1e-12 * (1 + scale)
        ).all(axis=1)
    problems = int((~same).sum() + (~finite).sum() + bad.sum())
    passed = problems == 0
    hint = ""
    if not passed:
        if (~finite).any():
            hint = (
                f"sample_weight returns NaN or inf in {(~finite).sum()} rows: where pdf is 0 the weight "
                "must be 0"
            )
        elif (~same).any():
            hint = (
                f"sample_weight's direction differs from sample's for the same u in {(~same).sum()} "
                "of {rows} rows: it must return the wi that sample returns"
            ).replace("{rows}", str(rows))
        else:
            hint = _explain_weight(weight[bad], reference[bad], cos_theta_i[bad])
    return Check(
        "sample_weight",
        verdict(passed),
        f"{problems} of {rows} rows differ from (sample, f cos / pdf)",
        f"0 (relative {SAMPLE_WEIGHT_RTOL:g})",
        hint,
    )


def _explain_weight(weight: np.ndarray, reference: np.ndarray, cos_theta_i: np.ndarray) -> str:
    """Name the factor by which sample_weight's weight differs from f cos / pdf."""
    w, r = weight.sum(axis=1), reference.sum(axis=1)
    if ((w > 0) & (r == 0)).mean() > 0.5:
        return "sample_weight is nonzero where pdf is 0: a failed sample must weigh 0"
    if ((w == 0) & (r > 0)).mean() > 0.5:
        return "sample_weight returns 0 where f cos / pdf is positive"
    both = (w > 0) & (r > 0) & (cos_theta_i > 0)
    if both.sum() >= 2:
        log_ratio = np.log(w[both] / r[both])
        log_cos = np.log(cos_theta_i[both])
        spreads = {k: np.ptp(log_ratio - k * log_cos) for k in (0, -1, 1)}
        k = min(spreads, key=lambda power: spreads[power])
        if spreads[k] < 1e-3:
            if k == -1:
                return (
                    "sample_weight misses the factor cos(theta_i): it returns f / pdf instead of f cos / pdf"
                )
            if k == 1:
                return "sample_weight multiplies by cos(theta_i) twice (f cos^2 / pdf)"
            factor = math.exp(float(np.median(log_ratio)))
            return f"sample_weight is {factor:.3g}x f cos / pdf (a constant factor: 1/pi or 2 pi somewhere?)"
    return "sample_weight differs from eval(wo, wi) cos(theta_i) / pdf(wo, wi): it must equal it"


# -- reciprocity --------------------------------------------------------------------------


def check_reciprocity(material, rng: np.random.Generator, rows: int = 20_000) -> Check:
    n = normalize(rng.normal(size=(rows, 3)))
    cosines = rng.random((rows, 2))
    cosines[: rows // 10] = rng.choice([1e-6, 1e-3, 0.01, 1.0], size=(rows // 10, 2))
    frames = []
    for k in range(2):
        phi = rng.uniform(0, 2 * math.pi, rows)
        sin = np.sqrt(1 - cosines[:, k] ** 2)
        frames.append(to_world(vec3(sin * np.cos(phi), sin * np.sin(phi), cosines[:, k]), n))
    wo, wi = frames
    forward = call(material, "eval", wo, wi, n, shapes=[(rows, 3)])
    tolerance = RECIPROCITY_RTOL_FLOAT32 if forward.dtype == np.float32 else RECIPROCITY_RTOL
    forward = forward.astype(np.float64)
    backward = call(material, "eval", wi, wo, n, shapes=[(rows, 3)]).astype(np.float64)
    finite = np.isfinite(forward).all(axis=1) & np.isfinite(backward).all(axis=1)
    scale = max(np.abs(forward[finite]).max(initial=0), np.abs(backward[finite]).max(initial=0))
    larger = np.maximum(np.maximum(np.abs(forward), np.abs(backward)), 1e-12 * (1 + scale))
    with np.errstate(invalid="ignore"):
        relative = (np.abs(forward - backward) / larger).max(axis=1)
    worst = float(relative[finite].max(initial=0.0))
    passed = bool(finite.all()) and worst <= tolerance
    hint = ""
    if not finite.all():
        hint = "eval returns NaN or inf for directions above the surface (see consistency)"
    elif not passed:
        hint = _explain_reciprocity(forward, backward, dot(wo, n), dot(wi, n))
    return Check(
        "reciprocity",
        verdict(passed),
        f"max |f(wo,wi) - f(wi,wo)| / f = {worst:.2g} ({rows} pairs)",
        f"<= {tolerance:g}",
        hint,
    )


def _explain_reciprocity(forward, backward, cos_theta_o, cos_theta_i) -> str:
    f, b = forward.sum(axis=1), backward.sum(axis=1)
    both = (f > 0) & (b > 0)
    if both.sum() >= 2:
        log_ratio = np.log(f[both] / b[both])
        log_cos = np.log(cos_theta_i[both] / cos_theta_o[both])
        for k, text in (
            (
                1,
                "eval includes cos(theta_i), and the renderer multiplies by it again "
                "(the cosine counted twice); a microfacet denominator 4 cos(theta_o) "
                "without cos(theta_i) does the same",
            ),
            (
                -1,
                "eval is divided by cos(theta_i) (or multiplied by cos(theta_o)): "
                "a cosine missing from the 4 cos(theta_o) cos(theta_i) denominator?",
            ),
        ):
            if np.abs(log_ratio - k * log_cos).max() < 1e-6:
                return text
    return (
        "eval(wo, wi) != eval(wi, wo): a term depends on wo or wi alone (Fresnel at n . wo instead "
        "of h . wo? G1(wo) instead of G2(wo, wi)?)"
    )


# -- consistency --------------------------------------------------------------------------


#: Directions (local frame, +z = n) at which consistency probes eval and pdf, by name.
def _probe_directions(wo_local: np.ndarray) -> dict[str, np.ndarray]:
    mirror = np.array([-wo_local[0], -wo_local[1], wo_local[2]])
    return {
        "n": np.array([0.0, 0, 1]),
        "-n": np.array([0.0, 0, -1]),
        "tangent": np.array([1.0, 0, 0]),
        "tangent (other)": np.array([0.0, 1, 0]),
        "1e-8 above": np.array([math.sqrt(1 - 1e-16), 0, 1e-8]),
        "1e-8 below": np.array([0.0, math.sqrt(1 - 1e-16), -1e-8]),
        "wo": wo_local,
        "-wo": -wo_local,
        "mirror of wo": mirror,
    }


_WO_PROBES = {
    "0°": 0.0,
    "30°": 30.0,
    "60°": 60.0,
    "85°": 85.0,
    "89.9°": 89.9,
    "90° (grazing)": 90.0,
    "95° (below)": 95.0,
    "180° (below)": 180.0,
}
#: The local frame's normal.
Z = np.array([0.0, 0.0, 1.0])
#: Random directions (eval, pdf) and values of u (sample) per wo, besides the named ones.
CONSISTENCY_RANDOM_ROWS = 64


def _wo_local(degrees: float) -> np.ndarray:
    """(3,) wo at ``degrees`` from +z in the x-z plane; exactly (1, 0, 0) at 90."""
    if degrees == 90.0:
        return np.array([1.0, 0.0, 0.0])
    return np.array([math.sin(math.radians(degrees)), 0.0, math.cos(math.radians(degrees))])


def _twice(rows: int, *arrays: np.ndarray) -> tuple[np.ndarray, ...]:
    """``arrays`` (rows, ...) repeated, and the (2 rows,) mask of the first copy: consistency
    sends every probe twice, once turned by an exact rotation (cosines to n kept exactly:
    exactly tangent stays so) and once by a uniformly random one."""
    return (np.arange(2 * rows) < rows, *(np.concatenate([a, a]) for a in arrays))


def check_consistency(material, rng: np.random.Generator) -> Check:
    """Nothing NaN, eval and pdf >= 0 and 0 below the surface, unit samples, at edge cases.

    Every wo of ``_WO_PROBES`` with every named direction, random directions and edge
    values of u, all shuffled into one call per method (``ptlab.grading.probes``).
    """
    at_directions = _look_at_directions(material, rng)
    at_samples = _look_at_samples(material, rng)
    problems = [problem for name in _WO_PROBES for problem in at_directions[name] + at_samples[name]]
    unique = list(dict.fromkeys(problems))
    hint = ""
    if unique:
        hint = unique[0] + (f" (and {len(unique) - 1} more problems)" if len(unique) > 1 else "")
        hint += _consistency_advice(unique[0])
    return Check(
        "consistency", verdict(not unique), f"{len(unique)} problems", "0 (grazing, ±n, below, edge u)", hint
    )


def _look_at_directions(material, rng: np.random.Generator) -> dict[str, list[str]]:
    """The problems of eval and pdf at the named and random directions, for each wo's name."""
    wo_blocks: list[np.ndarray] = []
    wi_blocks: list[np.ndarray] = []
    wo_name_list: list[str] = []
    wi_name_list: list[str] = []
    for wo_name, degrees in _WO_PROBES.items():
        wo_local = _wo_local(degrees)
        probes = _probe_directions(wo_local)
        random_wi = normalize(rng.normal(size=(CONSISTENCY_RANDOM_ROWS, 3)))
        wi_blocks += [np.vstack(list(probes.values())), random_wi]
        names = list(probes) + ["random"] * CONSISTENCY_RANDOM_ROWS
        wi_name_list += names
        wo_name_list += [wo_name] * len(names)
        wo_blocks.append(np.tile(wo_local, (len(names), 1)))
    exact, wo, wi, wo_names, wi_names = _twice(
        len(wo_name_list),
        np.vstack(wo_blocks),
        np.vstack(wi_blocks),
        np.array(wo_name_list),
        np.array(wi_name_list),
    )
    f, pdf = ask_at(material, ("eval", "pdf"), wo, wi, Z, rng, exact)
    below = (wi[:, 2] < -1e-6) | (wo[:, 2] < -1e-6)
    problems: dict[str, list[str]] = {}
    for wo_name in _WO_PROBES:
        rows = wo_names == wo_name
        problems[wo_name] = []
        for method, values in (("eval", f), ("pdf", pdf[:, None])):
            _look(problems[wo_name], method, values[rows], wi_names[rows], wo_name, below[rows])
    return problems


def _look_at_samples(material, rng: np.random.Generator) -> dict[str, list[str]]:
    """The problems of sample (and pdf there) and sample_weight at edge and random u, for each
    wo's name."""
    u_edges = np.array([0.0, 0.5, ONE_MINUS_EPSILON, largest_below_one(np.float64)])
    edges = np.array(np.meshgrid(u_edges, u_edges)).reshape(2, -1).T
    per_wo = CONSISTENCY_RANDOM_ROWS
    u = np.vstack([np.concatenate([edges, rng.random((per_wo - len(edges), 2))]) for _ in _WO_PROBES])
    wo = np.repeat(np.array([_wo_local(d) for d in _WO_PROBES.values()]), per_wo, axis=0)
    exact, wo, u, wo_names = _twice(len(u), wo, u, np.repeat(list(_WO_PROBES), per_wo))
    rows = len(u)
    probe = Probe(rng, rows, exact)
    wo_s, n_s, u_s = probe.send(wo), probe.send(Z), probe.send_rows(u)
    wi_s = call(material, "sample", wo_s, n_s, u_s, shapes=[(rows, 3)]).astype(np.float64)
    finite = np.isfinite(wi_s).all(axis=1)
    unit = finite & (np.abs(np.linalg.norm(np.where(finite[:, None], wi_s, 0), axis=1) - 1) <= 1e-6)
    pdf_finite = np.ones(rows, dtype=bool)
    if unit.any():
        good = np.flatnonzero(unit)
        pdf_s = call(material, "pdf", *(rows_of(a, good) for a in (wo_s, wi_s, n_s)), shapes=[(len(good),)])
        pdf_finite[good] = np.isfinite(pdf_s)
    _, weight = call(material, "sample_weight", wo_s, n_s, u_s, shapes=[(rows, 3), (rows, 3)])
    weight = np.asarray(weight, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        weight_finite = np.isfinite(weight).all(axis=1)
        negative = (weight < -NEGATIVE_ROUNDING).any(axis=1)
        nonzero = (weight != 0).any(axis=1)
    length = np.linalg.norm(wi_s, axis=1)
    # (asarray: NumPy's stubs type a reduction along an axis as perhaps a scalar.)
    finite, unit, pdf_finite, weight_finite, negative, nonzero, length = (
        probe.receive_rows(np.asarray(a))
        for a in (finite, unit, pdf_finite, weight_finite, negative, nonzero, length)
    )
    problems: dict[str, list[str]] = {}
    for wo_name, degrees in _WO_PROBES.items():
        rows = wo_names == wo_name
        found = problems[wo_name] = []
        if not finite[rows].all():
            found.append(f"sample returns NaN or inf for wo at {wo_name}")
        elif not unit[rows].all():
            worst = length[rows][np.argmax(np.abs(length[rows] - 1))]
            found.append(f"sample returns vectors of length {worst:.6g} for wo at {wo_name}: normalise them")
        elif not pdf_finite[rows].all():
            found.append(f"pdf is NaN or inf at a sampled direction for wo at {wo_name}")
        if not weight_finite[rows].all():
            found.append(f"sample_weight returns NaN or inf for wo at {wo_name}")
        elif negative[rows].any():
            found.append(f"sample_weight is negative for wo at {wo_name}")
        elif degrees > 90 and nonzero[rows].any():
            found.append(
                f"sample_weight is not 0 for wo at {wo_name}: a reflective material "
                "scatters nothing from below"
            )
    return problems


def _look(
    problems: list[str], method: str, values: np.ndarray, names: np.ndarray, wo_name: str, below: np.ndarray
) -> None:
    """Record where ``values`` (rows, K) are non-finite, negative, or nonzero below the surface
    (``names`` (rows,) the name of each row's wi)."""
    for test, text in (
        (~np.isfinite(values).all(axis=1), "NaN or inf"),
        ((values < -NEGATIVE_ROUNDING).any(axis=1), "negative"),
        (below & (values != 0).any(axis=1), "not 0 below the surface"),
    ):
        with np.errstate(invalid="ignore"):
            hit = np.flatnonzero(test)
        if len(hit):
            problems.append(f"{method} is {text} for wo at {wo_name}, wi = {names[hit[0]]}")


def _consistency_advice(problem: str) -> str:
    if "NaN" in problem:
        return (
            ": NaN at grazing angles or at wi = ±n? Guard divisions by cos(theta) (and "
            "tan(theta) = sin / cos) with np.where or a clamp"
        )
    if "below the surface" in problem:
        return ": a reflective material returns 0 when wo or wi is below the surface (test cos > 0)"
    if "negative" in problem:
        return ": BRDF values and densities are never negative (a cosine not clamped at 0?)"
    return ""


# -- float32 ------------------------------------------------------------------------------


def check_float32(material, rng: np.random.Generator, rows: int = 4096, kept: list | None = None) -> Check:
    """The renderer's float32, column-major arrays give finite results close to float64's.

    ``kept`` receives the first rows of the float32 calls.
    """
    n = normalize(rng.normal(size=(rows, 3)))
    cos_o = rng.uniform(0.05, 1.0, rows)
    phi = rng.uniform(0, 2 * math.pi, rows)
    sin_o = np.sqrt(1 - cos_o**2)
    wo = to_world(vec3(sin_o * np.cos(phi), sin_o * np.sin(phi), cos_o), n)
    wi = normalize(rng.normal(size=(rows, 3)))
    u = rng.random((rows, 2))
    single = [np.asfortranarray(a.astype(np.float32)) for a in (wo, wi, n, u)]
    results = {}
    for name, arrays, keep in (("float64", (wo, wi, n, u), None), ("float32", single, kept)):
        wo_, wi_, n_, u_ = arrays
        results[name] = dict(
            eval=call(material, "eval", wo_, wi_, n_, shapes=[(rows, 3)], keep=keep),
            pdf=call(material, "pdf", wo_, wi_, n_, shapes=[(rows,)], keep=keep),
            sample=call(material, "sample", wo_, n_, u_, shapes=[(rows, 3)], keep=keep),
        )
    worst, where, promoted = 0.0, "", []
    for method in ("eval", "pdf", "sample"):
        a64 = np.asarray(results["float64"][method], dtype=np.float64)
        a32 = results["float32"][method]
        if a32.dtype != np.float32:
            promoted.append(method)
        a32 = a32.astype(np.float64)
        if not np.isfinite(a32).all():
            return Check(
                "float32",
                "FAIL",
                f"{method} gives NaN or inf for float32 input",
                "finite",
                f"{method} is not finite with float32 arrays (an overflow, or 1 - x*x < 0 from rounding?)",
            )
        scale = np.abs(a64).max(initial=0) if method != "sample" else 1.0
        with np.errstate(invalid="ignore", divide="ignore"):
            error = np.abs(a32 - a64) / (np.abs(a64) + 1e-3 * scale + 1e-30)
        if method == "sample":
            error = np.abs(a32 - a64)
        if np.nanmax(error, initial=0) > worst:
            worst, where = float(np.nanmax(error)), method
    if worst > 1e-2:
        return Check(
            "float32",
            "FAIL",
            f"max relative difference {worst:.2g} ({where})",
            "<= 0.01",
            f"{where} with float32 input differs from float64: precision lost to cancellation "
            "(e.g. 1 - cos for small angles) or a float32 parameter?",
        )
    if promoted:
        return Check(
            "float32",
            "warn",
            f"{', '.join(promoted)} return float64 for float32 input",
            "float32 in, float32 out",
            "a np.float64 scalar or a float64 parameter array promotes the result: convert "
            "constants with float() and parameters with .astype(wi.dtype) (slower, still correct)",
        )
    return Check("float32", "pass", f"max relative difference {worst:.2g}", "<= 0.01, float32 out")


# -- row independence ---------------------------------------------------------------------


def batch_sizes(rng: np.random.Generator | None = None) -> list[int]:
    """The sizes of the batches ``check_row_independence`` puts kept rows in: a render's own
    batch (``RENDER_BATCH``) and ``RANDOM_BATCHES`` sizes log-uniform in
    [``ROW_INDEPENDENCE_ROWS`` + 1, ``LARGEST_BATCH``], drawn from fresh entropy (not the
    checks' seed) unless ``rng`` is given: a material cannot know them beforehand."""
    rng = rng if rng is not None else np.random.default_rng()
    low, high = math.log(ROW_INDEPENDENCE_ROWS + 1), math.log(LARGEST_BATCH)
    drawn = np.exp(rng.uniform(low, high, RANDOM_BATCHES)).astype(int)
    return [RENDER_BATCH, *(int(size) for size in drawn)]


def check_row_independence(
    material, kept: list[Kept], rng: np.random.Generator, sizes: list[int] | None = None
) -> Check:
    """Rows of large calls give the same answers asked one at a time, in another order, and
    inside batches of other sizes, unless they are ill-conditioned.

    ``kept`` holds the first rows of calls the other checks made (``call(..., keep=)``);
    each is asked again row by row (batches of one), as one shuffled batch, and at random
    places inside a batch of each of ``sizes`` rows (default ``batch_sizes()``: a render's
    batch and sizes drawn at random per run), in the dtype and memory layout of the
    original call. A material whose answer for a row depends on the other rows (their
    number, order, mean) could tell a probe from a render, and would be graded on answers
    the renderer never gets. The answers agree to ``ROW_RTOL`` (rounding of NumPy's vector
    and scalar loops). Where a row's answer differs, the same batching is asked again
    ``NUDGES`` times with every input moved by a few ulps (``Kept.nudged``): if that moves
    the answer beyond ``ROW_RTOL`` too, the row is ill-conditioned and its difference is
    rounding, not dependence (a material whose answer follows the other rows gives the same
    answer, to rounding, for inputs a few ulps away). No false alarm measured (see the
    module's text).
    """
    sizes = batch_sizes() if sizes is None else sizes
    compared = excused = 0
    for record in kept:
        order = rng.permutation(record.rows)
        # Each way: its name, how it asks a record's rows again, and the order it asks them in.
        ways: list[tuple[str, Callable[[Kept], tuple], np.ndarray | None]] = [
            ("alone", lambda r: _ask_alone(material, r), None),
            ("in another order", partial(_ask_again, material, index=order), order),
            *(
                (
                    f"inside a batch of {size} rows",
                    lambda r, size=size: _ask_inside(material, r, size, rng),
                    None,
                )
                for size in sizes
            ),
        ]
        for how, ask, order_of in ways:
            answers = ask(record)
            differ = _differ(record.answer, answers, order_of)
            compared += record.rows * len(record.answer)
            if differ.any():
                rounding = _ill_conditioned(ask, record, answers, rng)
                excused += int((differ & rounding).sum())
                differ &= ~rounding
            if differ.any():
                return _dependence(record, answers, order_of, differ, how)
    return Check(
        "row independence",
        "pass",
        f"0 of {compared} answers differ ({len(kept)} calls asked again, in {len(sizes) + 2} batchings"
        + (f"; {excused} ill-conditioned rows' differences are rounding)" if excused else ")"),
        _ROW_THRESHOLD,
    )


#: How often a batching whose answers differ is asked again with its inputs nudged.
NUDGES = 3
_ROW_THRESHOLD = f"0 (relative {ROW_RTOL:g}; ill-conditioned rows: rounding)"


def _differ(expected: tuple, answers: tuple, order_of: np.ndarray | None) -> np.ndarray:
    """(rows,) whether any part of ``answers`` (in the asked order) differs from the call's
    ``expected`` (in the call's order; ``order_of`` the call's row of each asked row)."""
    differ = np.zeros(len(answers[0]), dtype=bool)
    for answer, asked in zip(expected, answers, strict=True):
        differ |= ~_agree(answer if order_of is None else answer[order_of], asked)
    return differ


def _ill_conditioned(ask, record: Kept, answers: tuple, rng: np.random.Generator) -> np.ndarray:
    """(rows,) whether the answers for ``record``'s rows, asked by ``ask``, move beyond the
    tolerance when every input moves by a few ulps (``Kept.nudged``), in ``NUDGES`` tries."""
    ill = np.zeros(record.rows, dtype=bool)
    for _ in range(NUDGES):
        ill |= _differ(answers, ask(record.nudged(rng)), None)
    return ill


def _dependence(record: Kept, answers: tuple, order_of, differ: np.ndarray, how: str) -> Check:
    """The failure for the first answer that differs beyond rounding."""
    k = int(np.flatnonzero(differ)[0])
    row = k if order_of is None else int(order_of[k])
    j = next(
        j
        for j, (a, b) in enumerate(zip(record.answer, answers, strict=True))
        if not _agree(a[row : row + 1], b[k : k + 1])[0]
    )
    expected, got = record.answer[j][row], answers[j][k]
    count = int(differ.sum())
    hint = (
        f"the material's answer for a row depends on the other rows of the batch: "
        f"{record.method} gave {_values(expected)} for row {row} of a call of {record.batch_rows} "
        f"rows, and {_values(got)} for the same row {how} ({count} of {record.rows} rows differ, "
        "and their answers stay put when their inputs move by a few ulps: not rounding). "
        "Compute each row from its own wo, wi, n and u only (no means, sums, sorting or counts "
        "over the rows, nothing kept from earlier calls)"
    )
    return Check(
        "row independence",
        "FAIL",
        f"{record.method}: {count} of {record.rows} rows differ {how}",
        _ROW_THRESHOLD,
        hint,
    )


def _ask_alone(material, record: Kept) -> tuple:
    """The answers (a tuple of arrays) to ``record``'s call, each row asked in a call of its own."""
    alone = [_ask_again(material, record, slice(k, k + 1)) for k in range(record.rows)]
    return tuple(np.concatenate([a[j] for a in alone]) for j in range(len(record.answer)))


def _ask_inside(material, record: Kept, size: int, rng: np.random.Generator) -> tuple:
    """The answers for ``record``'s rows asked inside a batch of ``size`` rows (in the kept
    rows' order)."""
    arguments, places = record.inside(size, rng)
    answer = call(material, record.method, *arguments, shapes=[(size, *p.shape[1:]) for p in record.answer])
    answer = answer if isinstance(answer, tuple) else (answer,)
    return tuple(np.asarray(a)[places] for a in answer)


def _ask_again(material, record: Kept, index) -> tuple:
    """The answer (as a tuple of arrays) to ``record``'s call on its rows ``index`` alone."""
    arguments = (rows_of(a, index) for a in record.arguments)
    rows = len(np.arange(record.rows)[index])
    answer = call(material, record.method, *arguments, shapes=[(rows, *p.shape[1:]) for p in record.answer])
    return answer if isinstance(answer, tuple) else (answer,)


def _agree(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(rows,) whether the rows of ``a`` and ``b`` are equal up to ``ROW_RTOL`` (NaN equal to NaN)."""
    a, b = a.astype(np.float64), b.astype(np.float64)
    with np.errstate(invalid="ignore"):
        close = np.abs(a - b) <= ROW_RTOL * np.maximum(np.abs(a), np.abs(b)) + ROW_ATOL
    close |= (a == b) | (np.isnan(a) & np.isnan(b))
    return close.reshape(len(a), -1).all(axis=1)


def _values(row: np.ndarray) -> str:
    """One row of an answer as text: a number, or a vector."""
    if np.ndim(row):
        return np.array2string(np.asarray(row, dtype=np.float64), precision=5)
    return f"{float(row):.6g}"
