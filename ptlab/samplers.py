"""Samplers: where the uniform random numbers of a render come from.

A Monte Carlo estimate averages f(u) over sample points u in [0, 1)^d. Which points those
are matters: independent random points leave gaps and clumps, so some parts of the domain
are over-sampled and others missed; *stratified* and *quasi-Monte Carlo* points fill the
domain evenly and the same number of samples gives a smaller error (pbrt-v4, chapter 8;
GAMES101 lecture 16 samples independently). A sampler hands out the numbers one dimension
(or one pair of dimensions) at a time:

    keys = sampler.keys(pixel, index)        # once per camera sample, carried with its path
    u = sampler.get(keys, dim, count)        # (N, count) float32 in [0, 1)

``pixel`` (N,) are global pixel ids (y * width + x), ``index`` (N,) the number of the sample
within its pixel (0, 1, ..., spp - 1), ``dim`` the first dimension asked for. ``keys`` hold
what the sampler needs of (seed, pixel, index), hashed once per path rather than once per
request (docs/performance.md). The value is a pure function of (seed,
pixel, index, dimension): no state, no stream shared between jobs, so an image is the same
whatever its tiles, passes, workers or a checkpoint's resume.

Three samplers (``SAMPLERS``):

* ``independent``: every number a counter-based hash of (seed, pixel, index, dimension), the
  way a random number generator would give them (pbrt-v4's ``IndependentSampler``);
* ``stratified``: correlated multi-jittered sampling (Kensler 2013, "Correlated
  Multi-Jittered Sampling", Pixar technical memo 13-01; Mitsuba 3's ``multijitter``): each
  pair of dimensions puts the spp samples of a pixel one per cell of an m x n grid, and one
  per column of n and row of m sub-strata, with the grid permuted per pixel and pair. It
  depends on spp, so a render cannot be resumed with more samples;
* ``sobol``: Sobol's first two dimensions, a (0, 2)-sequence (Sobol 1967), for every pair: the
  first 2^k samples of a pixel put exactly one point in every elementary interval of area
  2^-k. Each pixel and pair gets its own scramble and its own shuffle of the sample indices
  (pbrt-v4's ``PaddedSobolSampler``; Burley 2020, "Practical Hash-based Owen Scrambling",
  JCGT 9(4)); one-dimensional requests use the shuffled, scrambled van der Corput sequence.
  Any first N samples of a pixel are a prefix of its first M > N, so a render resumes with
  more spp to the same image as one rendered straight.

Dimensions (``BounceUniforms``, used by every integrator): the camera's pixel jitter is the pair
(0, 1); bounce ``depth`` then uses, from ``2 + 5 * depth`` on, the light sample (a pair: its
first coordinate picks the light triangle and, stretched back to [0, 1) inside the chosen
interval, becomes the point's first coordinate; in a scene with point lights or a sky it
first picks the kind of light, stretched the same way: ``ptlab.lights.LightSampler``),
Russian roulette (one), and the BSDF direction (a pair: a material that also chooses a lobe
does it with the first coordinate, stretched the same way). Pairs are stratified together;
the warps that turn them into directions and points are bijective so that the
stratification survives (``ptlab.sampling``).
Only the camera's pair and the first two bounces are spread evenly (``PATTERNED_DIMENSIONS``):
later bounces take independent numbers from every sampler.

All arithmetic is NumPy integer arithmetic on whole arrays (uint32 and uint64, which wrap
around on overflow as the hash functions need).
"""

from __future__ import annotations

import time

import numpy as np

SAMPLERS = ("independent", "stratified", "sobol")
#: The sampler renders use unless told otherwise: the one measured best (docs/rendering.md, "Samplers").
DEFAULT_SAMPLER = "sobol"

