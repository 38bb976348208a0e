"""The scene as the renderer sees it: every mesh flattened into one array of triangles.

A ``Scene`` holds the triangles (T, 3, 3) with a material index each (and, for smooth
shading, a normal at each corner), the materials, the camera, and the lights: the emissive
triangles, point lights and a sky, from which ``ptlab.lights.build_lights`` makes the
lights that light sampling picks. The renderer never sees meshes. Scene files (TOML) are
read into a ``Scene`` by ``ptlab.scene_file`` (``load_scene``, the built-in scenes), which
imports this module: this one knows nothing of files.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ptlab.camera import Camera
from ptlab.lights import AreaLights, PointLights, Sky, build_lights, triangle_normals
from ptlab.materials import Diffuse, Material
from ptlab.meshes.base import face_normals_unnormalised, unit_corner_normals

#: Rays start this fraction of a triangle's largest coordinate off it (see ``Scene``).
OFFSET_SCALE = 1e-4


@dataclass(frozen=True)
class RenderDefaults:
    """What a scene file's ``[render]`` table asks for when the render does not say.

    Attributes:
        res: (width, height), or None for the renderer's default.
        max_depth: the most bounces, or None for the integrator's default.
    """

    res: tuple[int, int] | None = None
    max_depth: int | None = None


def bounds(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(3,) the lowest and (3,) the highest coordinates of (T, 3, 3) ``triangles``' corners:
    the corners of their bounding box."""
    corners = triangles.reshape(-1, 3)
    # One axis at a time: reducing (N, 3) along N runs NumPy's inner loop over 3 numbers at
    # a time, which is ~9x slower for a million triangles.
    low = np.array([corners[:, axis].min() for axis in range(3)])
    high = np.array([corners[:, axis].max() for axis in range(3)])
    return low, high


