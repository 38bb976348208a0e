"""The rows the checks send to a material: a render's walls, each seen on many rows.

A renderer asks a material about the hits of one batch of paths: a few flat surfaces (the
walls of a room, the faces of a box), each on many rows with one normal and one tangent
frame, every row with a ``wo`` of its own. A grader that asked otherwise could be
recognised: the old probes (one ``wo`` and one ``n`` on every row; later, every row turned
by a rotation of its own, so that every row had a normal of its own) both were, and a
material could be right only for them. So the checks think in a frame of their own (the
grid's, or the local frame with +z = n) and send each row turned onto one of ``WALLS``
walls (``Walls``): the wall's fixed rotation (its frame, drawn at random) after a twist
about +z by an angle of the row's own. The wall's normal is the same on all of its rows,
to the bit, as a wall's is in a render; wo is not, as it is not on a wall seen by a camera.
An isotropic material (whose answers depend on wo, wi and n only through the angles between
them, as every material of the homework) answers the same, and the checks turn what it
returns back (``Rotations.undo``) before they bin or compare it; ``Rotations.to_wall``
turns a direction into its wall's frame only, where the samples of a material that draws
its azimuth from a tangent frame of its own (a function of n, fixed on a wall) show any
skew in it (``ptlab.grading.checks.check_chi_square``, a test per wall). Rows of different
probes (the wo's of the lobe measurements, the special directions of consistency, the
angles of the delta checks) are shuffled into one batch (``Probe``), so that neither wo, n
nor the angle between them is the same on every row of a call.

The rotations cost rounding: a turned unit vector is off by about 1e-16, which is far
below every tolerance of the checks. Where a probe needs an exact value (wo exactly in the
tangent plane, wi exactly 1e-8 above it), ``Rotations.draw`` gives its rows ``exact``
rotations instead: a random twist about +z, then one of the 24 rotations that take the
axes to axes. They keep every cosine to +z exactly (n lands on an axis, and its one
nonzero component multiplies the z component alone).

``Kept`` holds a few rows of a large call, so that ``check_row_independence`` can ask them
again one by one, in another order, and inside batches of other sizes (``Kept.inside``: up to
a render's batch, the other rows made from more rows of the same call, each turned by a
rotation of its own, as the rows of a curved surface are: ``Rotations.each_row``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ptlab.samplers import largest_below_one
from ptlab.vectors import vec3

#: The permutations of the three axes and their signs (the determinants of their matrices).
_PERMUTATIONS = np.array([[0, 1, 2], [1, 2, 0], [2, 0, 1], [0, 2, 1], [2, 1, 0], [1, 0, 2]])
_PARITY = np.array([1.0, 1.0, 1.0, -1.0, -1.0, -1.0])


#: Walls per call: a render's call to a material holds the hits on a few flat surfaces (the
#: Cornell box's white material: the floor, the ceiling, the back wall and the boxes' faces).
WALLS = 8


class Walls:
    """``count`` flat surfaces, each a fixed rotation (its frame: ``frames``, 3 x 3 lists of
    (count,) entries) that takes the checks' +z to the wall's normal. Half of them face along
    a coordinate axis, as a room's walls and a box's faces do (a random one of the 24
    rotations taking axes to axes, after a twist about +z: the normal is exactly +-x, +-y or
    +-z), where a material may branch on the normal's components (its tangent frame does);
    the others are uniformly random, as a tilted surface is."""

    def __init__(self, rng: np.random.Generator, count: int = WALLS, along_axes: int | None = None):
        """``along_axes`` of the walls (default half, at most 6) face along distinct axes."""
        self.count = count
        along_axes = min(count // 2 if along_axes is None else along_axes, 6)
        axial, tilted = _along_axes(rng, along_axes), _uniform(rng, count - along_axes)
        self.frames = [
            [np.concatenate([a, b]) for a, b in zip(row_a, row_b, strict=True)]
            for row_a, row_b in zip(axial, tilted, strict=True)
        ]

    def rotations(self, rng: np.random.Generator, rows: int) -> Rotations:
        """``rows`` rotations, each row on a wall drawn at random: the wall's frame after a
        twist about +z by a uniformly random angle of the row's own (so that wo, turned,
        differs from row to row, and n, turned, is the wall's normal to the bit)."""
        wall = rng.integers(0, self.count, rows)
        phi = rng.uniform(0, 2 * np.pi, rows)
        c, s = np.cos(phi), np.sin(phi)
        f = [[entry[wall] for entry in row] for row in self.frames]
        # (frame) (twist): the twist's third column is +z, so the third column stays the frame's.
        m = [[f[i][0] * c + f[i][1] * s, f[i][1] * c - f[i][0] * s, f[i][2]] for i in range(3)]
        return Rotations(m, wall, self)