_U32 = np.uint32
_U64 = np.uint64
#: 2^-24: a uint32 whose top 24 bits are kept, times this, is a float32 in [0, 1) exactly.
_TO_UNIT = np.float32(2.0**-24)
#: The dimensions a sampler spreads evenly: the camera's pair and the first two bounces
#: (``BounceUniforms``). From the third bounce on, every sampler's numbers are independent:
#: a path's later dimensions mix with all its earlier ones, and stratifying them bought
#: little error for much of the sampler's time (docs/performance.md).
PATTERNED_DIMENSIONS = 2 + 5 * 2

#: SplitMix64's increment, 2^64 / phi: consecutive counters k * _GAMMA are far apart.
_GAMMA = 0x9E3779B97F4A7C15
_MASK64 = (1 << 64) - 1


def largest_below_one(dtype) -> np.floating:
    """The largest number below 1 in the float type ``dtype``: 1 - 2^-24 in float32,
    1 - 2^-53 in float64. Where arithmetic on uniforms (a sum, a stretch) can round up to 1,
    the result is clamped to it, so that it stays in [0, 1)."""
    float_type = np.dtype(dtype).type
    return np.nextafter(float_type(1), float_type(0))


#: ``largest_below_one`` of float32, the type of every sampler's uniforms (pbrt-v4's
#: ``OneMinusEpsilon``): 1 - 2^-24.
ONE_MINUS_EPSILON = largest_below_one(np.float32)


def mix64(x: np.ndarray) -> np.ndarray:
    """A 64-bit hash of uint64 values: SplitMix64's finalizer (D. Stafford's "Mix13", 2011;
    G. Steele et al. 2014, "Fast Splittable Pseudorandom Number Generators").

    ``mix64(seed + k * _GAMMA)`` for k = 0, 1, 2, ... is SplitMix64's stream from ``seed``,
    which passes the BigCrush tests of independence; every number here is one of those.
    """
    x = x ^ (x >> _U64(30))
    x *= _U64(0xBF58476D1CE4E5B9)
    x ^= x >> _U64(27)
    x *= _U64(0x94D049BB133111EB)
    x ^= x >> _U64(31)
    return x


def _counter(dim: int | np.ndarray, salt: int = 0) -> np.uint64 | np.ndarray:
    """The stream position of dimension ``dim``: (dim + 1) * _GAMMA (+ a salt), mod 2^64
    (per row, for an (N,) array of dimensions: uint64 arithmetic wraps around by itself)."""
    if isinstance(dim, np.ndarray):
        return (dim.astype(_U64) + _U64(1)) * _U64(_GAMMA) + _U64(salt)
    return _U64(((int(dim) + 1) * _GAMMA + salt) & _MASK64)


def _high(h: np.ndarray) -> np.ndarray:
    """The high 32 bits of uint64 values, as uint32."""
    return (h >> _U64(32)).astype(_U32)


def unit_float(bits: np.ndarray) -> np.ndarray:
    """uint32 values -> float32 in [0, 1) from their top 24 bits (all a float32 can hold)."""
    return (bits >> _U32(8)).astype(np.float32) * _TO_UNIT


def laine_karras(x: np.ndarray, seed: np.ndarray) -> np.ndarray:
    """A hash-based permutation of uint32 values in which each bit changes only with the bits
    below it (Laine and Karras 2011, with Burley 2020's constants, listing 2).

    Restricted to the low k bits it is a permutation of [0, 2^k), one of a random-looking
    family chosen by ``seed``. Applied to bit-reversed numbers it is a nested (Owen)
    scramble: each binary digit is flipped by a hash of the digits before it.
    """
    x = x + seed
    x ^= x * _U32(0x6C50B47C)
    x ^= x * _U32(0xB82F1E52)
    x ^= x * _U32(0xC7AFE638)
    x ^= x * _U32(0x8D22F6E6)
    return x


