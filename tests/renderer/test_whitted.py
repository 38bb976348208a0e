"""The Whitted integrator (``ptlab.integrators.whitted``): exact mirrors and glass, direct light only.

Most scenes here are a closed room whose six walls each glow with their own colour and
reflect nothing (albedo 0), so what a ray sees is exactly the emission of the wall it ends
on: a pixel's value is a sum of weights x wall colours, with no noise but the pixel jitter.
A scalar recursive tracer (``cast_ray``, Homework 5's ``castRay`` in plain Python with the
homework's own ``fresnel`` and ``refract``) gives the expected value of chosen pixels.

Statistical tests use fixed seeds and say their false-alarm rate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
import trimesh
from helpers import furnace_with

import ptlab
from ptlab.accel import make_accelerator
from ptlab.camera import Camera, generate_rays
from ptlab.integrators import whitted
from ptlab.integrators.whitted import fresnel_split
from ptlab.materials import Dielectric, Diffuse, Mirror

# -- the room -------------------------------------------------------------------------------

#: Wall name -> (inward normal, emitted radiance). The camera looks along +z, so +x is on
#: the image's left.
WALLS = {
    "left": ((-1, 0, 0), (0.9, 0.2, 0.1)),
    "right": ((1, 0, 0), (0.1, 0.7, 0.2)),
    "ceiling": ((0, -1, 0), (0.3, 0.4, 1.0)),
    "floor": ((0, 1, 0), (0.8, 0.8, 0.3)),
    "far": ((0, 0, -1), (0.6, 0.1, 0.7)),
    "near": ((0, 0, 1), (0.2, 0.5, 0.5)),
}
WALL_NAMES = list(WALLS)
MIRROR_REFLECTANCE = (0.9, 0.6, 0.3)
SLAB_ETA, SLAB_TRANSMITTANCE = 1.7, (1.0, 0.8, 0.6)
PRISM_ETA = 1.5


def room() -> tuple[np.ndarray, np.ndarray, list]:
    """The walls of the box [-4, 4]^3, facing in: triangles, material ids, materials."""
    box = trimesh.creation.box(extents=(8, 8, 8))
    box.invert()  # outward normals -> inward
    triangles = box.vertices[box.faces]
    # (Not box.face_normals: after invert() trimesh still reports the outward ones.)
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    ids = [next(k for k, name in enumerate(WALL_NAMES) if np.allclose(n, WALLS[name][0])) for n in normals]
    materials = [Diffuse([0, 0, 0], emission=WALLS[name][1]) for name in WALL_NAMES]
    return triangles, np.array(ids), materials


def outward(triangles: np.ndarray) -> np.ndarray:
    """A convex solid's triangles wound so that their normals point out of it."""
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    inward = ((triangles.mean(axis=1) - triangles.mean(axis=(0, 1))) * normals).sum(axis=1) < 0
    triangles = triangles.copy()
    triangles[inward] = triangles[inward][:, ::-1]
    return triangles


def right_prism(x0: float, x1: float, y0: float, z0: float, h: float) -> np.ndarray:
    """A glass prism along x whose cross-section is the right isosceles triangle with legs
    z = z0 (facing the camera) and y = y0 + h (facing up), and the hypotenuse between."""
    corners = [(y0, z0), (y0 + h, z0), (y0 + h, z0 + h)]
    ends = [[np.array([x, y, z]) for y, z in corners] for x in (x0, x1)]
    sides = [[ends[0][i], ends[0][j], ends[1][j]] for i, j in ((0, 1), (1, 2), (2, 0))]
    sides += [[ends[0][i], ends[1][j], ends[1][i]] for i, j in ((0, 1), (1, 2), (2, 0))]
    return outward(np.array(ends + sides, dtype=float))


def room_scene(objects: list[tuple[np.ndarray, object]], fov_y: float = 70.0) -> ptlab.Scene:
    """The room with ``objects`` [(triangles, material)] in it, seen from near its front wall."""
    triangles, ids, materials = room()
    for tris, material in objects:
        triangles = np.concatenate([triangles, tris])
        ids = np.concatenate([ids, np.full(len(tris), len(materials))])
        materials = [*materials, material]
    camera = Camera.look_at((0, 0, -3.5), (0, 0, 0), fov_y=fov_y)
    return ptlab.Scene(triangles, ids, materials, camera, name="whitted-room")