class Rotations:
    """One rotation per row: ``m[i][j]`` is the (rows,) array of the matrices' entries (i, j);
    ``wall`` the (rows,) wall of each row (-1 for an exact rotation, or for every row of
    ``each_row``), on ``walls``.

    Nine arrays rather than one (3, 3, rows) block: a block of 10^6 rows takes 72 MB, which
    glibc maps fresh (and the kernel faults in page by page) on every allocation, about
    three times the cost of computing it; arrays of 8 MB reuse the heap.
    """

    def __init__(self, m: list[list[np.ndarray]], wall: np.ndarray | None = None, walls: Walls | None = None):
        self.m = m
        self.wall = np.full(len(m[0][0]), -1) if wall is None else wall
        self.walls = walls

    @classmethod
    def draw(
        cls,
        rng: np.random.Generator,
        rows: int,
        exact: np.ndarray | None = None,
        walls: Walls | None = None,
    ) -> Rotations:
        """``rows`` rotations onto ``walls`` (default: ``WALLS`` new ones), each row on a wall
        drawn at random (``Walls.rotations``), except where the (rows,) bool ``exact`` is
        set: there a twist about +z and an axes-to-axes rotation (see the module's text)."""
        turn = (walls or Walls(rng)).rotations(rng, rows)
        if exact is not None and exact.any():
            for row, exact_row in zip(turn.m, _exact(rng, int(exact.sum())), strict=True):
                for entry, exact_entry in zip(row, exact_row, strict=True):
                    entry[exact] = exact_entry
            turn.wall[exact] = -1
        return turn

    @classmethod
    def each_row(cls, rng: np.random.Generator, rows: int) -> Rotations:
        """``rows`` uniformly random (Haar) rotations, one per row: a curved surface's rows,
        each with a normal of its own."""
        return cls(_uniform(rng, rows))

    def apply(self, v: np.ndarray) -> np.ndarray:
        """(rows, 3) column-major: each row's rotation of ``v``, (3,) or (rows, 3)."""
        m = self.m
        if v.ndim == 1:  # one unit vector for every row: its zero components cost nothing
            return vec3(*(sum(m[i][j] * v[j] for j in np.flatnonzero(v)) for i in range(3)))
        x, y, z = v[:, 0], v[:, 1], v[:, 2]
        return vec3(*(m[i][0] * x + m[i][1] * y + m[i][2] * z for i in range(3)))

    def undo(self, w: np.ndarray) -> np.ndarray:
        """(rows, 3) column-major: each row of ``w`` (rows, 3) turned back (by the transpose)."""
        return _transposed(self.m, w)

    def to_wall(self, w: np.ndarray) -> np.ndarray:
        """(rows, 3) column-major: each row of ``w`` (rows, 3, every row on a wall) in its
        wall's frame (the twist not undone): where a sampler's own tangent frame, a function
        of n, stays put from row to row."""
        if self.walls is None:
            raise ValueError("these rotations put no row on a wall")
        f = [[entry[self.wall] for entry in row] for row in self.walls.frames]
        return _transposed(f, w)


def _transposed(m: list[list[np.ndarray]], w: np.ndarray) -> np.ndarray:
    """(rows, 3) column-major: each row of ``w`` turned by the transpose of its ``m``."""
    x, y, z = w[:, 0], w[:, 1], w[:, 2]
    return vec3(*(m[0][j] * x + m[1][j] * y + m[2][j] * z for j in range(3)))


def _uniform(rng: np.random.Generator, rows: int) -> list[list[np.ndarray]]:
    """Uniformly random rotations (3 x 3 lists of (rows,) entries), from unit quaternions: a
    normal vector in R^4, normalised, is uniform on the unit sphere S^3 (Shoemake, Graphics
    Gems III)."""
    w, x, y, z = (rng.standard_normal(rows) for _ in range(4))
    scale = np.sqrt(2.0 / (w * w + x * x + y * y + z * z))  # |q| = sqrt(2): the 2s of the formula
    for part in (w, x, y, z):
        part *= scale
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz, wx, wy, wz = x * y, x * z, y * z, w * x, w * y, w * z
    return [
        [1.0 - (yy + zz), xy - wz, xz + wy],
        [xy + wz, 1.0 - (xx + zz), yz - wx],
        [xz - wy, yz + wx, 1.0 - (xx + yy)],
    ]


