"""Chapter 2's checks: ray-triangle intersection, Möller-Trumbore (``ray_triangle``).

Known answers come from the definition of the hit: ``o + t d = (1 - u - v) v0 + u v1 + v v2``
(Möller and Trumbore 1997; GAMES101 lecture 13). Rays are aimed at chosen ``(t, u, v)``,
just inside and just outside each edge, parallel to the triangle, at triangles behind the
origin and at the back face; 2000 random rays and triangles are compared with a direct
linear solve. The hit checks judge ``t`` (whether and where a ray hits), the barycentrics
check ``u, v`` of the same rays: an answer without barycentrics earns the hits. Then the
student's function runs inside the NumPy BVH, and a path-traced Cornell box (whose hit
points are built from ``u, v``) must match the library's.

Every grading moves the whole of each case by a turn and a shift of its own (``_moved``,
from the grading seed), which leaves ``(t, u, v)`` as they are; the random rays and the
render's seed come from the grading seed too. So no answers stored for known inputs match.
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
from ptlab.course.finite import require_finite
from ptlab.course.messages import aside, text
from ptlab.rendering.pieces import BVHPieces, Pieces

#: The unit triangle in the plane z = 0, and a triangle in general position, each with a
#: direction that sees its front face (det > 0; the opposite direction sees its back).
UNIT = ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
UNIT_FRONT = (0.0, 0.0, -1.0)
SLANTED = ((1.0, 2.0, 3.0), (4.0, 1.0, 2.0), (2.0, 5.0, 1.5))
SLANTED_FRONT = (-0.3, 0.4, -1.2)

#: The render check: the Cornell box path-traced (direct light and one bounce: the hit
#: points, built from u and v, start the shadow rays and the bounce) through the NumPy BVH,
#: cut into passes whose spread gives the standard errors; ``renders.compare_renders``
#: compares the regions (false-alarm rate at most 1e-3). The library's picture comes from
#: the fastest backend: the same hits, so the same picture up to rounding.
RENDER = dict(res=32, passes=8, spp_per_pass=4, integrator="path", max_depth=2)
#: The stream of the grading seed that the render check's seed comes from.
RENDER_SEED = 5


def _moved(origins, dirs, v0, e1, e2) -> tuple[np.ndarray, ...]:
    """The rays and triangles turned by one of the 24 rotations that permute the axes (with
    signs: exact in floating point, so a ray parallel to a triangle stays exactly parallel,
    and a front face stays a front face) and shifted by multiples of 1/16, both drawn from
    the grading seed: the same (t, u, v), other numbers."""
    rng = grading_rng(20)
    while True:
        turn = np.eye(3)[rng.permutation(3)] * rng.choice([-1.0, 1.0], 3)[:, None]
        if np.linalg.det(turn) > 0:
            break
    shift = rng.integers(-64, 65, 3) / 16
    points = (np.asarray(a, dtype=np.float64) @ turn.T for a in (origins, dirs, v0, e1, e2))
    origins, dirs, v0, e1, e2 = points
    return origins + shift, dirs, v0 + shift, e1, e2


def _call(module, origins, dirs, v0, e1, e2):
    """The student's (t, u, v) as float64 (N,) arrays, or a clear failure: for the rays and
    triangles ``_moved`` by the grading seed."""
    (ray_triangle,) = require(module, "ray_triangle")
    n = len(origins)
    origins, dirs, v0, e1, e2 = _moved(origins, dirs, v0, e1, e2)
    with np.errstate(all="ignore"):  # NaN and inf are judged below, not warned about
        result = ray_triangle(origins, dirs, v0, e1, e2)
    if not (isinstance(result, tuple) and len(result) == 3):
        raise CheckFailed(text("ch02.three_arrays"))
    t, u, v = (np.asarray(a, dtype=np.float64) for a in result)
    if t.shape != (n,) or u.shape != (n,) or v.shape != (n,):
        raise CheckFailed(text("ch02.shapes", n=n, t=t.shape, u=u.shape, v=v.shape))
    _require_finite_hits(t, u, v)
    return t, u, v


def _require_finite_hits(t: np.ndarray, u: np.ndarray, v: np.ndarray, bvh: bool = False) -> None:
    """Fail if t is NaN for a ray (a miss is inf), or u or v is NaN or infinite for a ray
    that hits (finite t), naming the first such ray (``bvh``: of those traced through the BVH)."""

    def ray(index, shape) -> str:
        return text("ch02.ray_of_bvh" if bvh else "ch02.ray_of", ray=index[0], rays=shape[0])

    require_finite(np.where(np.isinf(t), 0.0, t), "t", ray, hint=text("ch02.hint.det_zero"))
    hits = np.isfinite(t)
    for name, value in (("u", u), ("v", v)):
        require_finite(np.where(hits, value, 0.0), text("ch02.of_a_hit", name=name), ray)


def _aimed(triangle, uv, t, dirs):
    """Rays that reach the point ``uv`` (barycentrics) of ``triangle`` at parameter ``t``
    along ``dirs``, and the (N, 3) v0, e1, e2 of that triangle."""
    uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
    v0, e1, e2 = _edges(triangle, len(uv))
    dirs = np.broadcast_to(np.asarray(dirs, dtype=np.float64), (len(uv), 3)).copy()
    origins = v0 + uv[:, :1] * e1 + uv[:, 1:] * e2 - np.reshape(t, (-1, 1)) * dirs
    return origins, dirs, v0, e1, e2


def _edges(triangle, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(n, 3) copies of ``triangle``'s v0 and its edges e1 = v1 - v0, e2 = v2 - v0."""
    v0, v1, v2 = (np.asarray(p, dtype=np.float64) for p in triangle)
    return np.tile(v0, (n, 1)), np.tile(v1 - v0, (n, 1)), np.tile(v2 - v0, (n, 1))