def quad(centre: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The parallelogram centre +- a +- b as two triangles, facing a x b."""
    centre, a, b = (np.asarray(v, dtype=float) for v in (centre, a, b))
    return np.array(
        [[centre - a - b, centre + a - b, centre + a + b], [centre - a - b, centre + a + b, centre - a + b]]
    )


def mirror_glass_room(more: tuple = ()) -> ptlab.Scene:
    """A mirror (upper left), a tilted glass slab (lower right), a glass prism (middle),
    and ``more`` objects [(triangles, material)]."""
    # The mirror leans back at 45 degrees: it sends the camera's rays up to the ceiling.
    mirror = quad([2.0, 1.3, 1.5], [0.8, 0, 0], [0, 0.8, 0.8])
    slab = trimesh.creation.box(
        extents=(2.4, 2.0, 0.3),
        transform=(
            trimesh.transformations.translation_matrix([-1.6, -1.4, 1.2])
            @ trimesh.transformations.rotation_matrix(math.radians(50), [0, 1, 0])
        ),
    )
    prism = right_prism(-1.0, 1.0, y0=0.0, z0=0.5, h=1.8)
    return room_scene(
        [
            (mirror, Mirror(MIRROR_REFLECTANCE)),
            (slab.vertices[slab.faces], Dielectric(SLAB_ETA, SLAB_TRANSMITTANCE)),
            (prism, Dielectric(PRISM_ETA)),
            *more,
        ]
    )


# -- Homework 5's castRay, one ray at a time, for the expected values ------------------------


@dataclass
class Leaf:
    """One branch of a ray's Whitted tree: the wall it ends on and the weight it arrives with."""

    wall: str
    weight: np.ndarray  # (3,)
    events: str  # what happened at each glass or mirror: "R"eflect, "T"ransmit


def closest_hit(triangles: np.ndarray, o: np.ndarray, d: np.ndarray) -> tuple[int, float]:
    """Moller-Trumbore against every triangle (float64): (index, t), or (-1, inf) on a miss."""
    v0, e1, e2 = triangles[:, 0], triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]
    p = np.cross(d, e2)
    det = (e1 * p).sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = o - v0
        u = (s * p).sum(axis=1) / det
        q = np.cross(s, e1)
        v = (q @ d) / det
        t = (e2 * q).sum(axis=1) / det
        t = np.where((u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-7), t, np.inf)
    k = int(np.argmin(t))
    return (k, float(t[k])) if np.isfinite(t[k]) else (-1, math.inf)


def homework_fresnel(d: np.ndarray, n: np.ndarray, ior: float) -> float:
    """Homework 5's ``fresnel(I, N, ior)``: d the ray's direction, n the outward normal."""
    cosi = float(np.clip(d @ n, -1, 1))
    etai, etat = (ior, 1.0) if cosi > 0 else (1.0, ior)
    sint = etai / etat * math.sqrt(max(0.0, 1 - cosi * cosi))
    if sint >= 1:
        return 1.0  # total internal reflection
    cost = math.sqrt(max(0.0, 1 - sint * sint))
    cosi = abs(cosi)
    rs = (etat * cosi - etai * cost) / (etat * cosi + etai * cost)
    rp = (etai * cosi - etat * cost) / (etai * cosi + etat * cost)
    return (rs * rs + rp * rp) / 2


def homework_refract(d: np.ndarray, n: np.ndarray, ior: float) -> tuple[np.ndarray, float]:
    """Homework 5's ``refract(I, N, ior)`` (Snell's law), and eta_t / eta_i (for 1 / eta_rel^2)."""
    cosi = float(np.clip(d @ n, -1, 1))
    etai, etat = 1.0, ior
    if cosi < 0:
        cosi = -cosi
    else:
        etai, etat, n = ior, 1.0, -n
    eta = etai / etat
    k = 1 - eta * eta * (1 - cosi * cosi)
    return eta * d + (eta * cosi - math.sqrt(k)) * n, etat / etai


