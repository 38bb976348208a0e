"""Chapter 3's checks: reflection, refraction and Fresnel (``reflect``, ``refract``, ``fresnel``).

Known answers come from the laws themselves: the mirror direction makes equal angles with
the normal, Snell's law eta_i sin(theta_i) = eta_t sin(theta_t) bends the refracted ray
(GAMES101 lecture 13; pbrt-v4 section 9.3), and the Fresnel reflectance of unpolarised light
is the mean of the squared amplitude ratios r_parallel and r_perpendicular (pbrt-v4 section
9.3.5; Hecht, Optics, section 4.6), which is ((eta - 1) / (eta + 1))^2 at normal incidence,
1 at grazing incidence and 1 beyond the critical angle (total internal reflection). They are
computed here from first principles, in float64, independently of the library.

Then the student's three functions are the Whitted ray tracer's pieces (``PathPieces``: it
reflects at mirrors and glass and refracts into glass with them), which renders the Cornell box's
walls with a mirror sphere, a glass sphere and a glass block (``check_scene``: in the block
total internal reflection shows, which a sphere never has). Whitted's tracer spends no
random numbers on mirrors and glass, so with the same seed the two images must agree pixel
for pixel, up to float rounding: a deterministic check.

The normals, angles, indices of refraction and the render's seed come from the grading seed
(``ptlab.course.chapter.grading_rng``), new for each grading: answers stored for known
inputs match none of them.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from typing import TYPE_CHECKING

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
from ptlab.course.finite import at_pixel, finite_array, require_finite
from ptlab.course.messages import aside, check_name, text
from ptlab.integrators.path import PathPieces
from ptlab.rendering.pieces import Pieces

if TYPE_CHECKING:
    from ptlab.scene import Scene

#: The glass of the checks (and of the render's sphere), and diamond.
GLASS, DIAMOND = 1.5, 2.4


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _directions(theta: np.ndarray, n=(0.0, 0.0, 1.0), phi: float = 0.3) -> np.ndarray:
    """(N, 3) unit vectors at angles ``theta`` from the unit normal ``n``, azimuth ``phi``."""
    from ptlab.sampling import to_world

    theta = np.asarray(theta, dtype=np.float64)
    local = np.stack([np.sin(theta) * math.cos(phi), np.sin(theta) * math.sin(phi), np.cos(theta)], axis=1)
    return np.asarray(to_world(local, np.broadcast_to(np.asarray(n, dtype=np.float64), local.shape)))


def _call(function, name: str, *args, shape) -> np.ndarray:
    """``function(*args)`` as float64, checked for its shape and for NaN (the row of the
    first is named). The function gets copies of the arguments: what the check computes
    from them is the grader's own."""
    return finite_array(
        function(*copy.deepcopy(args)),
        name,
        shape,
        nan_hint=text("ch03.hint.sqrt"),
    )


def _normal(stream: int) -> np.ndarray:
    """(1, 3): a random unit normal, stream ``stream`` of the grading seed."""
    return _unit(grading_rng(stream).normal(size=(1, 3)))


def _indices(stream: int) -> tuple[float, float]:
    """(glass, diamond): indices of refraction around GLASS and DIAMOND, from the grading seed."""
    rng = grading_rng(stream)
    return float(rng.uniform(1.3, 1.7)), float(rng.uniform(2.2, 2.6))


def _random_cases(stream: int, count: int = 500):
    """(wo, n): random unit normals, and wo above each at angles up to 89 degrees."""
    rng = grading_rng(stream)
    n = _unit(rng.normal(size=(count, 3)))
    from ptlab.sampling import to_world

    theta = np.radians(rng.uniform(0, 89, count))
    phi = rng.uniform(0, 2 * math.pi, count)
    local = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=1)
    return np.asarray(to_world(local, n)), n


# -- reflect ----------------------------------------------------------------------------------