def _expect_hits(module, triangle, uv, t, dirs, what: str, barycentrics: bool = False) -> int:
    """The student's hits at known (t, u, v): each must hit at ``t`` or, with
    ``barycentrics``, have (u, v) = ``uv`` where it hits (a miss is the hit checks' to
    report). A failure names the first one off. ``what``: the id of their description."""
    what = text(what)
    t_want = np.broadcast_to(np.asarray(t, dtype=np.float64), len(uv))
    t_got, u_got, v_got = _call(module, *_aimed(triangle, uv, t_want, dirs))
    for i, (u_want, v_want) in enumerate(uv):
        got, want = (t_got[i], u_got[i], v_got[i]), (t_want[i], u_want, v_want)
        if barycentrics:
            if not np.isfinite(t_got[i]) or np.allclose(got[1:], want[1:], rtol=1e-5, atol=1e-6):
                continue
            hint = ""
            if np.allclose((u_got[i], v_got[i]), (v_want, u_want), rtol=1e-5, atol=1e-6):
                hint = aside(text("ch02.hint.uv_swapped"))
            elif np.isclose(u_got[i] + v_got[i], 1 - u_want - v_want, atol=1e-6):
                hint = aside(text("ch02.hint.uv_weights"))
            raise CheckFailed(text("ch02.hits_at_uv", what=what, want=_fmt(want), got=_fmt(got[1:])) + hint)
        if np.isclose(t_got[i], t_want[i], rtol=1e-5, atol=1e-6):
            continue
        if not np.isfinite(t_got[i]):
            raise CheckFailed(
                text("ch02.misses", what=what, want=_fmt(want), t=t_got[i])
                + _miss_hint(triangle, dirs, t_want[i])
            )
        hint = aside(text("ch02.hint.t_sign")) if np.isclose(t_got[i], -t_want[i], rtol=1e-5) else ""
        raise CheckFailed(text("ch02.hits_at_t", what=what, want=_fmt(want), t=t_got[i]) + hint)
    return len(uv)