def cast_ray(
    scene: ptlab.Scene,
    o: np.ndarray,
    d: np.ndarray,
    max_depth: int,
    depth: int = 0,
    weight: np.ndarray | None = None,
    events: str = "",
) -> list[Leaf]:
    """The leaves of a ray's Whitted tree in the room (walls emit and reflect nothing)."""
    weight = np.ones(3) if weight is None else weight
    k, t = closest_hit(scene.triangles, o, d)
    if k < 0:
        return []
    v0, v1, v2 = scene.triangles[k]
    n = np.cross(v1 - v0, v2 - v0)
    n /= np.linalg.norm(n)
    material = scene.materials[scene.material_ids[k]]
    if material.emission is not None:
        front = d @ n < 0
        return [Leaf(WALL_NAMES[scene.material_ids[k]], weight, events)] if front else []
    if depth == max_depth:
        return []
    p = o + t * d
    reflected = d - 2 * (d @ n) * n
    if isinstance(material, Mirror):
        return cast_ray(
            scene, p, reflected, max_depth, depth + 1, weight * material.reflectance, events + "R"
        )
    kr = homework_fresnel(d, n, material.eta)
    leaves = cast_ray(scene, p, reflected, max_depth, depth + 1, weight * kr, events + "R")
    if kr < 1:
        refracted, eta_rel = homework_refract(d, n, material.eta)
        leaves += cast_ray(
            scene,
            p,
            refracted,
            max_depth,
            depth + 1,
            weight * (1 - kr) * material.transmittance / eta_rel**2,
            events + "T",
        )
    return leaves


def radiance(leaves: list[Leaf]) -> np.ndarray:
    return sum((leaf.weight * np.array(WALLS[leaf.wall][1]) for leaf in leaves), np.zeros(3))