@dataclass
class Scene:
    """Everything the renderer needs, as flat arrays.

    Attributes:
        triangles: (T, 3, 3) float64, vertex k of triangle i at ``triangles[i, k]``.
        material_ids: (T,) intp index into ``materials`` for each triangle.
        materials: the scene's materials.
        camera: the pinhole camera.
        name: a short name for messages and metadata.
        material_names: the name of each material in the scene file.
        point_lights: the scene's ``PointLights``, or None.
        sky: the ``Sky`` that rays escaping the scene see, or None (black).
        uvs: (T, 3, 2) texture coordinates of each triangle's vertices, or None; textured
            materials need them.
        defaults: the scene file's ``[render]`` defaults.
        normals: (T, 3, 3) shading normals at each triangle's corners (a mesh file's vertex
            normals), or None: every triangle flat. Made unit length (a normal of length 0
            becomes the face's). Where a triangle's corner normals point, on the whole, to its
            back, its corners are put in the other order (with their uv), so that its front,
            which decides which side emits and which side is outside glass, is the side the
            normals give, as in pbrt-v4 and Mitsuba 3, where a mesh's normals decide it.

    After construction, ``light_sampler`` picks among all the lights (``build_lights``; None
    for a scene without light) and ``area_lights`` holds the emissive triangles among them
    (``AreaLights``, or None). ``point_lights`` and ``sky`` stay as given; the light sampler
    holds the probability of picking each kind (``LightSampler.pmf``).
    """

    triangles: np.ndarray
    material_ids: np.ndarray
    materials: list[Material]
    camera: Camera
    name: str = "scene"
    material_names: list[str] = field(default_factory=list)
    point_lights: PointLights | None = None
    sky: Sky | None = None
    uvs: np.ndarray | None = None
    defaults: RenderDefaults = field(default_factory=RenderDefaults)
    normals: np.ndarray | None = None

    def __repr__(self) -> str:
        # One line, not the arrays: what a notebook shows for a scene.
        emitting = int(self.emits.sum()) if hasattr(self, "emits") else 0
        lights = [f"{emitting} emitting triangles"] if emitting else []
        if self.point_lights is not None:
            lights.append(f"{len(self.point_lights.positions)} point lights")
        if self.sky is not None:
            lights.append("a sky")
        return (
            f"Scene({self.name!r}, {len(self.triangles)} triangles, {len(self.materials)} materials, "
            f"{', '.join(lights) or 'no light'})"
        )

    def __post_init__(self):
        tri = np.asarray(self.triangles, dtype=np.float64)
        self.triangles = tri
        self.material_ids = np.asarray(self.material_ids, dtype=np.intp)
        self.corner_normals = None
        if self.normals is not None:
            tri = self._with_corner_normals(tri)
        v0, v1, v2 = tri[:, 0], tri[:, 1], tri[:, 2]
        # Per-triangle data the renderer looks up by triangle id, in float32 like the rays.
        self.v0 = v0.astype(np.float32)
        self.e1 = (v1 - v0).astype(np.float32)
        self.e2 = (v2 - v0).astype(np.float32)
        #: (T, 3) float32 unit geometric normals, on each triangle's front face.
        self.face_normals = triangle_normals(tri).astype(np.float32)
        # How far a ray leaving the triangle starts off it, so that float32 rounding of the
        # hit point cannot put its origin behind the surface ("shadow acne"). The rounding
        # error of a point interpolated from the vertices is a few ulps of the largest vertex
        # coordinate (pbrt-v4 section 6.8): OFFSET_SCALE of it leaves a margin of ~100x and
        # stays far below any gap in a sensible scene (the Cornell light hangs 0.1 under the
        # ceiling; its offset there is 0.034).
        offset = OFFSET_SCALE * np.abs(tri).max(axis=(1, 2))
        # Everything the renderer gathers per hit, packed in one column: one `take` per
        # bounce instead of five. Rows: v0 | e1 | e2 | unit normal | offset.
        # (Filled in place: np.vstack made a float64 table and a float32 copy, 4x slower.)
        self.triangle_data = np.empty((13, len(tri)), np.float32)
        for k, rows in enumerate((self.v0, self.e1, self.e2, self.face_normals)):
            self.triangle_data[3 * k : 3 * k + 3] = rows.T
        self.triangle_data[12] = offset
        emission = np.zeros((len(self.materials), 3))
        for k, material in enumerate(self.materials):
            if material.emission is not None:
                emission[k] = material.emission
        emission = emission.astype(np.float32)
        self.emission = emission.take(self.material_ids, axis=0)
        #: (T,) bool: the triangle emits light.
        self.emits = (emission.max(axis=1) > 0).take(self.material_ids)
        emitting = np.flatnonzero(self.emits)
        # Shadow rays toward the sky go twice the scene's diagonal: out of it from anywhere.
        low, high = bounds(tri)
        sky_distance = 2 * float(np.linalg.norm(high - low))
        self.light_sampler = build_lights(
            tri[emitting],
            self.emission[emitting],
            offset[emitting],
            self.point_lights,
            self.sky,
            sky_distance,
        )
        self.area_lights = self.light_sampler.area_lights if self.light_sampler is not None else None
        self.material_table = MaterialTable(self.materials, self.material_ids)
        self.triangle_uv = None
        if self.uvs is not None:
            uvs = np.asarray(self.uvs, dtype=np.float64)
            if uvs.shape != (len(tri), 3, 2):
                raise ValueError(f"uvs must be (T, 3, 2) = {(len(tri), 3, 2)}, not {uvs.shape}")
            self.uvs = uvs
            # Packed for one gather per bounce: uv0 | uv1 - uv0 | uv2 - uv0, (6, T).
            self.triangle_uv = np.vstack(
                [uvs[:, 0].T, (uvs[:, 1] - uvs[:, 0]).T, (uvs[:, 2] - uvs[:, 0]).T]
            ).astype(np.float32)
        elif any(m.textured for m in self.materials):
            raise ValueError("a textured material needs texture coordinates: give uvs")

    def _with_corner_normals(self, tri: np.ndarray) -> np.ndarray:
        """Check and pack ``normals`` (``corner_normals``), turning the corners of triangles
        whose normals point to their back (class docstring); return the triangles."""
        normals = np.asarray(self.normals, dtype=np.float64)
        if normals.shape != (len(tri), 3, 3):
            raise ValueError(f"normals must be (T, 3, 3) = {(len(tri), 3, 3)}, not {normals.shape}")
        if not np.isfinite(normals).all():
            raise ValueError("normals must be finite")
        normals = unit_corner_normals(normals, tri)
        backward = np.einsum("ij,ij->i", face_normals_unnormalised(tri), normals.sum(axis=1)) < 0
        if backward.any():
            turned = [0, 2, 1]
            tri = np.where(backward[:, None, None], tri[:, turned], tri)
            normals = np.where(backward[:, None, None], normals[:, turned], normals)
            if self.uvs is not None and np.shape(self.uvs) == (len(tri), 3, 2):
                uvs = np.asarray(self.uvs, dtype=np.float64)
                self.uvs = np.where(backward[:, None, None], uvs[:, turned], uvs)
            self.triangles = tri
        self.normals = normals
        # Packed for one gather per hit, as the uv are: n0 | n1 - n0 | n2 - n0, (9, T).
        self.corner_normals = np.vstack(
            [normals[:, 0].T, (normals[:, 1] - normals[:, 0]).T, (normals[:, 2] - normals[:, 0]).T]
        ).astype(np.float32)
        return tri

    def with_sampling(self, sampling: str) -> Scene:
        """This scene with every diffuse material sampling directions by ``sampling``: the
        scene itself when they already do (a new Scene rebuilds its light and material
        tables)."""
        materials = [m.with_sampling(sampling) if isinstance(m, Diffuse) else m for m in self.materials]
        if all(new is old for new, old in zip(materials, self.materials, strict=True)):
            return self
        return self.with_materials(materials)

    def with_materials(self, materials: list[Material]) -> Scene:
        """This scene with ``materials`` in place of its own, one for one (the triangles keep
        their material ids; a new Scene rebuilds its light and material tables)."""
        return Scene(
            self.triangles,
            self.material_ids,
            materials,
            self.camera,
            self.name,
            self.material_names,
            self.point_lights,
            self.sky,
            self.uvs,
            self.defaults,
            self.normals,
        )

    def uv_at(self, prim: np.ndarray, b1: np.ndarray, b2: np.ndarray) -> np.ndarray:
        """(N, 2) float32 texture coordinates at the points with barycentrics ``b1``, ``b2``
        (N,) on triangles ``prim`` (N,): uv0 + b1 (uv1 - uv0) + b2 (uv2 - uv0)."""
        data = self.triangle_uv.take(prim, axis=1)
        return (data[0:2] + b1 * data[2:4] + b2 * data[4:6]).T

    def shading_normals_at(
        self, prim: np.ndarray, b1: np.ndarray, b2: np.ndarray, geometric: np.ndarray
    ) -> np.ndarray:
        """(N, 3) float32 unit shading normals at the points with barycentrics ``b1``, ``b2``
        (N,) on triangles ``prim`` (N,): the corners' normals interpolated, n0 + b1 (n1 - n0) +
        b2 (n2 - n0), and normalised (pbrt-v4 section 6.5.3, as pbrt-v3's 3.6.3 "Shading
        Geometry"); ``geometric`` (N, 3) where that is 0 (corners that cancel out)."""
        data = self.corner_normals.take(prim, axis=1)
        n = (data[0:3] + b1 * data[3:6] + b2 * data[6:9]).T
        length = np.sqrt(np.einsum("ij,ij->i", n, n))[:, None]
        if (length > 0).all():  # (the rule: spare the where)
            return n / length
        return np.where(length > 0, n / np.where(length > 0, length, 1), geometric).astype(np.float32)

    @property
    def lights(self) -> AreaLights | None:
        """``area_lights``, by the name that chapter 7's first students' files used
        (``scene.lights.sample(u)``), read-only, so that those files still run."""
        return self.area_lights

    @property
    def triangle_count(self) -> int:
        return len(self.triangles)

    def summary(self) -> str:
        """One line: name, triangles, materials, lights."""
        lights = len(self.area_lights) if self.area_lights is not None else 0
        points = len(self.point_lights) if self.point_lights is not None else 0
        sky = ", a sky" if self.sky is not None else ""
        return (
            f"{self.name}: {self.triangle_count} triangles, {len(self.materials)} materials, "
            f"{lights} emissive triangles, {points} point lights{sky}"
        )


class MaterialTable:
    """The scene's materials grouped by kind, so one vectorised call shades a whole group.

    Attributes:
        groups: one stacked material per kind (``Material.stack``).
        group: (M,) intp, the group of each scene material.
        row: (M,) intp, each scene material's row inside its stacked group.
        triangle_group, triangle_row: (T,) intp, the same for each triangle's material (one
            lookup per hit instead of two), given the triangles' ``material_ids``.
    """

    def __init__(self, materials: list[Material], material_ids: np.ndarray | None = None):
        members: dict[object, list[int]] = {}
        for k, material in enumerate(materials):
            members.setdefault(material.batch_key(), []).append(k)
        self.groups = []
        self.group = np.zeros(len(materials), dtype=np.intp)
        self.row = np.zeros(len(materials), dtype=np.intp)
        for g, indices in enumerate(members.values()):
            kind = type(materials[indices[0]])
            self.groups.append(kind.stack([materials[k] for k in indices]))
            self.group[indices] = g
            self.row[indices] = np.arange(len(indices))
        if material_ids is not None:
            self.triangle_group = self.group.take(material_ids)
            self.triangle_row = self.row.take(material_ids)