def _miss_hint(triangle, direction, t: float) -> str:
    """Why a ray that should hit at ``t`` may have been dropped: behind, or the back face."""
    v0, v1, v2 = (np.asarray(p, dtype=np.float64) for p in triangle)
    det = np.dot(v1 - v0, np.cross(direction, v2 - v0))
    if t < 0:
        return aside(text("ch02.hint.behind"))
    if det < 0:
        return aside(text("ch02.hint.back_face"))
    return ""


def _fmt(values) -> str:
    return "(" + ", ".join(f"{x:.4g}" for x in values) + ")"


#: Rays aimed at known points of a triangle, as ``_expect_hits`` takes them: (triangle, (u, v)
#: of each ray, t (one, or one per ray), direction, the id of what they are).
HitCase = tuple[
    tuple[tuple[float, float, float], ...],
    tuple[tuple[float, float], ...],
    float | tuple[float, ...],
    tuple[float, ...],
    str,
]
#: Those hitting the front face from in front, those hitting it from behind (negative t), and
#: those hitting the back face (det < 0).
FRONT_HITS: tuple[HitCase, ...] = (
    (UNIT, ((0.25, 0.5), (0.1, 0.1), (0.6, 0.3)), 1.0, UNIT_FRONT, "ch02.unit_triangle"),
    (SLANTED, ((0.2, 0.3), (0.7, 0.1), (0.05, 0.9)), (2.5, 0.5, 7.0), SLANTED_FRONT, "ch02.slanted_triangle"),
)
BEHIND_HITS: tuple[HitCase, ...] = (
    (UNIT, ((0.25, 0.5), (0.6, 0.2)), -1.0, UNIT_FRONT, "ch02.behind_triangle"),
)
BACK_HITS: tuple[HitCase, ...] = (
    (
        UNIT,
        ((0.25, 0.5), (0.6, 0.2)),
        1.0,
        tuple(np.negative(UNIT_FRONT)),
        "ch02.unit_back",
    ),
    (
        SLANTED,
        ((0.2, 0.3),),
        2.0,
        tuple(np.negative(SLANTED_FRONT)),
        "ch02.slanted_back",
    ),
)


def check_known_hits(module) -> str:
    n = sum(_expect_hits(module, *case) for case in FRONT_HITS)
    t, _, _ = _call(module, *_aimed(UNIT, [(0.25, 0.5)], 0.5, (0, 0, -2)))
    if not np.isclose(t[0], 0.5, rtol=1e-5):
        raise CheckFailed(text("ch02.long_direction", t=t[0]))
    return text("ch02.known_ok", n=n + 1)


def check_edges(module) -> str:
    eps = 0.01
    # (u, v) just outside and just inside each edge, and two far away.
    outside = {
        "ch02.edge.v0_v2": (-eps, 0.5),
        "ch02.edge.v0_v1": (0.5, -eps),
        "ch02.edge.v1_v2": (0.5, 0.5 + eps),
        "ch02.edge.v1_corner": (1.2, -0.1),
        "ch02.edge.far_side": (1.5, 1.5),
    }
    inside = [(eps, 0.5), (0.5, eps), (0.5, 0.5 - eps), (0.3, 0.3)]
    for triangle, dirs in ((UNIT, UNIT_FRONT), (SLANTED, SLANTED_FRONT)):
        t, _, _ = _call(module, *_aimed(triangle, list(outside.values()), 2.0, dirs))
        for (edge, uv), t_i in zip(outside.items(), t, strict=True):
            if np.isfinite(t_i):
                test = "u + v <= 1" if edge == "ch02.edge.v1_v2" else "u >= 0 and v >= 0"
                raise CheckFailed(text("ch02.outside", uv=uv, edge=text(edge), t=t_i, test=test))
        n_inside = _expect_hits(module, triangle, inside, 2.0, dirs, "ch02.just_inside")
    return text("ch02.edges_ok", n=n_inside)