def pixel_rays(scene: ptlab.Scene, res: int, y: int, x: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """The camera rays through the centre and the four corners of pixel (y, x), in float64."""
    rays = []
    for u in [(0.5, 0.5), (0, 0), (0.999, 0), (0, 0.999), (0.999, 0.999)]:
        o, d = generate_rays(
            scene.camera, res, res, np.array([x]), np.array([y]), np.array([u], dtype=np.float32)
        )
        rays.append((o[0].astype(float), d[0].astype(float)))
    return rays


# -- 1. mirrors and glass, exactly ---------------------------------------------------------

RES = 32


@pytest.fixture(scope="module")
def room_images() -> dict:
    scene = mirror_glass_room()
    return {
        backend: ptlab.render(scene, integrator="whitted", spp=8, res=RES, workers=1, backend=backend)
        for backend in ("embree", "numpy")
    }


def check_pixel(image: np.ndarray, y: int, x: int) -> list[Leaf]:
    """Assert pixel (y, x) shows what Homework 5's castRay sees; return the centre ray's leaves.

    The pixel's value is the mean over rays jittered inside it. The pixel is chosen away from
    edges: the rays through its centre and its corners end on the same walls by the same
    events (asserted), so the value is a smooth function over the pixel (only the Fresnel
    weights change with the angle) and its mean lies within the spread of the centre and
    corner values; 1e-5 more covers float32 rays.
    """
    scene = mirror_glass_room()
    trees = [cast_ray(scene, o, d, max_depth=5) for o, d in pixel_rays(scene, RES, y, x)]
    events = [[(leaf.wall, leaf.events) for leaf in tree] for tree in trees]
    assert all(e == events[0] for e in events), f"pixel {(y, x)} straddles an edge"
    expected = radiance(trees[0])
    spread = max(np.abs(radiance(tree) - expected).max() for tree in trees)
    np.testing.assert_allclose(image[y, x], expected, rtol=0, atol=spread + 1e-5)
    return trees[0]


@pytest.mark.parametrize("backend", ["embree", "numpy"])
def test_mirror_shows_the_wall_its_reflection_reaches(room_images, backend):
    leaves = check_pixel(room_images[backend], 10, 7)
    # The mirror leans back at 45 degrees: r = d - 2 (d . n) n sends the ray up, to the
    # ceiling, with the mirror's reflectance as its weight.
    assert [(leaf.wall, leaf.events) for leaf in leaves] == [("ceiling", "R")]
    np.testing.assert_allclose(leaves[0].weight, MIRROR_REFLECTANCE)


@pytest.mark.parametrize("backend", ["embree", "numpy"])
def test_glass_slab_reflects_kr_and_transmits_the_rest_through_both_faces(room_images, backend):
    leaves = check_pixel(room_images[backend], 22, 23)
    branches = {leaf.events: leaf for leaf in leaves}
    # The slab faces the camera at about 70 degrees (eta 1.7): the reflected ray (weight kr)
    # goes to the right wall; the transmitted one leaves the parallel slab along the camera
    # ray's own direction, to the far wall, weighted (1 - kr)^2 T^2 (the same kr on both
    # faces; the 1 / eta_rel^2 factors of entering and leaving cancel). The rest is light
    # reflected back and forth inside the slab.
    scene = mirror_glass_room()
    o, d = pixel_rays(scene, RES, 22, 23)[0]
    k, _ = closest_hit(scene.triangles, o, d)
    v0, v1, v2 = scene.triangles[k]
    kr = homework_fresnel(
        d, np.cross(v1 - v0, v2 - v0) / np.linalg.norm(np.cross(v1 - v0, v2 - v0)), SLAB_ETA
    )
    assert 0.1 < kr < 0.3
    assert branches["R"].wall == "right"
    assert np.allclose(branches["R"].weight, kr)
    assert branches["TT"].wall == "far"
    np.testing.assert_allclose(branches["TT"].weight, (1 - kr) ** 2 * np.square(SLAB_TRANSMITTANCE))
    assert {leaf.wall for leaf in leaves} == {"right", "far"}


@pytest.mark.parametrize("backend", ["embree", "numpy"])
def test_glass_prism_reflects_totally_inside(room_images, backend):
    leaves = check_pixel(room_images[backend], 12, 15)
    # The ray enters the prism's front face almost head-on and meets the hypotenuse at
    # about 45 degrees, beyond the critical angle asin(1 / 1.5) = 41.8 degrees: it is
    # reflected whole (kr = 1, no refracted ray) up through the top face to the ceiling,
    # the classic porro-prism turn.
    scene = mirror_glass_room()
    _o, d = pixel_rays(scene, RES, 12, 15)[0]
    inside, _ = homework_refract(d, np.array([0.0, 0.0, -1.0]), PRISM_ETA)
    cos_hypotenuse = inside @ np.array([0.0, -1.0, 1.0]) / math.sqrt(2)
    assert cos_hypotenuse < math.cos(math.asin(1 / PRISM_ETA))
    branches = {leaf.events: leaf for leaf in leaves}
    assert not any(leaf.events.startswith("TT") for leaf in leaves)
    assert branches["TRT"].wall == "ceiling"
    r0 = ((PRISM_ETA - 1) / (PRISM_ETA + 1)) ** 2  # 0.04 head-on
    np.testing.assert_allclose(branches["TRT"].weight, (1 - r0) ** 2, rtol=0.01)
    assert branches["R"].wall == "near"


def test_a_batch_grown_by_glass_is_traced_in_parts_to_the_same_image(room_images, monkeypatch):
    # Parts of 1000 rays instead of 2^18: the camera rays (8192) are split at once and again
    # as glass doubles them. In the room nothing is random but the pixel jitter (the walls
    # reflect no light), so only the order of additions may differ.
    monkeypatch.setattr(whitted, "MAX_BATCH", 1000)
    image = ptlab.render(mirror_glass_room(), integrator="whitted", spp=8, res=RES, workers=1)
    np.testing.assert_allclose(image, room_images["embree"], rtol=1e-6, atol=1e-7)


def test_the_glass_split_is_the_dielectrics_own_choice_averaged():
    # fresnel_split gives both branches where Dielectric.sample_weight picks one at random
    # (reflection when u < kr, weight 1; else refraction, weight T / eta_rel^2): the same
    # directions, and weights kr x 1 and (1 - kr) x its refraction weight, for rays from
    # outside and inside, below and beyond the critical angle, per-row eta and T.
    rng = np.random.default_rng(5)
    rows = 400
    glass = Dielectric.stack([Dielectric(1.5, (1.0, 0.8, 0.6)), Dielectric(2.4, (0.5, 1.0, 0.9))])
    glass = glass.take(rng.integers(0, 2, rows))
    n = np.asfortranarray(np.tile(np.array([[0.0, 0.0, 1.0]], dtype=np.float32), (rows, 1)))
    cos_theta = rng.uniform(0.01, 1, rows)
    phi = rng.uniform(0, 2 * math.pi, rows)
    sin_theta = np.sqrt(1 - cos_theta**2)
    wo = np.asfortranarray(
        np.stack([sin_theta * np.cos(phi), sin_theta * np.sin(phi), cos_theta], axis=1).astype(np.float32)
    )
    front = rng.random(rows) < 0.5
    (wi_r, weight_r), (wi_t, weight_t) = fresnel_split(glass, wo, n, front)
    always = np.zeros((rows, 2), dtype=np.float32)
    wi_reflect, one = glass.sample_weight(wo, n, always, front)
    wi_refract, weight_refract = glass.sample_weight(wo, n, always + np.float32(0.9999999), front)
    kr = weight_r[:, 0]
    assert (kr == 1).sum() > 20
    assert ((kr > 0) & (kr < 1)).sum() > 200
    np.testing.assert_allclose(one, 1)
    np.testing.assert_allclose(wi_r, wi_reflect, atol=1e-6)
    refracts = kr < 1
    np.testing.assert_allclose(wi_t[refracts], wi_refract[refracts], atol=1e-5)
    np.testing.assert_allclose(weight_t[refracts], ((1 - kr)[:, None] * weight_refract)[refracts], rtol=1e-5)
    assert (weight_t[~refracts] == 0).all()


# -- 2.-4. diffuse surfaces: direct light only ---------------------------------------------


def footprint_on(scene: ptlab.Scene, res: int, wanted: np.ndarray) -> np.ndarray:
    """(res, res) float: the fraction of the rays through each pixel's centre and corners
    that hit a triangle where ``wanted`` (T,) bool is True."""
    accel = make_accelerator(scene.triangles, "embree")
    ys, xs = np.mgrid[0:res, 0:res]
    hits = []
    for u in [(0.5, 0.5), (0, 0), (0.999, 0), (0, 0.999), (0.999, 0.999)]:
        origins, dirs = generate_rays(
            scene.camera,
            res,
            res,
            xs.ravel(),
            ys.ravel(),
            np.tile(np.array([u], dtype=np.float32), (res * res, 1)),
        )
        prim = accel.intersect(origins, dirs).prim
        hits.append((prim >= 0) & wanted[np.maximum(prim, 0)])
    return np.mean(hits, axis=0).reshape(res, res)


def emitters(scene: ptlab.Scene) -> np.ndarray:
    return scene.emission.max(axis=1) > 0


def test_diffuse_surfaces_get_no_indirect_light(cornell):
    # The Cornell box's ceiling is lit only by light that has bounced off the walls: the
    # light hangs under it and emits downward. Whitted shows it black (it would take a
    # diffuse bounce), the path tracer does not.
    ceiling = (cornell.face_normals[:, 1] < -0.99) & ~emitters(cornell)
    on_ceiling = footprint_on(cornell, 32, ceiling) == 1
    assert on_ceiling.sum() >= 20
    whitted = ptlab.render(cornell, integrator="whitted", spp=4, res=32, workers=1)
    path = ptlab.render(cornell, integrator="path", spp=4, res=32, workers=1)
    assert (whitted[on_ceiling] == 0).all()
    assert path[on_ceiling].mean() > 0.05
    assert (path[on_ceiling].max(axis=1) > 0).mean() > 0.9


def renders(scene, seeds, **kwargs) -> np.ndarray:
    """(len(seeds), H, W, 3) independent renders, one per seed."""
    return np.array([ptlab.render(scene, seed=s, workers=1, **kwargs) for s in seeds])


def assert_same_block_means(a: np.ndarray, b: np.ndarray, regions: int, sigmas: float) -> None:
    """Two sets of independent renders (``renders``) have the same mean colour in each of
    ``regions`` x ``regions`` blocks, to within ``sigmas`` standard errors of the difference.

    A block's standard error comes from the spread of each of its pixels over the renders
    (different pixels use different random numbers, so they are independent), pooled over
    the block: hundreds of degrees of freedom, so normal quantiles apply. Blocks that no
    noise reaches must agree to float32 rounding.
    """

    def block_mean_and_variance(images):
        h, w = images.shape[1:3]

        def blocks(x):
            return x.reshape(regions, h // regions, regions, w // regions, 3).sum(axis=(1, 3))

        pixels = (h // regions) * (w // regions)
        pixel_variance = images.var(axis=0, ddof=1) / len(images)  # of each pixel's mean
        return blocks(images.mean(axis=0)) / pixels, blocks(pixel_variance) / pixels**2

    (mean_a, variance_a), (mean_b, variance_b) = map(block_mean_and_variance, (a, b))
    z = np.abs(mean_a - mean_b) / np.maximum(np.sqrt(variance_a + variance_b), 1e-6)
    assert np.all(z < sigmas), z.max()


def test_direct_light_agrees_with_the_path_tracer_at_one_bounce():
    # On diffuse and rough-metal surfaces Whitted adds the path tracer's direct light and
    # stops, so its image (at any depth) has the expectation of a path-traced image with
    # max_depth 1. 4 x 4 blocks, 48 comparisons at 4.5 standard errors: a false alarm with
    # probability about 3e-4 for normal z-scores (measured with 10 other sets of seeds: sd
    # 1.08, largest |z| 3.3 of 480). The seeds are fixed: a run always passes or always fails.
    scene = ptlab.load_scene("cornell-box-microfacet")
    whitted = renders(scene, range(4), integrator="whitted", spp=4, res=32)
    path = renders(scene, range(10, 14), integrator="path", max_depth=1, spp=4, res=32)
    assert_same_block_means(whitted, path, regions=4, sigmas=4.5)


@pytest.mark.parametrize("name", ["cornell-box", "cornell-box-microfacet"])
def test_cornell_boxes_render_clean_images_and_bright_lights(name):
    scene = ptlab.load_scene(name)
    image = ptlab.render(scene, integrator="whitted", spp=4, res=64, workers=1)
    assert np.isfinite(image).all()
    assert (image >= 0).all()
    on_light = footprint_on(scene, 64, emitters(scene)) == 1
    assert on_light.sum() >= 4
    radiance = scene.materials[scene.material_names.index("light")].emission
    # The camera sees the light's emission (plus what its albedo reflects of the other
    # light triangle: nothing, they lie in one plane).
    np.testing.assert_allclose(image[on_light], np.broadcast_to(radiance, (on_light.sum(), 3)), rtol=1e-5)
    # max_depth 0: emission only, exactly what the path tracer sees at depth 0.
    emission_only = ptlab.render(scene, integrator="whitted", spp=4, res=64, workers=1, max_depth=0)
    assert np.array_equal(emission_only, ptlab.render(scene, spp=4, res=64, workers=1, max_depth=0))
    assert (emission_only[footprint_on(scene, 64, emitters(scene)) == 0] == 0).all()
    assert (emission_only[on_light] == image[on_light]).all()


# -- 5. the same expectation as the path tracer --------------------------------------------


def test_whitted_has_the_path_tracers_mean_where_light_comes_through_glass_and_mirrors():
    # In the glowing room every light path that reaches the camera bounces off mirrors and
    # glass only. The path tracer picks reflection or refraction at random with the Fresnel
    # odds where Whitted takes both, weighted: at the same depth the images have the same
    # expectation. Added here: a tessellated glass sphere (lower left) and a Fresnel mirror
    # (upper right), so that four kinds of material shade side by side. 4 x 4 blocks, 48
    # comparisons at 4.5 standard errors: a false alarm with probability about 3e-4 for
    # normal z-scores (measured with 10 other sets of seeds: sd 1.05, largest |z| 3.8 of 480).
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=1.1)
    scene = mirror_glass_room(
        more=(
            (sphere.vertices[sphere.faces] + [2.0, -1.6, 1.0], Dielectric(1.5, (1.0, 0.9, 0.8))),
            (quad([-1.8, 2.6, 3.0], [0.8, 0, 0], [0, 0.8, 0.5]), Mirror((0.5, 0.7, 0.9), fresnel=True)),
        )
    )
    whitted = renders(scene, range(4), integrator="whitted", spp=8, res=32)
    path = renders(scene, range(10, 18), integrator="path", max_depth=5, spp=8, res=32)
    assert_same_block_means(whitted, path, regions=4, sigmas=4.5)


def test_a_scene_without_lights_renders_black():
    # (Scene files must have a light, but a Scene built in Python need not.)
    scene = furnace_with(Mirror(), emission=0.0)
    assert scene.area_lights is None
    image = ptlab.render(scene, integrator="whitted", spp=1, res=8, workers=1)
    assert (image == 0).all()
