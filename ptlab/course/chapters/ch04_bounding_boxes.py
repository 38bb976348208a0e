"""Chapter 4's checks: the slab test (``slab_test``), ray against axis-aligned box.

Known answers come from the slabs themselves (Kay and Kajiya 1986; GAMES101 lecture 13;
pbrt-v4 6.1.2): unit boxes entered through each face, along each axis and backwards,
boxes behind the ray or beyond ``tmax``, rays that start inside, rays parallel to a slab
(``inv_dirs = ±inf``; on a boundary plane ``0 * inf`` is NaN), and flat boxes of zero
thickness like the leaves around the Cornell box's walls. Then the student's slab test
runs inside the NumPy BVH: the Cornell box's normals must come out as the library's, and a
row of balls seen end on must cost no more boxes per camera ray than the library's slab
test enters (``WORK_TOLERANCE``). The BVH tests every triangle's t against [tmin, tmax]
itself, so a slab test that ignores them draws the right picture; what it changes is the
work: boxes behind the nearest hit so far are entered too.

Every grading moves each case by a mirroring and permutation of the axes and a shift of its
own (``_moved``, from the grading seed): the same hits at the same t, other numbers, so no
answers stored for known inputs match.
"""

from __future__ import annotations

import numpy as np

from ptlab.course.chapter import (
    Chapter,
    ChapterCheck,
    ChapterRender,
    CheckFailed,
    grading_rng,
    grading_seed_for,
    require,
)
from ptlab.course.messages import aside, text
from ptlab.rendering.pieces import BVHPieces, Pieces

UNIT_BOX = ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
FLAT_BOX = ((0.0, 0.0, 1.0), (1.0, 1.0, 1.0))  # the square z = 1, 0 <= x, y <= 1


def _moved(origins, dirs, box_min, box_max) -> tuple[np.ndarray, ...]:
    """(N, 3) rays and boxes with their axes permuted and mirrored, and shifted by multiples
    of 1/16, all drawn from the grading seed: exact in float32 for the cases here (a ray on
    a slab's plane stays on it), and the same hits at the same t."""
    rng = grading_rng(40)
    axes, signs = rng.permutation(3), rng.choice([-1.0, 1.0], 3)
    shift = rng.integers(-32, 33, 3) / 16
    # (taking columns, not a product with a matrix, keeps the sign of a -0.0)
    origins, dirs, corner_a, corner_b = (
        np.asarray(a, dtype=np.float64)[:, axes] * signs for a in (origins, dirs, box_min, box_max)
    )
    corner_a, corner_b = corner_a + shift, corner_b + shift
    return origins + shift, dirs, np.minimum(corner_a, corner_b), np.maximum(corner_a, corner_b)


def _slab(module, origins, dirs, box_min, box_max, tmin=0.0, tmax=np.inf):
    """The student's (hit, t_enter) for rays and boxes (one box for all, or one per ray),
    ``_moved`` by the grading seed, checked for shape, type and NaN."""
    (slab_test,) = require(module, "slab_test")
    origins = np.asarray(origins, dtype=np.float32).reshape(-1, 3)
    dirs = np.asarray(dirs, dtype=np.float32).reshape(-1, 3)
    n = len(origins)
    box_min = np.broadcast_to(np.asarray(box_min, dtype=np.float32), (n, 3))
    box_max = np.broadcast_to(np.asarray(box_max, dtype=np.float32), (n, 3))
    origins, dirs, box_min, box_max = (a.astype(np.float32) for a in _moved(origins, dirs, box_min, box_max))
    with np.errstate(divide="ignore"):
        inv_dirs = (1 / dirs).astype(np.float32)
    with np.errstate(all="ignore"):  # NaN and inf are judged below, not warned about
        result = slab_test(origins, inv_dirs, box_min, box_max, np.copy(tmin), np.copy(tmax))
    return _checked(result, n)