class Sampler:
    """Base class: per-path ``keys``, then ``get`` the uniforms of any dimension.

    A key is a uint64: a hash of (seed, pixel) in its high 32 bits, the sample index in its
    low 32 (subclasses may store the index in another form). Every random number is a
    SplitMix64 output (``mix64``) at a counter made of the key (or its pixel half) and the
    dimension, so no two of them share bits and no generator keeps state.

    Attributes:
        name: the sampler's name (``SAMPLERS``).
        seed: the render's seed.
    """

    name = ""

    def __init__(self, seed: int = 0):
        self.seed = int(seed)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(seed={self.seed})"

    @property
    def identity(self) -> str:
        """What of the sampler an image depends on, besides the seed (checkpoints compare it)."""
        return self.name

    def keys(self, pixel: np.ndarray, index: np.ndarray) -> np.ndarray:
        """(N,) uint64 keys of the samples ``index`` (N,) of the pixels ``pixel`` (N,)."""
        seed = mix64(np.array([int(self.seed) & _MASK64], dtype=_U64))[0]
        pixel_hash = _high(mix64(np.asarray(pixel).astype(_U64) * _U64(_GAMMA) ^ seed))
        index = self.index_part(np.asarray(index).astype(_U32))
        return (pixel_hash.astype(_U64) << _U64(32)) | index.astype(_U64)

    def index_part(self, index: np.ndarray) -> np.ndarray:
        """(N,) uint32: what of the sample index goes into a key (by default, the index)."""
        return index

    def get(self, keys: np.ndarray, dim: int | np.ndarray, count: int) -> np.ndarray:
        """(N, count) float32 uniforms in [0, 1), in the column-major layout of
        ``ptlab.vectors``.

        Args:
            keys: (N,) from ``keys``.
            dim: the first dimension of the request; a pair (count 2) is stratified together.
                An (N,) array asks each row for its own dimension (paths at different depths
                in one batch: ``BounceUniforms``).
            count: 1 or 2.
        """
        if isinstance(dim, np.ndarray):
            return self._get_per_row(keys, dim, count)
        patterned = dim < PATTERNED_DIMENSIONS
        if count == 1:
            return (self.one(keys, dim) if patterned else independent_one(keys, dim))[:, None]
        if count == 2:
            return np.stack(self.pair(keys, dim) if patterned else independent_pair(keys, dim)).T
        raise ValueError(f"count must be 1 or 2, got {count}")

    def _get_per_row(self, keys: np.ndarray, dims: np.ndarray, count: int) -> np.ndarray:
        """``get`` with a dimension per row: each patterned dimension's rows in one call
        (there are few of them: ``PATTERNED_DIMENSIONS``), and all the independent rows in
        one more (a hash takes its dimension per row as well as one for all).

        In a batch kept full by path regeneration, the paths that entered it together stay
        together, in order, and are at one depth: each group is then a run of rows, taken as
        a slice, without copying (``_rows_where``).
        """
        if dims.min() >= PATTERNED_DIMENSIONS:  # (every row independent: one call, no copy)
            if count == 1:
                return independent_one(keys, dims)[:, None]
            return np.stack(independent_pair(keys, dims)).T
        out = np.empty((len(keys), count), dtype=np.float32, order="F")
        patterned = dims < PATTERNED_DIMENSIONS
        # The patterned dimensions present (a count per value: faster than np.unique).
        present = np.flatnonzero(np.bincount(dims[patterned], minlength=PATTERNED_DIMENSIONS))
        groups: list[tuple[np.ndarray, int | None]] = [(dims == d, int(d)) for d in present]
        groups.append((~patterned, None))
        for mask, dim in groups:
            rows = _rows_where(mask)
            if isinstance(rows, slice) and rows.start == rows.stop:
                continue
            run = keys[rows]
            if dim is None:  # (the independent rows, each with its own dimension)
                values = independent_one(run, dims[rows]) if count == 1 else independent_pair(run, dims[rows])
            else:
                values = self.one(run, dim) if count == 1 else self.pair(run, dim)
            if count == 1:
                out[rows, 0] = values
            else:
                out[rows, 0], out[rows, 1] = values
        return out

    def one(self, keys: np.ndarray, dim: int) -> np.ndarray:
        """(N,) float32 uniforms of dimension ``dim``."""
        raise NotImplementedError

    def pair(self, keys: np.ndarray, dim: int) -> tuple[np.ndarray, np.ndarray]:
        """Two (N,) float32 arrays, dimensions ``dim`` and ``dim + 1``, stratified together."""
        raise NotImplementedError