def check_reflect(module) -> str:
    (reflect,) = require(module, "reflect")
    n = _normal(30)
    straight = _call(reflect, "reflect", n.copy(), n.copy(), shape=(1, 3))
    if np.allclose(straight, -n, atol=1e-6):
        raise CheckFailed(text("ch03.reflect_minus_n"))
    if not np.allclose(straight, n, atol=1e-6):
        raise CheckFailed(text("ch03.reflect_normal", n=np.round(n[0], 4), yours=np.round(straight[0], 4)))
    wo, n = _random_cases(31)
    expected = 2 * np.sum(wo * n, axis=1, keepdims=True) * n - wo
    wi = _call(reflect, "reflect", wo, n, shape=wo.shape)
    if np.allclose(wi, -expected, atol=1e-5):
        raise CheckFailed(text("ch03.reflect_into"))
    if not np.allclose(wi, expected, atol=1e-5):
        cos_in, cos_out = np.sum(wo * n, axis=1), np.sum(wi * n, axis=1)
        if not np.allclose(np.linalg.norm(wi, axis=1), 1, atol=1e-5):
            raise CheckFailed(text("ch03.reflect_unit"))
        if not np.allclose(cos_in, cos_out, atol=1e-5):
            raise CheckFailed(text("ch03.reflect_angle"))
        raise CheckFailed(text("ch03.reflect_plane"))
    return text("ch03.reflect_ok")


# -- refract ----------------------------------------------------------------------------------


def snell(wo: np.ndarray, n: np.ndarray, eta: float | np.ndarray) -> np.ndarray:
    """The refracted direction from Snell's law, built from its two components (float64);
    ``eta``: one ratio of indices, or an (N, 1) column of them, one per row.

    The tangential part of the transmitted direction is -(tangential part of wo) / eta, and
    its normal part is -cos(theta_t) n with cos(theta_t) = sqrt(1 - sin^2(theta_t)).
    """
    cos_theta_i = np.sum(wo * n, axis=1, keepdims=True)
    tangent = wo - cos_theta_i * n
    sin2_theta_t = np.sum(tangent * tangent, axis=1, keepdims=True) / eta**2
    return -tangent / eta - np.sqrt(np.maximum(0, 1 - sin2_theta_t)) * n


def check_refract(module) -> str:
    (refract,) = require(module, "refract")
    n = _normal(35)
    glass, diamond = _indices(36)
    jitter = grading_rng(37).uniform(-3, 3, 3)
    for eta in (glass, 1 / glass):
        straight = _call(refract, "refract", n.copy(), n.copy(), eta, shape=(1, 3))
        if not np.allclose(straight, -n, atol=1e-6):
            raise CheckFailed(
                text("ch03.refract_normal", eta=eta, n=np.round(-n[0], 4), yours=np.round(straight[0], 4))
            )
    # Leaving glass first: with eta taken the wrong way up, it bends the wrong way there
    # (entering, it would be totally reflected, which says less).
    for eta, degrees in zip((1 / glass, glass, diamond), jitter + np.array([30.0, 45.0, 70.0]), strict=True):
        wo = _directions(np.radians([degrees]), n[0])
        wt = _call(refract, "refract", wo, n.copy(), eta, shape=(1, 3))
        if not np.isclose(np.linalg.norm(wt), 1, atol=1e-5):
            raise CheckFailed(text("ch03.refract_unit", degrees=degrees, eta=eta, length=np.linalg.norm(wt)))
        sin_i = math.sin(math.radians(degrees))
        sin_t = math.sqrt(max(0.0, 1 - (wt[0] @ n[0]) ** 2))
        if not math.isclose(sin_t, sin_i / eta, abs_tol=1e-5):
            inverted = math.isclose(sin_t, min(1.0, sin_i * eta), abs_tol=1e-4)
            hint = aside(text("ch03.hint.eta_inverted")) if inverted else ""
            raise CheckFailed(
                text("ch03.snell", degrees=degrees, eta=eta, expected=sin_i / eta, yours=sin_t) + hint
            )
        if not wt[0] @ n[0] < 0:
            raise CheckFailed(text("ch03.refract_through"))
    _check_refract_random(refract, glass)
    return text("ch03.refract_ok")


def _check_refract_random(refract: Callable, glass: float) -> None:
    """``refract`` of random directions about random normals, with one ``eta`` for all rows
    (into glass, out of it) and with one per row (in and out by turns)."""
    wo, n = _random_cases(32)
    in_and_out = np.where(np.arange(len(wo)) % 2, glass, 1 / glass)
    etas: tuple[float | np.ndarray, ...] = (glass, 1 / glass, in_and_out)
    for eta in etas:
        column = eta[:, None] if isinstance(eta, np.ndarray) else eta
        refracts = np.sum(wo * n, axis=1) ** 2 > 1 - np.ravel(column**2)  # not totally reflected
        expected = snell(wo, n, column)
        wt = _call(refract, "refract", wo, n, eta, shape=wo.shape)
        ok = np.all(np.abs(wt - expected) < 1e-5, axis=1) | ~refracts
        if not ok.all():
            per_row = aside(text("ch03.hint.per_row_column")) if np.ndim(eta) else ""
            raise CheckFailed(text("ch03.refract_random", wrong=(~ok).sum(), n=ok.size, per_row=per_row))