def _exact(rng: np.random.Generator, rows: int) -> list[list[np.ndarray]]:
    """Rotations (3 x 3 lists of (rows,) entries) that keep every z component: a twist about +z
    by a random angle, then a random one of the 24 rotations taking axes to axes (signed
    permutations, det 1)."""
    phi = rng.uniform(0, 2 * np.pi, rows)
    c, s, zero, one = np.cos(phi), np.sin(phi), np.zeros(rows), np.ones(rows)
    twist = np.array([[c, -s, zero], [s, c, zero], [zero, zero, one]])
    which = rng.integers(0, len(_PERMUTATIONS), rows)
    signs = rng.choice([-1.0, 1.0], size=(3, rows))
    signs[2] = signs[0] * signs[1] * _PARITY[which]
    # Row i of the result is row permutation[i] of the twist, times its sign.
    picked = np.take_along_axis(twist, _PERMUTATIONS[which].T[:, None, :], axis=0) * signs[:, None, :]
    return [list(row) for row in picked]


def _along_axes(rng: np.random.Generator, count: int) -> list[list[np.ndarray]]:
    """``count`` (at most 6) of ``_exact``'s rotations whose normals (+z turned: their third
    columns) are distinct axes, picked from enough draws that all six axes are among them."""
    drawn = _exact(rng, 64)
    normals = np.column_stack([drawn[i][2] for i in range(3)])
    _, first = np.unique(normals, axis=0, return_index=True)
    picked = rng.permutation(first)[:count]
    return [[entry[picked] for entry in row] for row in drawn]


class Probe:
    """How the checks' rows go out in one call: each turned onto a wall (``Rotations.draw``),
    and shuffled (sent row k is the checks' row ``order[k]``) unless the checks' order
    already mixes them."""

    def __init__(
        self,
        rng: np.random.Generator,
        rows: int,
        exact: np.ndarray | None = None,
        shuffle: bool = True,
        walls: Walls | None = None,
    ):
        """``exact``: (rows,) bool in the checks' order, rows that need exact cosines to +z;
        ``walls``: the walls of several calls (a render's are the same in every call), or
        None for new ones."""
        self.order = rng.permutation(rows) if shuffle else None
        if exact is not None and shuffle:
            exact = exact[self.order]
        self.rotations = Rotations.draw(rng, rows, exact, walls)

    def send(self, v: np.ndarray) -> np.ndarray:
        """(rows, 3) column-major: the vectors ``v`` ((rows, 3) in the checks' order and frame,
        or one (3,) for every row) as the material receives them."""
        return self.rotations.apply(self.send_rows(v) if v.ndim == 2 else v)

    def send_rows(self, a: np.ndarray) -> np.ndarray:
        """(rows, ...) the rows of ``a`` (the checks' order) in the sent order."""
        return a if self.order is None else a[self.order]

    def receive(self, w: np.ndarray) -> np.ndarray:
        """(rows, 3) the material's directions ``w`` (sent order) in the checks' order and frame."""
        return self.receive_rows(self.rotations.undo(w))

    def receive_rows(self, a: np.ndarray) -> np.ndarray:
        """(rows, ...) the material's answers ``a`` (sent order) in the checks' order."""
        if self.order is None:
            return a
        back = np.empty_like(a)
        back[self.order] = a
        return back


#: Rows of a call kept besides the asked ones, to make the other rows of a larger batch from.
POOL_ROWS = 1024
#: How far ``Kept.nudged`` moves every float input: this many units in the last place of 1
#: in the input's type (3.6e-15 in float64, 1.9e-6 in float32), far below any precision that
#: a render's answer may rest on.
NUDGE_ULPS = 16


