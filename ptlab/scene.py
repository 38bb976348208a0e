"""Scenes: a small TOML file naming a camera, materials and meshes.

A scene file looks like this (``scenes/cornell-box/scene.toml`` is a full example)::

    [camera]
    position = [278, 273, -800]
    look_at = [278, 273, 0]     # or: direction = [0, 0, 1]
    up = [0, 1, 0]              # optional, default +y
    fov = 40                    # vertical field of view, degrees

    [materials.white]
    type = "diffuse"
    albedo = [0.725, 0.71, 0.68]

    [materials.light]
    type = "diffuse"
    albedo = 0.65                           # one number is a grey
    emission = [47.8348, 38.5664, 31.0808]  # emitted radiance, from the front face

    [[mesh]]
    file = "meshes/floor.obj"   # any format trimesh reads; relative to the scene file
    material = "white"

Loading flattens every mesh into one array of triangles with a material index each
(``Scene``); the renderer never sees meshes. Anything wrong in the file raises a
``SceneError`` that names the file, the key and the problem.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ptlab.camera import Camera
from ptlab.errors import SceneError
from ptlab.lights import AreaLights
from ptlab.materials import Dielectric, Diffuse, Material, Microfacet, Mirror

SCENE_FILE_NAME = "scene.toml"

#: The keys each material type takes in a scene file (besides ``type`` and ``emission``).
MATERIAL_KEYS = {
    "diffuse": {"albedo"},
    "microfacet": {"f0", "roughness", "alpha", "kd", "ks", "sampling"},
    "mirror": {"reflectance", "fresnel"},
    "dielectric": {"eta", "transmittance"},
}

#: Rays start this fraction of a triangle's largest coordinate off it (see ``Scene``).
OFFSET_SCALE = 1e-4


def builtin_scenes_dir() -> Path:
    """The folder of the built-in scenes: inside the installed package, or the checkout's."""
    package = Path(__file__).resolve().parent
    for candidate in (package / "scenes", package.parent / "scenes"):
        if candidate.is_dir():
            return candidate
    return package / "scenes"


