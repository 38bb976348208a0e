"""The wavefront toolkit: a batch of paths as arrays, and what every integrator does to it.

A wavefront tracer advances a whole batch of paths one bounce at a time, each step a few
whole-array operations, instead of following one path to its end (Laine, Karras and Aila
2013, "Megakernels considered harmful"; pbrt-v4 chapter 15, the GPU integrator). The state
of the batch is structure-of-arrays, one row per path (``Paths``; at a surface,
``SurfaceHit``); dead paths are compacted away (``kept``), each hit's material is found
(``material_groups``) and called for its rows (``shade``), new rays leave the surface
(``leave_surface``), shadow rays test what a vertex sees (``sees``), and radiance is added
into the film per pixel (``add_to_film``), where a NaN or infinite sample is left out and
counted (``counting_nonfinite``).

The integrators (``path.py``, ``whitted.py``, ``debug.py``) are written with these pieces, so
that each reads like its pseudo-code.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field
from typing import overload

import numpy as np

from ptlab.accel.base import Accelerator
from ptlab.scene import Scene
from ptlab.vectors import concatenate_rows, dot, take_rows

#: A shadow ray stops this fraction short of the (offset) light point (pbrt's ShadowEpsilon).
SHADOW_EPSILON = 1e-4


@dataclass
class Paths:
    """The state of a batch of paths, as structure-of-arrays: one row per path, every field
    of a path in this one object, made for new camera rays by ``camera`` and compacted
    together (``take``) when paths end."""

    origins: np.ndarray  # (N, 3) float32
    dirs: np.ndarray  # (N, 3) float32 unit
    throughput: np.ndarray  # (N, 3) float32, product of f cos / pdf so far
    pixel: np.ndarray  # (N,) intp, the film row each path adds its radiance to
    sees_emission: np.ndarray  # (N,) bool: add the emission the ray hits (camera or delta bounce)
    sample: np.ndarray  # (N,) uint64 sampler keys: whose random numbers the path uses
    pdf: np.ndarray | None = None  # (N,) solid-angle pdf that chose dirs ("mis" only)
    #: The bounce each path is at (0: a camera ray): one for the whole batch, or (N,) intp
    #: when the batch holds paths at different depths (path regeneration, ``path.py``).
    depth: int | np.ndarray = 0

    @classmethod
    def camera(cls, origins: np.ndarray, dirs: np.ndarray, pixel: np.ndarray, sample: np.ndarray) -> Paths:
        """New paths from the camera: rays from ``origins`` along ``dirs`` (N, 3) float32,
        each adding its radiance into film row ``pixel`` (N,) and drawing its random numbers
        with the sampler keys ``sample`` (N,) uint64; throughput 1, at depth 0, seeing the
        emission they hit (a camera ray counts the lights it sees)."""
        count = len(pixel)
        return cls(
            origins=origins,
            dirs=dirs,
            throughput=np.ones((count, 3), dtype=np.float32, order="F"),
            pixel=pixel,
            sees_emission=np.ones(count, dtype=bool),
            sample=sample,
        )

    def __len__(self) -> int:
        return len(self.pixel)

    def take(self, rows: np.ndarray) -> Paths:
        """The paths ``rows`` (an index array), every field at once: the one place where a
        batch is compacted."""
        return Paths(
            origins=take_rows(self.origins, rows),
            dirs=take_rows(self.dirs, rows),
            throughput=take_rows(self.throughput, rows),
            pixel=self.pixel.take(rows),
            sees_emission=self.sees_emission.take(rows),
            sample=self.sample.take(rows),
            pdf=None if self.pdf is None else self.pdf.take(rows),
            depth=self.depth.take(rows) if isinstance(self.depth, np.ndarray) else self.depth,
        )

    def depths(self) -> np.ndarray:
        """(N,) the depth of each path."""
        if isinstance(self.depth, np.ndarray):
            return self.depth
        return np.full(len(self), self.depth, dtype=np.intp)


def joined(first: Paths, second: Paths) -> Paths:
    """One batch of the paths of ``first``, then those of ``second`` (new camera paths that fill
    a batch's free rows). A pdf missing on one side is 0 there (camera rays have none)."""

    def both(a: np.ndarray | None, b: np.ndarray | None, count_a: int, count_b: int) -> np.ndarray | None:
        if a is None and b is None:
            return None
        a = np.zeros(count_a, np.float32) if a is None else a
        b = np.zeros(count_b, np.float32) if b is None else b
        return np.concatenate([a, b])

    return Paths(
        origins=concatenate_rows([first.origins, second.origins]),
        dirs=concatenate_rows([first.dirs, second.dirs]),
        throughput=concatenate_rows([first.throughput, second.throughput]),
        pixel=concatenate_rows([first.pixel, second.pixel]),
        sees_emission=concatenate_rows([first.sees_emission, second.sees_emission]),
        sample=concatenate_rows([first.sample, second.sample]),
        pdf=both(first.pdf, second.pdf, len(first), len(second)),
        depth=concatenate_rows([first.depths(), second.depths()]),
    )


@dataclass
class SurfaceHit:
    """The live paths at their current vertex: the vertex's geometry, one row per path, and
    the paths themselves (``paths``; ``hit.throughput`` is ``hit.paths.throughput``, and so
    on for every field of ``Paths`` that a vertex needs).

    Two normals, as pbrt-v4's ``SurfaceInteraction`` has (section 3.11.1): ``n``, the shading
    normal, which the materials shade with, and ``ng``, the triangle's own (geometric) normal,
    which decides which side of the surface a point is on: where new rays leave it and how
    far off (``leave_surface``), and which face a ray hit (``front``). They are the same
    array on a flat triangle; on a smooth-shaded one (``Scene.normals``), ``n`` is
    interpolated from the corners' normals.
    """

    prim: np.ndarray  # (N,) intp triangle ids
    p: np.ndarray  # (N, 3) float32 hit points
    n: np.ndarray  # (N, 3) unit shading normal, turned to the side of wo
    wo: np.ndarray  # (N, 3) unit direction back along the ray
    front: np.ndarray  # (N,) bool: the ray hit the triangle's front face
    offset: np.ndarray  # (N,) float32: how far new rays start off the surface
    materials: list  # [(rows, material)]: who shades which rows (``material_groups``)
    delta: np.ndarray  # (N,) bool: the material here is a mirror or glass
    t: np.ndarray  # (N,) distance from the previous vertex
    paths: Paths  # the paths that arrived here, row for row
    #: (N, 3) unit geometric normal, turned to the side of wo, where it differs from ``n``;
    #: None: the same as ``n`` (a flat surface, and a vertex a chapter's code makes).
    geometric_normal: np.ndarray | None = None

    @property
    def ng(self) -> np.ndarray:
        """(N, 3) the unit geometric normal, turned to the side of wo (``n`` itself where the
        surface is flat)."""
        return self.n if self.geometric_normal is None else self.geometric_normal

    @property
    def smooth(self) -> bool:
        """The shading normal ``n`` is not the geometric one ``ng``."""
        return self.geometric_normal is not None

    # The paths' fields, read (and throughput and pixel written) through the vertex, as
    # chapter 7's files do.
    @property
    def throughput(self) -> np.ndarray:
        """(N, 3) float32: the paths' throughput."""
        return self.paths.throughput

    @throughput.setter
    def throughput(self, value: np.ndarray) -> None:
        self.paths.throughput = value

    @property
    def pixel(self) -> np.ndarray:
        """(N,) intp: the film rows the paths add their radiance to."""
        return self.paths.pixel

    @pixel.setter
    def pixel(self, value: np.ndarray) -> None:
        self.paths.pixel = value

    @property
    def sees_emission(self) -> np.ndarray:
        """(N,) bool, from the ray that arrived here."""
        return self.paths.sees_emission

    @property
    def sample(self) -> np.ndarray:
        """(N,) uint64 sampler keys (``ptlab.samplers``)."""
        return self.paths.sample

    @property
    def pdf(self) -> np.ndarray | None:
        """(N,) the pdf with which the previous vertex chose this direction, or None."""
        return self.paths.pdf

    @property
    def depth(self) -> int | np.ndarray:
        """The paths' depth (``Paths.depth``)."""
        return self.paths.depth

    @property
    def bsdf(self) -> HitBSDF:
        """The materials at these vertices, asked as one BSDF (``HitBSDF``)."""
        return HitBSDF(self)


@dataclass(frozen=True)
class BSDFSample:
    """Directions drawn from each vertex's material, with what the path needs of them
    (pbrt-v4's ``BSDFSample``, Mitsuba 3's ``BSDFSample3f``).

    Attributes:
        wi: (N, 3) unit directions, away from the surface.
        weight: (N, 3) f_r |cos theta_i| / pdf: what the throughput is multiplied by.
        pdf: (N,) the solid-angle density of ``wi``, where asked for (MIS weighs emission
            found along ``wi`` by it); else None.
        delta: (N,) bool: the material is a mirror or glass (its pdf has no value).
    """

    wi: np.ndarray
    weight: np.ndarray
    pdf: np.ndarray | None
    delta: np.ndarray


class HitBSDF:
    """The materials of a batch of vertices, asked as one BSDF at the vertices' ``wo`` and
    normals: ``f(wi)``, ``pdf(wi)`` and ``sample(u)``, each row by its own material. (A
    student's file, holding to the homework's three functions, calls ``shade`` instead.)"""

    def __init__(self, hit: SurfaceHit):
        self.hit = hit

    def f(self, wi: np.ndarray) -> np.ndarray:
        """(N, 3) f_r(wo, wi), cosine not included (``Material.eval``)."""
        hit = self.hit
        return _each_material(hit, "eval", hit.wo, wi, hit.n)

    def pdf(self, wi: np.ndarray) -> np.ndarray:
        """(N,) the density with which ``sample`` would have drawn ``wi`` (``Material.pdf``)."""
        hit = self.hit
        return _each_material(hit, "pdf", hit.wo, wi, hit.n)

    def sample(self, u: np.ndarray, with_pdf: bool = False) -> BSDFSample:
        """Draw a direction per row from (N, 2) uniforms ``u``; its pdf too if ``with_pdf``
        (``Material.sample_weight`` and ``sample_weight_pdf``)."""
        hit = self.hit
        if with_pdf:  # (the sample carries its pdf: ``Material.sample_weight_pdf``)
            wi, weight, pdf = _each_material(hit, "sample_weight_pdf", hit.wo, hit.n, u, hit.front)
            return BSDFSample(wi, weight, pdf, hit.delta)
        wi, weight = _each_material(hit, "sample_weight", hit.wo, hit.n, u, hit.front)
        return BSDFSample(wi, weight, None, hit.delta)


@overload
def kept(a: np.ndarray, rows: np.ndarray, every_row: bool) -> np.ndarray: ...
@overload
def kept(a: None, rows: np.ndarray, every_row: bool) -> None: ...
def kept(a: np.ndarray | None, rows: np.ndarray, every_row: bool) -> np.ndarray | None:
    """Rows ``rows`` of ``a`` (None stays None); ``a`` itself, not a copy, when ``rows`` are
    all of its rows, as after the first bounces in a closed room, where no path ends."""
    if a is None or every_row:
        return a
    return take_rows(a, rows)


def surface_hit(scene: Scene, paths: Paths, hits) -> SurfaceHit:
    """The vertices of the paths that hit something; the others are dropped.

    Where every path hit (as in a closed room), the vertices share the paths' arrays: no copy.
    """
    alive = np.flatnonzero(hits.prim >= 0)
    every = len(alive) == len(hits.prim)
    if not every:
        paths = paths.take(alive)
    prim = kept(hits.prim, alive, every)
    # One gather of the triangles' packed data instead of five (``Scene.triangle_data``).
    data = scene.triangle_data.take(prim, axis=1)  # (13, N); .T gives (N, 3) views
    v0, e1, e2, n, offset = data[0:3].T, data[3:6].T, data[6:9].T, data[9:12].T, data[12]
    u, v = kept(hits.u, alive, every)[:, None], kept(hits.v, alive, every)[:, None]
    # The point from its barycentrics: more accurate than origin + t * dir (pbrt-v4 6.8.5),
    # computed in place: v0 + u e1 + v e2 with two temporaries fewer.
    p = u * e1
    p += v0
    p += v * e2
    wo = -paths.dirs
    front = dot(n, wo) > 0
    # Materials are two-sided: shade on the side the ray came from.
    n = n * np.where(front, np.float32(1), np.float32(-1))[:, None]
    geometric = None
    if scene.corner_normals is not None:
        # Smooth shading: the corners' normals interpolated and, as the geometric normal just
        # was, turned to the side of wo by their own sign (a material shades in the hemisphere
        # around n that holds wo, as pbrt-v4's BxDFs and Mitsuba 3's two-sided BSDFs do); the
        # geometric normal keeps its other duties.
        geometric = n
        n = scene.shading_normals_at(prim, u[:, 0], v[:, 0], geometric)
        n *= np.where(dot(n, wo) >= 0, np.float32(1), np.float32(-1))[:, None]
    uv = scene.uv_at(prim, u[:, 0], v[:, 0]) if scene.triangle_uv is not None else None
    materials = material_groups(scene, prim, uv)
    delta = np.zeros(len(prim), dtype=bool)
    for rows, material in materials:
        if material.is_delta:
            delta[slice(None) if rows is None else rows] = True
    tally = _nonfinite.get()
    if tally is not None:
        tally.bounces += 1  # (the depth a student's loop is at, for ``NonFinite``)
    hit = SurfaceHit(
        prim=prim,
        p=p,
        n=n,
        wo=wo,
        front=front,
        offset=offset,
        materials=materials,
        delta=delta,
        t=kept(hits.t, alive, every),
        paths=paths,
        geometric_normal=geometric,
    )
    if (rec := _recorder.get()) is not None:
        rec.vertices(scene, hit)
    return hit


#: The inspector's recorder (``ptlab.inspector``), None when off. The integrators ask for it
#: once per step of a bounce, never per ray: while off it costs a lookup of about 60 ns a
#: step, some 160 of them in a 256 x 256 x 16 render (docs/rendering.md, "One pixel, vertex by vertex").
_recorder: ContextVar = ContextVar("recorder", default=None)


def recorder():
    """The recorder of ``recording`` under way, or None (the integrators' hooks: ``if (rec :=
    recorder()) is not None: rec.<step>(...)``)."""
    return _recorder.get()


@contextmanager
def recording(rec) -> Iterator:
    """Let the integrators report each step of each bounce to ``rec`` while the block runs
    (``ptlab.inspector.Recorder``)."""
    token = _recorder.set(rec)
    try:
        yield rec
    finally:
        _recorder.reset(token)


@dataclass
class NonFinite:
    """The samples whose radiance was NaN or infinite (a material's bug, a pdf of 0), which
    ``add_to_film`` left out of the film. A sample here is one row that ``add_to_film`` was
    given: a path adds one at each vertex where it finds light.

    Attributes:
        count: how many.
        first_row: the film row of the first of them (-1 while there is none).
        first_depth: the depth at which it was found (-1 while there is none).
        rows: the film rows of all of them, an array per ``add_to_film`` call that had some.
        depths: their depths, arrays alike.
        bounces: the vertices found so far (``surface_hit`` calls): the depth of a loop that
            does not say its own.
    """

    count: int = 0
    first_row: int = -1
    first_depth: int = -1
    rows: list[np.ndarray] = field(default_factory=list)
    depths: list[np.ndarray] = field(default_factory=list)
    bounces: int = 0


#: Where ``add_to_film`` counts, inside ``counting_nonfinite`` (one per thread: each thread
#: runs in a context of its own, so jobs on threads count apart).
_nonfinite: ContextVar[NonFinite | None] = ContextVar("nonfinite", default=None)


@contextmanager
def counting_nonfinite() -> Iterator[NonFinite]:
    """Count, in the ``NonFinite`` yielded, the samples that ``add_to_film`` leaves out
    while the block runs (``ptlab.rendering.jobs.run_jobs`` counts each job's)."""
    tally = NonFinite()
    token = _nonfinite.set(tally)
    try:
        yield tally
    finally:
        _nonfinite.reset(token)


def add_to_film(
    film: np.ndarray, pixel: np.ndarray, radiance: np.ndarray, depth: int | np.ndarray | None = None
) -> None:
    """film[pixel[k]] += radiance[k] for every k, in float64.

    A film has a row per pixel, or, in a render, a row per path (``ptlab.rendering.jobs``,
    which sums a pixel's paths afterwards, in one order whatever the batch they were traced in).
    A NaN or infinite sample is left out, so that it does not poison its pixel for good, and
    counted (``counting_nonfinite``, with ``depth``, the sample's bounce, where the caller
    knows it; outside it, a ``RuntimeWarning`` says so), so that the bug that made it does not
    go unseen. One sum over the samples finds them: the common case costs little.
    """
    if not np.isfinite(radiance.sum()):
        bad = ~np.isfinite(radiance).all(axis=1)
        if bad.any():  # (else finite samples whose sum overflowed: kept)
            count_nonfinite(pixel[bad], depth[bad] if isinstance(depth, np.ndarray) else depth)
            keep = np.flatnonzero(~bad)
            pixel, radiance = pixel.take(keep), take_rows(radiance, keep)
    if len(pixel) and (pixel[1:] > pixel[:-1]).all():
        # Each row once (a batch's paths, in order): add in place, column by column.
        for c in range(3):
            column = film[:, c]
            column[pixel] += radiance[:, c]
    elif len(pixel) > len(film) // 8:
        # ``np.bincount`` with weights sums repeated rows correctly, and faster than
        # ``np.add.at`` when the rows are many (docs/performance.md).
        sums = [np.bincount(pixel, weights=radiance[:, c], minlength=len(film)) for c in range(3)]
        film += np.stack(sums, axis=1)
    else:
        np.add.at(film, pixel, radiance)


def count_nonfinite(pixel: np.ndarray, depth: int | np.ndarray | None) -> None:
    """Count samples left out of the film at film rows ``pixel``, found at ``depth`` (one, one
    per sample, or None: the bounces counted so far say) (``NonFinite``; the graders count
    here those that a student's process left out)."""
    tally = _nonfinite.get()
    if tally is None:
        warnings.warn(
            f"{len(pixel)} samples were NaN or infinite and were left out of the film",
            RuntimeWarning,
            stacklevel=3,
        )
        return
    if depth is None:
        depth = max(tally.bounces - 1, 0)
    depths = np.broadcast_to(np.asarray(depth, dtype=np.intp), pixel.shape)
    if tally.count == 0:
        tally.first_row, tally.first_depth = int(pixel[0]), int(depths[0])
    tally.count += len(pixel)
    tally.rows.append(pixel)
    tally.depths.append(depths)


def sees(accel: Accelerator, hit: SurfaceHit, rows: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """(N,) bool: which vertices see their light sample, by one shadow ray each from the
    vertices ``rows`` (the others count as not seeing it) to ``targets`` (len(rows), 3).

    The ray starts ``offset`` off the surface on the side of the geometric normal
    (``leave_surface``; only rows whose light lies above the shading normal come here, which
    on a flat surface is that side) and stops ``SHADOW_EPSILON`` short of the target, so that
    neither the surface it leaves nor the light blocks it.
    """
    p, ng, offset = take_rows(hit.p, rows), take_rows(hit.ng, rows), hit.offset.take(rows)
    if hit.smooth:
        # Above the shading normal may be below the surface: leave on the target's side.
        offset = np.where(dot(targets - p, ng) >= 0, offset, -offset)
    origin = p + offset[:, None] * ng
    visible = np.zeros(len(hit.prim), dtype=bool)
    visible[rows] = ~accel.occluded(origin, targets - origin, 1.0 - SHADOW_EPSILON)
    return visible


def leave_surface(p: np.ndarray, n: np.ndarray, offset: np.ndarray, wi: np.ndarray) -> np.ndarray:
    """(N, 3) origins of new rays from points ``p`` along ``wi``: moved ``offset`` off the
    surface along ``n``, to the side ``wi`` goes to (so a ray neither hits the surface it
    leaves nor starts on the wrong side of it; pbrt-v4's ``OffsetRayOrigin``)."""
    side = np.where(dot(wi, n) >= 0, offset, -offset)
    return p + side[:, None] * n


def material_groups(scene: Scene, prim: np.ndarray, uv: np.ndarray | None = None) -> list:
    """[(rows, material)]: the material that shades each group of hits.

    Materials of one kind (all ``Diffuse`` in the Cornell box) are stacked into one
    (``Scene.material_table``) whose parameters are taken per hit, so the common case is
    one group over every row (``rows`` is None: no copying at all). A textured material
    looks its parameters up at the hits' texture coordinates ``uv`` (N, 2).
    """
    table = scene.material_table
    if len(table.groups) == 1:
        return [(None, taken(table.groups[0], table.triangle_row.take(prim), uv))]
    group_of = table.triangle_group.take(prim)
    groups = []
    for g, stacked in enumerate(table.groups):
        rows = np.flatnonzero(group_of == g)
        if len(rows):
            groups.append(
                (
                    rows,
                    taken(
                        stacked,
                        table.triangle_row.take(prim.take(rows)),
                        None if uv is None else take_rows(uv, rows),
                    ),
                )
            )
    return groups


def taken(stacked, index: np.ndarray, uv: np.ndarray | None):
    """``stacked.take(index)``: a stacked material's parameters for each hit, looked up at
    the hits' uv for a textured one (``Material.take``)."""
    return stacked.take(index, uv) if getattr(stacked, "textured", False) else stacked.take(index)


def shade(hit: SurfaceHit, method: str, *arrays: np.ndarray):
    """Call ``material.<method>(*arrays)`` for every hit, each with its own material: the
    homework's three functions by name, as chapter 7's files call them (the renderer asks
    ``hit.bsdf``, the same calls with their names fixed)."""
    return _each_material(hit, method, *arrays)


def _each_material(hit: SurfaceHit, method: str, *arrays: np.ndarray):
    """``material.<method>(*arrays)`` for every hit, each with its own material: with
    several groups the rows of each are gathered, shaded and put back."""
    if hit.materials[0][0] is None:
        return getattr(hit.materials[0][1], method)(*arrays)
    outputs: tuple[np.ndarray, ...] = ()
    for rows, material in hit.materials:
        result = getattr(material, method)(*(take_rows(a, rows) for a in arrays))
        parts = result if isinstance(result, tuple) else (result,)
        if not outputs:
            outputs = tuple(np.zeros((len(hit.prim), *r.shape[1:]), r.dtype, order="F") for r in parts)
        for out, part in zip(outputs, parts, strict=True):
            out[rows] = part
    return outputs if len(outputs) > 1 else outputs[0]