def _rows_where(mask: np.ndarray) -> slice | np.ndarray:
    """The rows where ``mask`` holds: a slice when they are one run (no copy), else indices."""
    rows = np.flatnonzero(mask)
    if len(rows) == 0:
        return slice(0, 0)
    if rows[-1] - rows[0] + 1 == len(rows):
        return slice(int(rows[0]), int(rows[-1]) + 1)
    return rows


def sample_hash(keys: np.ndarray, dim: int | np.ndarray) -> np.ndarray:
    """(N,) uint64: 64 random bits of each sample in dimension ``dim``."""
    return mix64(keys + _counter(dim))


def pattern_hash(keys: np.ndarray, dim: int) -> np.ndarray:
    """(N,) uint64: 64 random bits of each sample's pixel in dimension ``dim``, the same for
    every sample of the pixel (what its pattern is scrambled and shuffled with)."""
    return mix64((keys >> _U64(32)) + _counter(dim, salt=0x632BE59BD9B4E019))


def independent_one(keys: np.ndarray, dim: int | np.ndarray) -> np.ndarray:
    """(N,) float32 independent uniforms of dimension ``dim``."""
    return unit_float(_high(sample_hash(keys, dim)))


def independent_pair(keys: np.ndarray, dim: int | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two (N,) float32 arrays of independent uniforms, from one 64-bit hash."""
    bits = sample_hash(keys, dim)
    return unit_float(_high(bits)), unit_float(bits.astype(_U32))


class IndependentSampler(Sampler):
    """Independent uniforms: a hash of (seed, pixel, index, dimension) per number."""

    name = "independent"

    def one(self, keys, dim):
        return independent_one(keys, dim)

    def pair(self, keys, dim):
        return independent_pair(keys, dim)


def reverse_bits(x: np.ndarray) -> np.ndarray:
    """uint32 values with their 32 bits in reverse order (swapping halves, then quarters, ...)."""
    for shift, mask in ((1, 0x55555555), (2, 0x33333333), (4, 0x0F0F0F0F), (8, 0x00FF00FF)):
        x = ((x >> _U32(shift)) & _U32(mask)) | ((x & _U32(mask)) << _U32(shift))
    return (x >> _U32(16)) | (x << _U32(16))


def sobol_second_dimension(reversed_index: np.ndarray) -> np.ndarray:
    """Sobol's second dimension, as a 32-bit binary fraction, of the indices whose bit
    reversals are ``reversed_index`` (uint32).

    Its generator matrix is Pascal's triangle mod 2 (Burley 2020, listing 1): digit t of the
    result is the XOR of the index bits b with C(b, t) odd, that is (Lucas's theorem) of
    those with t a bitwise subset of b. In the reversed index's bit positions that turns
    into: result bit q = XOR of reversed-index bits p over every p whose bits are a subset of
    q's. Five shift-and-XOR steps compute that for all q at once, one bit of p at a time
    (a "subset-sum transform").
    """
    y = reversed_index.copy()
    for j, mask in enumerate((0xAAAAAAAA, 0xCCCCCCCC, 0xF0F0F0F0, 0xFF00FF00, 0xFFFF0000)):
        y ^= (y << _U32(1 << j)) & _U32(mask)
    return y


class SobolSampler(Sampler):
    """Shuffled, scrambled Sobol (0, 2)-sequence points for every pair of dimensions.

    For one pixel and pair: the sample index is shuffled by a nested scramble of its bits,
    which maps the first 2^k indices onto an aligned block of 2^k indices (so every
    power-of-two prefix of a pixel's samples is still a net, whatever spp); the Sobol point
    of the shuffled index is computed; and both coordinates get a random digital shift (an
    XOR with a random 32-bit number, which keeps every elementary interval's count and makes
    each point uniform on [0, 1)). The shift gave the same error as a full nested (Owen)
    scramble of the coordinates, for less than half the sampler's time (docs/performance.md).

    Keys hold the bit-reversed index: the shuffle works on the reversed index (so that the
    scramble nests from the index's highest bit down), and its result ``a`` is then the
    shuffled index reversed, which is van der Corput's first coordinate itself.
    """

    name = "sobol"

    def index_part(self, index):
        return reverse_bits(index)

    @staticmethod
    def _parts(keys, dim) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The shuffled index's reversal ``a`` and the pixel's two 32-bit digital shifts.

        One 64-bit pattern hash holds all three in separate bits: the shuffle's seed in bits
        0-15, the second shift in 16-39 and the first in 40-63 (a shift's low 8 bits are
        cut off by ``unit_float`` anyway, so each shift's 24 bits that count are its own).
        """
        pattern = pattern_hash(keys, dim)
        a = laine_karras(keys.astype(_U32), pattern.astype(_U32) & _U32(0xFFFF))
        return a, _high(pattern), (pattern >> _U64(8)).astype(_U32)

    def one(self, keys, dim):
        a, shift, _ = self._parts(keys, dim)
        return unit_float(a ^ shift)

    def pair(self, keys, dim):
        a, shift_x, shift_y = self._parts(keys, dim)
        return unit_float(a ^ shift_x), unit_float(sobol_second_dimension(a) ^ shift_y)


def permute(i: np.ndarray, length: int, seed: np.ndarray) -> np.ndarray:
    """A random-looking permutation of [0, length), chosen per row by ``seed``, applied to ``i``.

    ``laine_karras`` on the low k bits permutes [0, 2^k), 2^k >= length; values that land at
    ``length`` or beyond are permuted again until they fall inside ("cycle walking", Black
    and Rogaway 2002), which makes it a permutation of [0, length). A final rotation by a
    random offset makes every ``i`` land on each value with the same probability (Kensler
    2013's ``(i + p) % l``).
    """
    bits = max(1, int(length - 1).bit_length())
    mask = _U32((1 << bits) - 1)
    out = laine_karras(i, seed) & mask
    outside = np.flatnonzero(out >= length)
    while len(outside):
        out[outside] = laine_karras(out[outside], seed.take(outside)) & mask
        outside = outside[out[outside] >= length]
    return (out + (seed >> _U32(16))) % _U32(length)


class StratifiedSampler(Sampler):
    """Correlated multi-jittered samples (Kensler 2013) of ``spp`` per pixel and pair.

    The spp samples of a pixel fill the cells of an m x n grid (m = floor(sqrt(spp)),
    n = ceil(spp / m)); when spp < m n, the cells used are a random choice, so that every
    sample is uniform. Within its cell a sample sits in one of n sub-columns and m sub-rows,
    permuted so that the samples' x and y are each stratified into m n intervals too.
    One-dimensional requests put the spp samples one per interval of length 1 / spp.
    """

    name = "stratified"

    def __init__(self, seed: int = 0, spp: int = 1):
        super().__init__(seed)
        self.spp = int(spp)
        self.m = max(1, int(np.sqrt(self.spp)))
        self.n = -(-self.spp // self.m)

    def __repr__(self) -> str:
        return f"StratifiedSampler(seed={self.seed}, spp={self.spp})"

    @property
    def identity(self) -> str:
        return f"stratified, {self.spp} spp"

    def one(self, keys, dim):
        seed = pattern_hash(keys, dim).astype(_U32)
        stratum = permute(keys.astype(_U32), self.spp, seed)
        jitter = unit_float(_high(sample_hash(keys, dim)))
        return _below_one((stratum + jitter) / np.float32(self.spp))

    def pair(self, keys, dim):
        m, n = self.m, self.n
        pattern = pattern_hash(keys, dim)
        cell = permute(keys.astype(_U32), m * n, pattern.astype(_U32))
        column, row = cell % _U32(m), cell // _U32(m)
        # Kensler's correlated permutations: the sub-column within a cell depends on the
        # cell's row only (and the sub-row on its column), the same for the whole pixel.
        sub_column = permute(row, n, _high(pattern))
        sub_row = permute(column, m, pattern_hash(keys, dim + 1).astype(_U32))
        jitter = sample_hash(keys, dim)
        jitter_x, jitter_y = unit_float(_high(jitter)), unit_float(jitter.astype(_U32))
        x = (column + (sub_column + jitter_x) / np.float32(n)) / np.float32(m)
        y = (row + (sub_row + jitter_y) / np.float32(m)) / np.float32(n)
        return _below_one(x), _below_one(y)


def _below_one(x: np.ndarray) -> np.ndarray:
    """float32 values clamped below 1 (a sum of floats can round up to 1.0 exactly)."""
    return np.minimum(x, ONE_MINUS_EPSILON, dtype=np.float32)


def make_sampler(name: str, seed: int = 0, spp: int = 1) -> Sampler:
    """The sampler called ``name`` (``SAMPLERS``) for a render of ``spp`` samples per pixel."""
    if name == "independent":
        return IndependentSampler(seed)
    if name == "stratified":
        return StratifiedSampler(seed, spp)
    if name == "sobol":
        return SobolSampler(seed)
    raise ValueError(f"unknown sampler {name!r}; choose one of {', '.join(SAMPLERS)}")


class TimedSampler:
    """A sampler that adds up the time spent in it, so that a render can report the
    sampler's share of its time (as ``ptlab.accel.timed`` does for ray queries).

    Attributes:
        seconds: the summed wall time of ``keys`` and ``get`` so far.
    """

    def __init__(self, inner: Sampler):
        self.inner = inner
        self.seconds = 0.0

    def keys(self, pixel: np.ndarray, index: np.ndarray) -> np.ndarray:
        start = time.perf_counter()
        try:
            return self.inner.keys(pixel, index)
        finally:
            self.seconds += time.perf_counter() - start

    def get(self, keys: np.ndarray, dim: int | np.ndarray, count: int) -> np.ndarray:
        start = time.perf_counter()
        try:
            return self.inner.get(keys, dim, count)
        finally:
            self.seconds += time.perf_counter() - start


class BounceUniforms:
    """The uniforms of one bounce of a batch of paths, in the documented layout (module
    docstring): ``light()`` (N, 2), ``roulette()`` (N,), ``bsdf()`` (N, 2).

    Args:
        sampler: the render's sampler.
        keys: (N,) the paths' sampler keys.
        depth: the bounce, 0 at the surface a camera ray hits: one for the batch, or (N,) one
            per path, when the batch holds paths at different depths (path regeneration,
            ``ptlab.integrators.path``).
    """

    #: The camera's jitter inside the pixel is the pair of dimensions (0, 1).
    PIXEL = 0
    #: Dimensions each bounce uses: the light pair, roulette, the BSDF pair.
    PER_BOUNCE = 5

    def __init__(self, sampler: Sampler, keys: np.ndarray, depth: int | np.ndarray):
        self.sampler, self.keys = sampler, keys
        self.first = 2 + self.PER_BOUNCE * depth

    def light(self) -> np.ndarray:
        """(N, 2): which light (stretched back to [0, 1) afterwards), and where on it."""
        return self.sampler.get(self.keys, self.first, 2)

    def roulette(self) -> np.ndarray:
        """(N,): does the path go on."""
        return self.sampler.get(self.keys, self.first + 2, 1)[:, 0]

    def bsdf(self) -> np.ndarray:
        """(N, 2): the next direction (and the lobe, for a material that chooses one)."""
        return self.sampler.get(self.keys, self.first + 3, 2)