def builtin_scene_names() -> list[str]:
    """Names of the scenes that ship with ptlab, e.g. ``cornell-box``."""
    root = builtin_scenes_dir()
    if not root.is_dir():
        return []
    return sorted(p.name for p in root.iterdir() if (p / SCENE_FILE_NAME).is_file())


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
    """

    triangles: np.ndarray
    material_ids: np.ndarray
    materials: list[Material]
    camera: Camera
    name: str = "scene"
    material_names: list[str] = field(default_factory=list)

    def __post_init__(self):
        tri = np.asarray(self.triangles, dtype=np.float64)
        self.triangles = tri
        self.material_ids = np.asarray(self.material_ids, dtype=np.intp)
        v0, v1, v2 = tri[:, 0], tri[:, 1], tri[:, 2]
        cross = np.cross(v1 - v0, v2 - v0)
        # Per-triangle data the renderer looks up by triangle id, in float32 like the rays.
        self.v0 = v0.astype(np.float32)
        self.e1 = (v1 - v0).astype(np.float32)
        self.e2 = (v2 - v0).astype(np.float32)
        self.normals = (cross / np.linalg.norm(cross, axis=1, keepdims=True)).astype(np.float32)
        # How far a ray leaving the triangle starts off it, so that float32 rounding of the
        # hit point cannot put its origin behind the surface ("shadow acne"). The rounding
        # error of a point interpolated from the vertices is a few ulps of the largest vertex
        # coordinate (pbrt-v4 section 6.8): OFFSET_SCALE of it leaves a margin of ~100x and
        # stays far below any gap in a sensible scene (the Cornell light hangs 0.1 under the
        # ceiling; its offset there is 0.034).
        offset = OFFSET_SCALE * np.abs(tri).max(axis=(1, 2))
        # Everything the renderer gathers per hit, packed in one column: one `take` per
        # bounce instead of five. Rows: v0 | e1 | e2 | unit normal | offset.
        self.triangle_data = np.vstack([self.v0.T, self.e1.T, self.e2.T, self.normals.T,
                                        offset[None]]).astype(np.float32)
        emission = np.zeros((len(self.materials), 3))
        for k, material in enumerate(self.materials):
            if material.emission is not None:
                emission[k] = material.emission
        self.emission = emission.astype(np.float32).take(self.material_ids, axis=0)
        emitters = np.flatnonzero(self.emission.max(axis=1) > 0)
        self.lights = AreaLights(v0[emitters], v1[emitters], v2[emitters],
                                 self.emission[emitters], offset[emitters]) if len(emitters) else None
        self.material_table = MaterialTable(self.materials)

    def with_sampling(self, sampling: str) -> Scene:
        """This scene with every diffuse material sampling directions by ``sampling``."""
        materials = [m.with_sampling(sampling) if isinstance(m, Diffuse) else m
                     for m in self.materials]
        return Scene(self.triangles, self.material_ids, materials, self.camera, self.name,
                     self.material_names)

    @property
    def triangle_count(self) -> int:
        return len(self.triangles)

    def summary(self) -> str:
        """One line: name, triangles, materials, lights."""
        lights = len(self.lights) if self.lights is not None else 0
        return (f"{self.name}: {self.triangle_count} triangles, {len(self.materials)} materials, "
                f"{lights} emissive triangles")


class MaterialTable:
    """The scene's materials grouped by kind, so one vectorised call shades a whole group.

    Attributes:
        groups: one stacked material per kind (``Material.stack``).
        group: (M,) intp, the group of each scene material.
        row: (M,) intp, each scene material's row inside its stacked group.
    """

    def __init__(self, materials: list[Material]):
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


def find_scene_file(name_or_path: str | Path) -> Path:
    """A scene file from a path (a file, or a folder holding ``scene.toml``) or a built-in name."""
    path = Path(name_or_path)
    if path.is_file():
        return path
    if path.is_dir():
        if (path / SCENE_FILE_NAME).is_file():
            return path / SCENE_FILE_NAME
        raise SceneError(path, f"folder has no {SCENE_FILE_NAME}")
    builtin = builtin_scenes_dir() / str(name_or_path) / SCENE_FILE_NAME
    if builtin.is_file():
        return builtin
    names = ", ".join(builtin_scene_names()) or "none found"
    raise SceneError(name_or_path, f"no such scene file or built-in scene (built-in: {names})")


def load_scene(name_or_path: str | Path) -> Scene:
    """Load a scene by built-in name (``"cornell-box"``) or from a scene file path."""
    path = find_scene_file(name_or_path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as error:
        raise SceneError(path, f"malformed TOML: {error}") from None
    except (OSError, UnicodeDecodeError) as error:
        raise SceneError(path, f"cannot read: {error}") from None
    return _SceneReader(path).read(data)


class _SceneReader:
    """Turns the parsed TOML of one scene file into a ``Scene``, checking every value."""

    def __init__(self, path: Path):
        self.path = path

    def error(self, key: str | None, problem: str) -> SceneError:
        return SceneError(self.path, problem, key)

    def read(self, data: dict) -> Scene:
        self.check_keys(data, None, {"camera", "materials", "mesh"})
        if "camera" not in data:
            raise self.error(None, "no [camera] section")
        camera = self.camera(data["camera"])
        materials_table = data.get("materials", {})
        if not isinstance(materials_table, dict) or not materials_table:
            raise self.error("materials", "no materials: add a [materials.NAME] section")
        names = list(materials_table)
        materials = [self.material(f"materials.{name}", spec)
                     for name, spec in materials_table.items()]
        meshes = data.get("mesh", [])
        if not isinstance(meshes, list) or not meshes:
            raise self.error("mesh", "no meshes: add a [[mesh]] section")
        triangles, material_ids = [], []
        for i, spec in enumerate(meshes):
            tri, material = self.mesh(f"mesh[{i}]", spec, names)
            triangles.append(tri)
            material_ids.append(np.full(len(tri), material, dtype=np.intp))
        scene = Scene(triangles=np.concatenate(triangles), material_ids=np.concatenate(material_ids),
                      materials=materials, camera=camera, name=self.path.parent.name
                      if self.path.name == SCENE_FILE_NAME else self.path.stem,
                      material_names=names)
        if scene.lights is None:
            raise self.error(None, "the scene has no light: give a material an `emission` "
                                   "and a mesh that uses it")
        if not scene.lights.total_area > 0:
            raise self.error(None, "the lights have zero area")
        return scene

    def check_keys(self, table: dict, key: str | None, allowed: set[str]) -> None:
        if not isinstance(table, dict):
            raise self.error(key, "must be a table")
        for name in table:
            if name not in allowed:
                full = name if key is None else f"{key}.{name}"
                raise self.error(full, f"unknown key (expected one of: {', '.join(sorted(allowed))})")

    def vector(self, table: dict, key: str, name: str, default=None) -> np.ndarray:
        full = f"{key}.{name}"
        if name not in table:
            if default is None:
                raise self.error(full, "missing")
            return np.asarray(default, dtype=np.float64)
        value = table[name]
        if (not isinstance(value, list) or len(value) != 3
                or not all(isinstance(x, int | float) and not isinstance(x, bool) for x in value)):
            raise self.error(full, f"must be a list of 3 numbers, got {value!r}")
        vector = np.asarray(value, dtype=np.float64)
        if not np.all(np.isfinite(vector)):
            raise self.error(full, f"must be finite, got {value!r}")
        return vector

    def number(self, table: dict, key: str, name: str, default: float | None = None) -> float:
        full = f"{key}.{name}"
        if name not in table:
            if default is None:
                raise self.error(full, "missing")
            return default
        value = table[name]
        if not isinstance(value, int | float) or isinstance(value, bool) or not math.isfinite(value):
            raise self.error(full, f"must be a finite number, got {value!r}")
        return float(value)

    def colour(self, table: dict, key: str, name: str, default, upper: float | None) -> np.ndarray:
        full = f"{key}.{name}"
        value = table.get(name, default)
        if isinstance(value, int | float) and not isinstance(value, bool):
            value = [value] * 3
        colour = self.vector({name: value}, key, name)
        if np.any(colour < 0):
            raise self.error(full, f"must not be negative, got {colour.tolist()}")
        if upper is not None and np.any(colour > upper):
            raise self.error(full, f"must be at most {upper} (energy conservation), "
                                   f"got {colour.tolist()}")
        return colour

    def camera(self, spec: dict) -> Camera:
        key = "camera"
        self.check_keys(spec, key, {"position", "look_at", "direction", "up", "fov"})
        position = self.vector(spec, key, "position")
        if ("look_at" in spec) == ("direction" in spec):
            raise self.error(key, "give exactly one of `look_at` and `direction`")
        if "look_at" in spec:
            forward = self.vector(spec, key, "look_at") - position
        else:
            forward = self.vector(spec, key, "direction")
        up = self.vector(spec, key, "up", default=(0.0, 1.0, 0.0))
        fov = self.number(spec, key, "fov", default=40.0)
        if not 0 < fov < 180:
            raise self.error(f"{key}.fov", f"must be between 0 and 180 degrees, got {fov}")
        if np.linalg.norm(forward) == 0:
            raise self.error(key, "the camera looks nowhere (zero direction)")
        forward = forward / np.linalg.norm(forward)
        if np.linalg.norm(up) == 0 or np.linalg.norm(np.cross(forward, up / np.linalg.norm(up))) < 1e-6:
            raise self.error(f"{key}.up", "must not be zero or parallel to the viewing direction")
        return Camera.look_at(position, position + forward, up, fov)

    def material(self, key: str, spec: dict) -> Material:
        if not isinstance(spec, dict):
            raise self.error(key, "must be a table")
        kind = spec.get("type")
        known = ", ".join(MATERIAL_KEYS)
        if kind is None:
            raise self.error(f"{key}.type", f"missing (known types: {known})")
        if kind not in MATERIAL_KEYS:
            raise self.error(f"{key}.type", f"unknown material type {kind!r} (known types: {known})")
        self.check_keys(spec, key, {"type", "emission"} | MATERIAL_KEYS[kind])
        emission = self.colour(spec, key, "emission", default=0.0, upper=None)
        try:
            material = self.build_material(kind, key, spec)
        except ValueError as error:
            raise self.error(key, str(error)) from None
        material.emission = emission if emission.max() > 0 else None
        return material

    def build_material(self, kind: str, key: str, spec: dict) -> Material:
        """The material of one ``[materials.NAME]`` table (its keys already checked)."""
        if kind == "diffuse":
            return Diffuse(albedo=self.colour(spec, key, "albedo", default=0.8, upper=1.0))
        if kind == "mirror":
            return Mirror(reflectance=self.colour(spec, key, "reflectance", 1.0, upper=1.0),
                          fresnel=self.flag(spec, key, "fresnel", default=False))
        if kind == "dielectric":
            return Dielectric(eta=self.number(spec, key, "eta", default=1.5),
                              transmittance=self.colour(spec, key, "transmittance", 1.0, 1.0))
        f0 = spec.get("f0", "gold")
        if not isinstance(f0, str):
            f0 = self.colour(spec, key, "f0", default=None, upper=1.0)
        options = {name: self.number(spec, key, name) for name in ("roughness", "alpha")
                   if name in spec}
        sampling = spec.get("sampling", "vndf")
        if not isinstance(sampling, str):
            raise self.error(f"{key}.sampling", f"must be a string, got {sampling!r}")
        return Microfacet(f0=f0, kd=self.colour(spec, key, "kd", 0.0, upper=1.0),
                          ks=self.colour(spec, key, "ks", 1.0, upper=1.0), sampling=sampling,
                          **options)

    def flag(self, table: dict, key: str, name: str, default: bool) -> bool:
        value = table.get(name, default)
        if not isinstance(value, bool):
            raise self.error(f"{key}.{name}", f"must be true or false, got {value!r}")
        return value

    def mesh(self, key: str, spec: dict, material_names: list[str]) -> tuple[np.ndarray, int]:
        self.check_keys(spec, key, {"file", "sphere", "material"})
        if not isinstance(spec.get("material"), str):
            raise self.error(f"{key}.material", "missing, or not a string")
        if spec["material"] not in material_names:
            raise self.error(f"{key}.material", f"no material named {spec['material']!r} "
                                                f"(defined: {', '.join(material_names)})")
        if ("file" in spec) == ("sphere" in spec):
            raise self.error(key, "give exactly one of `file` and `sphere`")
        if "sphere" in spec:
            triangles = self.sphere(f"{key}.sphere", spec["sphere"])
        else:
            if not isinstance(spec["file"], str):
                raise self.error(f"{key}.file", "must be a string")
            mesh_path = self.path.parent / spec["file"]
            if not mesh_path.is_file():
                raise self.error(f"{key}.file", f"mesh file not found: {mesh_path}")
            triangles = read_mesh_triangles(mesh_path, f"{self.path}: {key}.file")
        return triangles, material_names.index(spec["material"])

    def sphere(self, key: str, spec: dict) -> np.ndarray:
        """An icosphere (trimesh) from ``{center = [x, y, z], radius = r, subdivisions = 4}``."""
        import trimesh

        self.check_keys(spec, key, {"center", "radius", "subdivisions"})
        center = self.vector(spec, key, "center")
        radius = self.number(spec, key, "radius")
        subdivisions = spec.get("subdivisions", 4)
        if radius <= 0:
            raise self.error(f"{key}.radius", f"must be positive, got {radius}")
        if not isinstance(subdivisions, int) or isinstance(subdivisions, bool) or not (
                0 <= subdivisions <= 7):
            raise self.error(f"{key}.subdivisions", f"must be an integer from 0 to 7, "
                                                    f"got {subdivisions!r}")
        mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
        return mesh.vertices[mesh.faces] + center


def read_mesh_triangles(path: Path, where: str | None = None) -> np.ndarray:
    """(T, 3, 3) float64 triangles of a mesh file, through trimesh.

    Raises ``SceneError`` for unreadable files, empty meshes and non-finite vertices.
    Degenerate (zero-area) triangles are dropped: no ray can hit them.
    """
    import trimesh

    where = where or str(path)
    try:
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as error:  # trimesh raises many kinds for unreadable files
        raise SceneError(where, f"cannot read mesh {path.name}: {error}") from None
    vertices = np.asarray(getattr(mesh, "vertices", ()), dtype=np.float64)
    faces = np.asarray(getattr(mesh, "faces", ()), dtype=np.intp)
    if len(faces) == 0:
        raise SceneError(where, f"mesh {path.name} has no triangles")
    bad = ~np.isfinite(vertices).all(axis=1)
    if bad.any():
        raise SceneError(where, f"mesh {path.name} has {int(bad.sum())} vertices that are NaN "
                                f"or infinite (first: vertex {int(np.flatnonzero(bad)[0])})")
    triangles = vertices[faces]
    area2 = np.linalg.norm(np.cross(triangles[:, 1] - triangles[:, 0],
                                    triangles[:, 2] - triangles[:, 0]), axis=1)
    triangles = triangles[area2 > 0]
    if len(triangles) == 0:
        raise SceneError(where, f"mesh {path.name} has only zero-area triangles")
    return triangles