@dataclass
class Kept:
    """The first rows of one call of a material: its arguments and its answer (a tuple of
    arrays for ``sample_weight``), with the number of rows the call had, and the arguments
    of up to ``POOL_ROWS`` rows of it (``pool``) to fill larger batches with."""

    method: str
    arguments: tuple
    answer: tuple
    batch_rows: int
    pool: tuple = ()

    @classmethod
    def first_rows(cls, method: str, arguments: tuple, answer, rows: int) -> Kept:
        parts = answer if isinstance(answer, tuple) else (answer,)
        return cls(
            method,
            tuple(rows_of(a, slice(0, rows)) for a in arguments),
            tuple(rows_of(np.asarray(p), slice(0, rows)) for p in parts),
            len(arguments[0]),
            tuple(rows_of(a, slice(0, POOL_ROWS)) for a in arguments),
        )

    @property
    def rows(self) -> int:
        return len(self.arguments[0])

    def inside(self, size: int, rng: np.random.Generator) -> tuple[tuple, np.ndarray]:
        """The kept rows' arguments inside a batch of ``size`` (> ``rows``) rows, in the dtype
        and layout of the call: the kept rows at random places in a random order, the others
        rows of ``pool`` each turned by a rotation of its own (u drawn anew). Returns the
        arguments and the (rows,) places of the kept rows."""
        places = rng.choice(size, self.rows, replace=False)
        others = np.ones(size, dtype=bool)
        others[places] = False
        filler = self._filler(size - self.rows, rng)
        arguments = []
        for kept, fill in zip(self.arguments, filler, strict=True):
            full = np.empty((size, *kept.shape[1:]), dtype=kept.dtype, order="F" if _fortran(kept) else "C")
            full[places], full[others] = kept, fill
            arguments.append(full)
        return tuple(arguments), places

    def nudged(self, rng: np.random.Generator) -> Kept:
        """The same call with every float input of the kept rows moved by up to
        ``NUDGE_ULPS`` ulps of 1 (each component by a uniformly random amount, so that two
        nudged vectors differ in every direction; u kept in [0, 1)), in the same dtype and
        layout. Where a material's answer for a row moves beyond the checks' tolerance
        under that, the row is ill-conditioned, and so its answer is only as reproducible as
        the rounding of its inputs (which NumPy's vector and scalar loops may do differently):
        GGX visible normals as Heitz (2018) publishes them pick their tangent from wo's
        local x and y, which are rounding noise at wo = n."""
        arguments = []
        for a in self.arguments:
            if a.dtype.kind != "f":
                arguments.append(a)
                continue
            step = NUDGE_ULPS * float(np.finfo(a.dtype).eps)
            moved = a + (step * rng.uniform(-1.0, 1.0, a.shape)).astype(a.dtype)
            if a.ndim == 2 and a.shape[1] != 3:  # uniforms, not directions
                moved = np.clip(moved, 0, largest_below_one(a.dtype))
            arguments.append(np.asfortranarray(moved) if _fortran(a) else np.ascontiguousarray(moved))
        return replace(self, arguments=tuple(arguments))

    def _filler(self, count: int, rng: np.random.Generator) -> list[np.ndarray]:
        """``count`` rows like the pool's: directions turned by a random rotation per row
        (one for all of a row's directions: a curved surface's rows, so that a batch holds
        many normals, as a render's of curved objects does), other columns (u) uniform in
        [0, 1)."""
        pool = self.pool or self.arguments
        which = rng.integers(0, len(pool[0]), count)
        turn = Rotations.each_row(rng, count)
        filler = []
        for a in pool:
            if a.ndim == 2 and a.shape[1] == 3:
                filler.append(turn.apply(a[which].astype(np.float64)).astype(a.dtype))
            elif a.ndim == 2 and a.dtype.kind == "f":
                below_one = largest_below_one(a.dtype)
                filler.append(np.minimum(rng.random((count, a.shape[1])).astype(a.dtype), below_one))
            else:
                filler.append(a[which])
        return filler


def _fortran(a: np.ndarray) -> bool:
    return a.ndim == 2 and a.flags.f_contiguous and not a.flags.c_contiguous


def rows_of(a: np.ndarray, index) -> np.ndarray:
    """The rows ``index`` (a slice or an index array) of ``a``, copied in ``a``'s memory layout
    (column-major stays column-major: the material sees the arrays it saw in the batch)."""
    taken = a[index]
    if _fortran(a):
        return np.asfortranarray(taken)
    return np.ascontiguousarray(taken)


class Turned:
    """``material`` asked with every row of every call turned onto a wall (new walls for each
    call: ``Rotations.draw``), and the directions it samples turned back: an isotropic
    material gives the answers it would give unturned (to rounding), and no call it gets
    repeats one wo and one n on every row. For checks written in one frame (the exercises'
    known answers) that must not look like probes."""

    def __init__(self, material, rng: np.random.Generator):
        self.material, self.rng = material, rng

    def eval(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray):
        turn = Rotations.draw(self.rng, len(wo))
        return self.material.eval(turn.apply(wo), turn.apply(wi), turn.apply(n))

    def pdf(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray):
        turn = Rotations.draw(self.rng, len(wo))
        return self.material.pdf(turn.apply(wo), turn.apply(wi), turn.apply(n))

    def sample(self, wo: np.ndarray, n: np.ndarray, u: np.ndarray):
        turn = Rotations.draw(self.rng, len(wo))
        wi = np.asarray(self.material.sample(turn.apply(wo), turn.apply(n), u))
        if wi.shape != (len(wo), 3) or wi.dtype.kind != "f":
            return wi  # (for the check to report as it is)
        return turn.undo(wi.astype(np.float64))