# -- Fresnel ---------------------------------------------------------------------------------


def fresnel_reference(cos_theta_i: np.ndarray, eta) -> np.ndarray:
    """The Fresnel reflectance of unpolarised light from the Fresnel equations (float64).

    r_perpendicular = (cos_i - eta cos_t) / (cos_i + eta cos_t), r_parallel = (eta cos_i -
    cos_t) / (eta cos_i + cos_t), F = (r_perpendicular^2 + r_parallel^2) / 2, and F = 1 when
    sin(theta_t) = sin(theta_i) / eta exceeds 1 (Hecht, Optics, 4.6; pbrt-v4 eq. 9.7).
    """
    cos_i = np.asarray(cos_theta_i, dtype=np.float64)
    sin2_t = (1 - cos_i**2) / np.asarray(eta, dtype=np.float64) ** 2
    cos_t = np.sqrt(np.maximum(0, 1 - sin2_t))
    with np.errstate(invalid="ignore", divide="ignore"):
        r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
        r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return np.where(sin2_t >= 1, 1.0, (r_perpendicular**2 + r_parallel**2) / 2)


def check_fresnel(module) -> str:
    (fresnel,) = require(module, "fresnel")
    glass, diamond = _indices(38)
    rng = grading_rng(39)
    for eta in (glass, 1 / glass, diamond):
        normal = _call(fresnel, "fresnel", np.array([1.0]), eta, shape=(1,))[0]
        expected = ((eta - 1) / (eta + 1)) ** 2
        if not math.isclose(normal, expected, abs_tol=1e-6):
            raise CheckFailed(text("ch03.fresnel_normal", expected=expected, eta=eta, yours=normal))
    grazing = _call(fresnel, "fresnel", np.array([1e-4]), glass, shape=(1,))[0]
    if not grazing >= 0.99:
        raise CheckFailed(text("ch03.fresnel_grazing", yours=grazing))
    _check_fresnel_random(fresnel, glass, diamond, rng)
    return text("ch03.fresnel_ok")


def _check_fresnel_random(fresnel: Callable, glass: float, diamond: float, rng: np.random.Generator) -> None:
    """``fresnel`` at 200 random angles (from ``rng``), with one ``eta`` for all (glass from
    either side, diamond) and with a random one per angle."""
    cos_i = np.sort(rng.uniform(0.02, 1, 200))
    etas: tuple[float | np.ndarray, ...] = (glass, 1 / glass, diamond, rng.uniform(1.1, 2.0, 200))
    for eta in etas:
        expected = fresnel_reference(cos_i, eta)
        F = _call(fresnel, "fresnel", cos_i, eta, shape=cos_i.shape)  # noqa: N806 (the usual name)
        if not np.abs(F - expected).max() <= 1e-5:
            worst = int(np.argmax(np.abs(F - expected)))
            schlick_r0 = ((eta - 1) / (eta + 1)) ** 2
            schlick = schlick_r0 + (1 - schlick_r0) * (1 - cos_i) ** 5
            eta_here = eta[worst] if isinstance(eta, np.ndarray) else eta
            hint = ""
            if eta_here < 1 and 1 - cos_i[worst] ** 2 >= eta_here**2:  # sin(theta_t) >= 1 there
                critical = math.degrees(math.asin(eta_here))
                hint = aside(text("ch03.hint.fresnel_tir", critical=critical))
            elif np.abs(F - schlick).max() < 1e-4:
                hint = aside(text("ch03.hint.schlick"))
            elif np.abs(F - fresnel_reference(cos_i, 1 / np.asarray(eta))).max() < 1e-5:
                hint = aside(text("ch03.hint.fresnel_eta_inverted"))
            elif np.ndim(eta):
                hint = aside(text("ch03.hint.per_row"))
            angle = math.degrees(math.acos(cos_i[worst]))
            raise CheckFailed(
                text("ch03.fresnel", angle=angle, eta=eta_here, expected=expected[worst], yours=F[worst])
                + hint
            )