def check_parallel(module) -> str:
    cases = {
        "ch02.parallel.above": ((0.25, 0.5, 1.0), (1.0, 0.0, 0.0)),
        "ch02.parallel.in_plane": ((0.25, 0.5, 0.0), (1.0, 1.0, 0.0)),
        "ch02.parallel.crossing": ((-1.0, 0.2, 0.0), (1.0, 0.0, 0.0)),
    }
    origins, dirs = (np.array(a, dtype=np.float64) for a in zip(*cases.values(), strict=True))
    t, _, _ = _call(module, origins, dirs, *_edges(UNIT, len(cases)))
    for what, t_i in zip(cases, t, strict=True):
        if t_i != np.inf:
            raise CheckFailed(text("ch02.parallel", what=text(what), t=t_i))
    return text("ch02.parallel_ok")


def check_behind(module) -> str:
    ((triangle, uv, t_want, dirs, _),) = BEHIND_HITS
    t, _, _ = _call(module, *_aimed(triangle, uv, t_want, dirs))
    if not np.all(np.isfinite(t)):
        raise CheckFailed(text("ch02.behind_inf"))
    if not np.allclose(t, t_want, rtol=1e-5):
        raise CheckFailed(text("ch02.behind_t", t=_fmt(t)))
    return text("ch02.behind_ok")


def check_both_faces(module) -> str:
    n = sum(_expect_hits(module, *case) for case in BACK_HITS)
    return text("ch02.faces_ok", n=n)


def _random_cases(n: int = 2000):
    """``n`` random rays and triangles (o, d, v0, e1, e2), each ray's (t, u, v) from a direct
    3 x 3 linear solve of o + t d = v0 + u e1 + v e2, and whether the ray hits (inside)."""
    rng = grading_rng(1)
    o, d, v0, e1, e2 = (rng.normal(size=(n, 3)) for _ in range(5))
    tuv = np.linalg.solve(np.stack([d, -e1, -e2], axis=-1), (v0 - o)[..., None])[..., 0]
    inside = (tuv[:, 1] >= 0) & (tuv[:, 2] >= 0) & (tuv[:, 1] + tuv[:, 2] <= 1)
    return (o, d, v0, e1, e2), tuv, inside


def check_many(module) -> str:
    rays, tuv, inside = _random_cases()
    o, d, v0, e1, e2 = rays
    n = len(o)
    t, _, _ = _call(module, *rays)
    clear = np.min(np.abs([tuv[:, 1], tuv[:, 2], 1 - tuv[:, 1] - tuv[:, 2]]), axis=0) > 1e-6
    wrong = clear & (np.isfinite(t) != inside)
    if wrong.any():
        i = np.flatnonzero(wrong)[0]
        hint = ""
        if inside[i]:
            hint = _miss_hint((v0[i], v0[i] + e1[i], v0[i] + e2[i]), d[i], tuv[i, 0])
        wrongly = "ch02.random_miss" if inside[i] else "ch02.random_hit"
        raise CheckFailed(text(wrongly, wrong=wrong.sum(), n=n, ray=i, tuv=_fmt(tuv[i])) + hint)
    error = np.abs(t[inside] - tuv[inside, 0]) / np.maximum(1, np.abs(tuv[inside, 0]))
    if error.max() > 1e-6:
        raise CheckFailed(text("ch02.random_t", error=error.max()) + _error_hint("t", error.max()))
    return text("ch02.many_ok", n=n)


def check_barycentrics(module) -> str:
    n = sum(_expect_hits(module, *case, barycentrics=True) for case in FRONT_HITS + BEHIND_HITS + BACK_HITS)
    rays, tuv, inside = _random_cases()
    t, u, v = _call(module, *rays)
    hits = inside & np.isfinite(t)  # (a ray that should hit and misses is 'many rays'' to report)
    for name, got, want in (("u", u, tuv[:, 1]), ("v", v, tuv[:, 2])):
        error = np.abs(got[hits] - want[hits]).max(initial=0.0)
        if error > 1e-6:
            swapped = np.allclose(u[hits], tuv[hits, 2], atol=1e-6) and np.allclose(
                v[hits], tuv[hits, 1], atol=1e-6
            )
            hint = _error_hint(name, error, swapped)
            raise CheckFailed(text("ch02.random_uv", name=name, error=error) + hint)
    return text("ch02.barycentrics_ok", n=n, hits=hits.sum())