def _checked(result, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The student's (hit, t_enter) as arrays of shape (n,), or a clear failure."""
    if not (isinstance(result, tuple) and len(result) == 2):
        raise CheckFailed(text("ch04.two_arrays"))
    hit, t_enter = np.asarray(result[0]), np.asarray(result[1])
    if hit.shape != (n,) or t_enter.shape != (n,):
        raise CheckFailed(text("ch04.shapes", n=n, hit=hit.shape, t_enter=t_enter.shape))
    if hit.dtype != bool:
        raise CheckFailed(text("ch04.bool", dtype=hit.dtype))
    nan = np.flatnonzero(hit & np.isnan(t_enter))
    if len(nan):
        raise CheckFailed(text("ch04.nan", count=len(nan), row=nan[0], n=n))
    return hit, t_enter


def _expect(module, cases, what: str, box=UNIT_BOX, **limits) -> int:
    """Each case (origin, dir, hit, t_enter or None) against the student's answer; ``what``:
    the id of what the cases are."""
    what = text(what)
    origins, dirs, want_hit, want_t = zip(*cases, strict=True)
    hit, t_enter = _slab(module, origins, dirs, *box, **limits)
    for i, (o, d) in enumerate(zip(origins, dirs, strict=True)):
        if hit[i] != want_hit[i]:
            verdict = "ch04.should_hit" if want_hit[i] else "ch04.should_miss"
            hint = aside(_swap_hint(module)) if want_hit[i] else ""
            corners = [list(c) for c in box]
            raise CheckFailed(text(verdict, what=what, o=list(o), d=list(d), box=corners) + hint)
        if (
            want_hit[i]
            and want_t[i] is not None
            and not np.isclose(t_enter[i], want_t[i], rtol=1e-5, atol=1e-6)
        ):
            raise CheckFailed(
                text("ch04.enters_at", what=what, o=list(o), d=list(d), t=want_t[i], yours=t_enter[i])
            )
    return len(cases)


def check_entering(module) -> str:
    n = _expect(
        module,
        [
            ((-1, 0.5, 0.5), (2, 0, 0), True, 0.5),  # through the x = 0 face
            ((0.5, -2, 0.5), (0, 1, 0), True, 2.0),  # the y = 0 face
            ((0.5, 0.5, -4), (0, 0, 2), True, 2.0),  # the z = 0 face, t in |d|s
            ((-1, -1, 0.5), (1, 1.5, 0), True, 1.0),  # slanted: x enters last
            ((-0.5, 0.25, -1), (1, 0.25, 2), True, 0.5),  # slanted: x and z tie
        ],
        "ch04.entering",
    )
    return text("ch04.entering_ok", n=n)


def check_backwards(module) -> str:
    n = _expect(
        module,
        [
            ((2, 0.5, 0.5), (-1, 0, 0), True, 1.0),  # through x = 1, going -x
            ((0.5, 3, 0.5), (0, -2, 0), True, 1.0),
            ((0.5, 0.5, 1.5), (0, 0, -1), True, 0.5),
            ((2, 2, 2), (-1, -1, -1), True, 1.0),  # into the far corner
            ((1.5, -0.5, 0.5), (-1, 1, 0), True, 0.5),
        ],
        "ch04.backwards",
    )
    return text("ch04.backwards_ok", n=n)


def check_misses(module) -> str:
    n = _expect(
        module,
        [
            ((-1, 0.5, 0.5), (1, 1, 0), False, None),  # passes by the corner
            ((-1, 2, 0.5), (1, 0.1, 0), False, None),  # above the box
            ((-1, 0.5, 0.5), (-1, 0, 0), False, None),  # the box is behind
            ((3, 0.5, 0.5), (1, 0, 0), False, None),  # behind, on the other side
        ],
        "ch04.missing",
    )
    n += _expect(
        module,
        [
            ((-1, 0.5, 0.5), (1, 0, 0), False, None),  # enters at 1 > tmax
            ((-1, 0.5, 0.5), (1, 0, 0), True, 1.0),
        ],
        "ch04.with_tmax",
        tmax=np.array([0.9, 1.5], np.float32),
    )
    n += _expect(
        module,
        [((-1, 0.5, 0.5), (1, 0, 0), False, None)],  # leaves at 2 < tmin
        "ch04.with_tmin",
        tmin=2.5,
    )
    return text("ch04.misses_ok", n=n)


def check_inside(module) -> str:
    n = _expect(
        module,
        [
            ((0.5, 0.5, 0.5), (1, 1, 1), True, 0.0),
            ((0.5, 0.5, 0.5), (0, 0, -1), True, 0.0),
            ((0.1, 0.9, 0.2), (-1, 0, 0), True, 0.0),
        ],
        "ch04.inside",
    )
    n += _expect(
        module,
        [((-1, 0.5, 0.5), (1, 0, 0), True, 1.5), ((0.5, 0.5, 0.5), (0, 1, 0), True, 0.25)],
        "ch04.with_tmins",
        tmin=np.array([1.5, 0.25], np.float32),
    )
    return text("ch04.inside_ok", n=n)


def check_parallel(module) -> str:
    n = _expect(
        module,
        [
            ((-1, 0.5, 0.5), (1, 0, 0), True, 1.0),  # inside the y and z slabs
            ((-1, 2, 0.5), (1, 0, 0), False, None),  # outside the y slab
            ((0.5, 0.5, -1), (0, 0, 1), True, 1.0),
            ((0.5, -0.5, -1), (0, 0, 1), False, None),
            ((0.5, 1.5, 0.5), (0, -1, 0), True, 0.5),
        ],
        "ch04.parallel",
    )
    n += _expect(
        module,
        [
            ((-1, 1, 0.5), (1, 0, 0), True, 1.0),  # on the y = 1 plane
            ((-1, 0, 0), (1, 0, 0), True, 1.0),  # along an edge
            ((0.5, 0, 3), (0, 0, -1), True, 2.0),
            ((-1, 0, 0.5), (1, -0.0, 0), True, 1.0),  # -0.0: inv_dirs = -inf
        ],
        "ch04.on_face",
    )
    return text("ch04.parallel_ok", n=n)


def check_flat(module) -> str:
    n = _expect(
        module,
        [
            ((0.5, 0.5, 0), (0, 0, 1), True, 1.0),  # perpendicular
            ((0.5, 0.5, 3), (0, 0, -2), True, 1.0),  # from the other side
            ((0, 0, 0), (1, 1, 1), True, 1.0),  # through a corner
            ((0.2, -0.6, 0), (0.1, 1, 1), True, 1.0),  # slanted
            ((2, 0.5, 0), (0, 0, 1), False, None),  # beside it
            ((0.5, 0.5, 2), (0, 0, 1), False, None),  # behind
            ((-1, 0.5, 1), (1, 0, 0), True, 1.0),  # in its plane
        ],
        "ch04.flat",
        box=FLAT_BOX,
    )
    return text("ch04.flat_ok", n=n)


#: The render check's second view: a row of balls seen end on, where a camera ray that
#: hits the first ball enters few boxes when the slab test culls those beyond tmax (the
#: nearest hit so far). A slab test that ignores tmin and tmax enters 2.6 times as many
#: (measured: 21.0 boxes per ray against the library's 8.2); a right one as many, or a few
#: fewer where it rounds otherwise at a box's faces (the library's widens them by a
#: rounding bound). The student's may enter at most WORK_TOLERANCE more.
WORK_TOLERANCE = 0.05
#: The row of balls' view (``ptlab.render``'s keywords): ROW_SPP camera rays through each
#: pixel of a ROW_RES (width, height) image, on the NumPy BVH.
ROW_RES = (32, 32)
ROW_SPP = 1
ROW_VIEW = dict(spp=ROW_SPP, res=ROW_RES, integrator="normals", workers=1, backend="numpy")


def _row_of_balls():
    """Eight balls in a row along x, seen end on from before the first."""
    from ptlab.camera import Camera
    from ptlab.course.chapters.ch05_bvh import _ball
    from ptlab.materials import Diffuse
    from ptlab.scene import Scene

    triangles = np.concatenate([_ball([3.0 * i, 0, 0], 1.0) for i in range(8)])
    camera = Camera.look_at((-6, 0.3, 0.2), (21, 0, 0), fov_y=25)
    with np.errstate(invalid="ignore"):  # (the balls' poles have triangles of no area)
        return Scene(triangles, np.zeros(len(triangles), int), [Diffuse((0.5, 0.5, 0.5))], camera)


def boxes_entered(slab_test, seed: int) -> float:
    """The boxes a camera ray enters on average, rendering ``_row_of_balls``' normals with
    ``slab_test`` in the NumPy BVH."""
    import ptlab

    entered = 0

    def counting(*arguments):
        nonlocal entered
        hit, t_enter = slab_test(*arguments)
        entered += int(np.count_nonzero(hit))
        return hit, t_enter

    # (A tree given a slab test of its own walks the tree whatever the scene's size.)
    ptlab.render(_row_of_balls(), seed=seed, **ROW_VIEW, pieces=Pieces(bvh=BVHPieces(slab_test=counting)))
    width, height = ROW_RES
    return entered / (width * height * ROW_SPP)


def _student_slab_test(module) -> Pieces:
    """A render's pieces with the student's ``slab_test`` in the NumPy BVH, its results
    checked."""
    (slab_test,) = require(module, "slab_test")

    def student_slab_test(origins, inv_dirs, box_min, box_max, tmin, tmax):
        with np.errstate(all="ignore"):
            result = slab_test(origins, inv_dirs, box_min, box_max, tmin, tmax)
        return _checked(result, len(origins))

    return Pieces(bvh=BVHPieces(slab_test=student_slab_test))


def check_render(module) -> str:
    from ptlab.course.renders import check_render_through

    pieces = _student_slab_test(module)
    hint = _swap_hint(module)
    note = check_render_through(
        text("ch04.yours"),
        pieces,
        hint=hint or text("ch04.hint.render"),
        missing_hint=hint or text("ch04.hint.missing"),
    )
    seed = grading_seed_for(41)
    library = boxes_entered(BVHPieces().slab_test, seed)
    student = boxes_entered(pieces.bvh.slab_test, seed)
    if not student <= library * (1 + WORK_TOLERANCE):
        raise CheckFailed(text("ch04.work", student=student, library=library))
    return note + text("ch04.work_ok", student=student, library=library)


def _swap_hint(module) -> str:
    """The min/max swap named, if rays going up each axis enter the unit box and rays going
    down it do not (as they are, not ``_moved``: mirroring turns one into the other); else
    ""."""
    (slab_test,) = require(module, "slab_test")
    eye = np.eye(3, dtype=np.float32)
    with np.errstate(divide="ignore"):
        inv_dirs = 1 / np.concatenate([eye, -eye])
    origins = np.concatenate([0.5 - 1.5 * eye, 0.5 + 1.5 * eye]).astype(np.float32)
    box = [np.zeros((6, 3), np.float32), np.ones((6, 3), np.float32)]
    with np.errstate(all="ignore"):
        hit, _ = _checked(slab_test(origins, inv_dirs, *box, np.float32(0), np.float32(np.inf)), 6)
    return text("ch04.hint.swap") if hit[:3].all() and not hit[3:].any() else ""


def render_yours(module, scene, options: dict) -> np.ndarray:
    """``scene`` rendered through the student's slab test (``ptlab exercise render``), on the
    NumPy BVH, which walks its tree through it whatever the scene's size."""
    from ptlab.course.side_by_side import render_with_pieces

    return render_with_pieces(scene, options, _student_slab_test(module))


CHAPTER = Chapter(
    number=4,
    slug="bounding_boxes",
    title="Bounding boxes: the slab test",
    functions=("slab_test",),
    answers=("ptlab.accel.numpy_bvh.slab_test",),
    # A box is twelve triangles: any ray-triangle query finds where a ray enters it.
    also_left_out=("ptlab.accel.embree", "ptlab.accel.numpy_bvh", "ptlab.accel.triangle"),
    packages=("numpy", "scipy"),
    checks=(
        ChapterCheck("entering a box", 2, check_entering, timeout=30),
        ChapterCheck("going backwards", 1, check_backwards, timeout=30),
        ChapterCheck("misses", 1, check_misses, timeout=30),
        # "Every ray hits at tmin" is right for rays that start inside: that check scores
        # only once the slab test finds where rays enter. It draws the right picture too
        # (the BVH then tests every triangle), but not the row of balls' few boxes: the
        # render fails it by itself, and waits only for rays to enter boxes, not for
        # 'misses' (which a slab test that ignores tmin and tmax fails, as the render does).
        ChapterCheck("starting inside", 1, check_inside, timeout=30, requires=("entering a box",)),
        ChapterCheck("parallel to a slab", 1, check_parallel, timeout=30),
        ChapterCheck("flat boxes", 2, check_flat, timeout=30),
        ChapterCheck("render", 2, check_render, timeout=60, requires=("entering a box",)),
    ),
    render=ChapterRender(render_yours, options=dict(backend="numpy")),
)