def check_total_internal_reflection(module) -> str:
    fresnel, refract = require(module, "fresnel", "refract")
    glass, _ = _indices(40)
    rng = grading_rng(34)
    eta = 1 / glass
    critical = math.degrees(math.asin(eta))
    degrees = np.concatenate([[critical + 0.5], np.sort(rng.uniform(critical + 1, 89, 4))])
    F = _call(fresnel, "fresnel", np.cos(np.radians(degrees)), eta, shape=degrees.shape)  # noqa: N806
    if not np.abs(F - 1).max() <= 1e-6:
        bad = int(np.argmax(np.abs(F - 1)))
        raise CheckFailed(
            text("ch03.tir", glass=glass, critical=critical, yours=F[bad], degrees=degrees[bad])
        )
    n = _unit(rng.normal(size=(len(degrees), 3)))  # (no row repeats n)
    wo = np.concatenate(
        [_directions(np.radians(d)[None], normal) for d, normal in zip(degrees, n, strict=True)]
    )
    _call(refract, "refract", wo, n, eta, shape=wo.shape)
    return text("ch03.tir_ok", critical=critical)


# -- the render ------------------------------------------------------------------------------


def icosphere(subdivisions: int = 2) -> np.ndarray:
    """(20 * 4^subdivisions, 3, 3) triangles of a unit sphere, wound to face outward.

    An icosahedron whose triangles are each split into 4, the new corners pushed out onto
    the sphere, ``subdivisions`` times (NumPy only: no trimesh needed).
    """
    g = (1 + math.sqrt(5)) / 2
    vertices = np.array(
        [
            [-1, g, 0],
            [1, g, 0],
            [-1, -g, 0],
            [1, -g, 0],
            [0, -1, g],
            [0, 1, g],
            [0, -1, -g],
            [0, 1, -g],
            [g, 0, -1],
            [g, 0, 1],
            [-g, 0, -1],
            [-g, 0, 1],
        ]
    )
    faces = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ]
    triangles = vertices[np.array(faces)] / np.linalg.norm(vertices[0])
    for _ in range(subdivisions):
        a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
        ab, bc, ca = (
            (p + q) / np.linalg.norm(p + q, axis=1, keepdims=True) for p, q in ((a, b), (b, c), (c, a))
        )
        triangles = np.concatenate(
            [np.stack(t, axis=1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))]
        )
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    inward = np.sum(normals * triangles.mean(axis=1), axis=1) < 0
    triangles[inward] = triangles[inward][:, ::-1]
    return triangles


def spheres_scene(glass_block: bool = False) -> Scene:
    """The Cornell box's walls and light (its two boxes left out) with a mirror sphere at the
    back on the left and a glass sphere (eta 1.5) at the front on the right; with
    ``glass_block``, the tall box in glass at the back on the left, and the mirror sphere,
    smaller, in front of it."""
    import ptlab
    from ptlab.materials import Dielectric, Mirror
    from ptlab.meshes import read_mesh_triangles
    from ptlab.scene import Scene
    from ptlab.scene_file import builtin_scenes_dir

    cornell = ptlab.load_scene("cornell-box")
    meshes = builtin_scenes_dir() / "cornell-box" / "meshes"
    parts = [
        (read_mesh_triangles(meshes / f"{name}.obj"), cornell.material_names.index(material))
        for name, material in (("floor", "white"), ("left", "red"), ("right", "green"), ("light", "light"))
    ]
    materials = [*list(cornell.materials), Mirror(), Dielectric(eta=GLASS)]
    mirror, glass = len(materials) - 2, len(materials) - 1
    sphere = icosphere(3)
    parts.append((sphere * 90 + [180, 90, 170], glass))
    if glass_block:
        block = read_mesh_triangles(meshes / "tallbox.obj")
        parts += [(sphere * 70 + [420, 70, 150], mirror), (block, glass)]
    else:
        parts.append((sphere * 100 + [380, 100, 370], mirror))
    triangles = np.concatenate([t for t, _ in parts])
    ids = np.concatenate([np.full(len(t), k) for t, k in parts])
    names = [*list(cornell.material_names), "mirror", "glass"]
    name = "cornell-glass-block" if glass_block else "cornell-spheres"
    return Scene(triangles, ids, materials, cornell.camera, name, names)


def check_scene() -> Scene:
    """The render check's scene: ``spheres_scene`` with the glass block, seen from closer.

    A ray leaves a sphere at the angle it entered at, below the critical angle, so a sphere
    shows no total internal reflection (an answer without it changed 0.1% of the pixels);
    inside a block, rays meet the sides far beyond the critical angle. From this camera an
    answer whose fresnel gives 0 or less than 1 there differs from the library's in about
    10% of the 48 x 48 pixels (measured for three seeds), five times the check's allowance.
    """
    from ptlab.camera import Camera

    scene = spheres_scene(glass_block=True)
    scene.camera = Camera.look_at((278, 273, -300), (340, 165, 380), fov_y=40)
    return scene