#: Errors up to this are small numerical slips (computing these rays in float32 is off by up
#: to 4e-7, an epsilon of 1e-6 added to det by 6e-6); larger ones come from a wrong formula.
SMALL_ERROR = 1e-4


def _error_hint(name: str, error: float, swapped: bool = False) -> str:
    """Why the student's ``name`` (t, u or v) of random hits is off by ``error``."""
    if error <= SMALL_ERROR:
        return aside(text("ch02.hint.small_error"))
    if swapped:
        return text("ch02.hint.swapped")
    if name == "t":
        return text("ch02.hint.t_formula")
    return text("ch02.hint.uv_formula")


def _student_ray_triangle(module) -> Pieces:
    """A render's pieces with the student's ``ray_triangle`` in the NumPy BVH, its results
    checked."""
    (ray_triangle,) = require(module, "ray_triangle")

    def student_ray_triangle(origins, dirs, v0, e1, e2):
        with np.errstate(all="ignore"):
            result = ray_triangle(origins, dirs, v0, e1, e2)
        if not (isinstance(result, tuple) and len(result) == 3):
            raise CheckFailed(text("ch02.three_arrays"))
        t, u, v = (np.array(a, dtype=np.float32) for a in result)
        if t.shape != (len(origins),) or u.shape != t.shape or v.shape != t.shape:
            raise CheckFailed(text("ch02.render_shapes", n=len(origins), t=t.shape, u=u.shape, v=v.shape))
        _require_finite_hits(t, u, v, bvh=True)
        return t, u, v

    return Pieces(bvh=BVHPieces(ray_triangle=student_ray_triangle))


def check_render(module) -> str:
    from ptlab.course.renders import check_render_through

    return check_render_through(
        text("ch02.yours"),
        _student_ray_triangle(module),
        passes=dict(RENDER, seed=grading_seed_for(RENDER_SEED)),
        hint=text("ch02.hint.render"),
    )


def render_yours(module, scene, options: dict) -> np.ndarray:
    """``scene`` rendered through the student's ray_triangle (``ptlab exercise render``), on the
    NumPy BVH, which walks its tree through it whatever the scene's size."""
    from ptlab.course.side_by_side import render_with_pieces

    return render_with_pieces(scene, options, _student_ray_triangle(module))


CHAPTER = Chapter(
    number=2,
    slug="ray_triangle",
    title="Ray-triangle intersection (Möller–Trumbore)",
    functions=("ray_triangle",),
    answers=("ptlab.accel.triangle.ray_triangle",),
    # Embree answers a ray-triangle query, and so does a BVH of one triangle.
    also_left_out=("ptlab.accel.embree", "ptlab.accel.numpy_bvh.NumpyBVH"),
    packages=("numpy", "scipy"),
    checks=(
        # Hits and distances first (t), the barycentrics (u, v) apart: an answer without
        # them still earns the hit checks. Every ray missing gets parallel rays right, and a
        # constant t = -1 the rays behind: those score only once known hits pass.
        ChapterCheck("known hits", 2, check_known_hits, timeout=30),
        ChapterCheck("outside each edge", 1, check_edges, timeout=30),
        ChapterCheck("parallel rays", 1, check_parallel, timeout=30, requires=("known hits",)),
        ChapterCheck("behind the origin", 1, check_behind, timeout=30, requires=("known hits",)),
        ChapterCheck("both faces", 1, check_both_faces, timeout=30, requires=("known hits",)),
        ChapterCheck("many rays", 1, check_many, timeout=30),
        ChapterCheck("barycentrics", 1, check_barycentrics, timeout=30, requires=("known hits",)),
        ChapterCheck("render", 2, check_render, timeout=60),
    ),
    render=ChapterRender(render_yours, options=dict(backend="numpy")),
)