def surface_pieces(reflect=None, refract=None, fresnel=None) -> Pieces:
    """A render's pieces with the given laws of the smooth surface (those not None) in the
    library's place: the Whitted tracer reflects at mirrors and glass, and refracts into
    glass with them."""
    given = {
        name: f
        for name, f in (("reflect", reflect), ("refract", refract), ("fresnel_dielectric", fresnel))
        if f is not None
    }
    return Pieces(path=PathPieces(**given))


def whitted_image(scene: Scene, reflect=None, refract=None, fresnel=None, **options) -> np.ndarray:
    """The Whitted render of ``scene`` in this process, with the given functions (those not
    None) as its pieces."""
    import ptlab

    options = dict(dict(spp=2, res=48, workers=1), **options)
    return ptlab.render(
        scene, integrator="whitted", **options, pieces=surface_pieces(reflect, refract, fresnel)
    )


def check_render(module) -> str:
    reflect, refract, fresnel = require(module, "reflect", "refract", "fresnel")
    scene = check_scene()
    seed = grading_seed_for(3)
    expected = whitted_image(scene, seed=seed)
    image = whitted_image(scene, reflect, refract, fresnel, seed=seed)
    require_finite(image, text("ch03.the_render"), at_pixel)
    # Float rounding may send a ray that grazes an edge to the other side of it: allow a few
    # pixels to differ, none of the others by more than 0.1%.
    close = np.isclose(image, expected, rtol=1e-3, atol=1e-4).all(axis=2)
    if close.mean() < 0.98:
        from ptlab.course.inspect_command import suggestion

        ratio = image.mean() / expected.mean()
        raise CheckFailed(
            text("ch03.render", wrong=(~close).sum(), n=close.size, ratio=ratio)
            + _render_hint(fresnel)
            + suggestion(3, image, expected, seed)
        )
    return text("ch03.render_ok", share=close.mean())


def _render_hint(fresnel) -> str:
    """What may make the render differ: light let out of the glass block beyond the critical
    angle, if ``fresnel`` is not 1 there (leaving glass at 50 to 85 degrees); else nothing."""
    degrees = np.array([50.0, 65.0, 85.0])
    with np.errstate(all="ignore"):
        F = np.asarray(fresnel(np.cos(np.radians(degrees)), 1 / GLASS), dtype=np.float64)  # noqa: N806
    if F.shape == degrees.shape and np.all(np.abs(F - 1) <= 1e-6):
        return ""
    return aside(text("ch03.hint.render_tir", check=check_name(3, "total internal reflection")))


def render_yours(module, scene: Scene, options: dict) -> np.ndarray:
    """``scene`` rendered by the Whitted tracer with the student's ``reflect``, ``refract``
    and ``fresnel`` (``ptlab exercise render``); a scene without a mirror or glass, which
    would never call them, is refused."""
    from ptlab.course.side_by_side import render_with_pieces
    from ptlab.materials import Dielectric, Mirror

    if not any(isinstance(m, Mirror | Dielectric) for m in scene.materials):
        raise CheckFailed(text("ch03.no_mirror_or_glass", scene=scene.name))
    pieces = surface_pieces(*require(module, "reflect", "refract", "fresnel"))
    return render_with_pieces(scene, options, pieces)


CHAPTER = Chapter(
    number=3,
    slug="whitted",
    title="Whitted ray tracing: reflection, refraction, Fresnel",
    functions=("reflect", "refract", "fresnel"),
    answers=("ptlab.scattering.reflect", "ptlab.scattering.refract", "ptlab.scattering.fresnel_dielectric"),
    # The mirror and the glass reflect and refract; Whitted's tracer splits by Fresnel.
    also_left_out=(
        "ptlab.scattering",
        "ptlab.materials.mirror",
        "ptlab.materials.dielectric",
        "ptlab.integrators.whitted",
        "ptlab.inspector",
    ),
    checks=(
        ChapterCheck("reflect", 2, check_reflect, timeout=20),
        ChapterCheck("refract", 2, check_refract, timeout=20),
        ChapterCheck("fresnel", 2, check_fresnel, timeout=20),
        # F = 1 for every angle is right beyond the critical angle, and a constant refract
        # never NaN: this scores only once the Fresnel equations themselves are right.
        ChapterCheck(
            "total internal reflection", 1, check_total_internal_reflection, timeout=20, requires=("fresnel",)
        ),
        ChapterCheck("render", 3, check_render, timeout=60),
    ),
    render=ChapterRender(render_yours, scene="games101-hw5", options=dict(integrator="whitted")),
)
