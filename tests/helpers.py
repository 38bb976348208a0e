"""What several test files build or check: small scenes made in Python (closed furnaces,
a furnace around one object, cameras that graze a floor), a material that records how the
graders call it, and the list of the library's modules. Fixtures stay in ``conftest.py``;
test files import these by name (``from helpers import closed_sphere_scene``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from ptlab.camera import Camera
from ptlab.materials import Diffuse
from ptlab.scene import Scene

# -- scenes -----------------------------------------------------------------------------------


def closed_box_scene(albedo: float, emission: float, sampling: str = "cosine") -> Scene:
    """A closed unit-ish box whose every inner face has ``albedo`` and emits ``emission``.

    Its normals point inward, so every face emits into the box. The exact radiance
    everywhere inside is Le / (1 - albedo) (the "furnace").
    """
    return _furnace(
        trimesh.creation.box(extents=(2.0, 3.0, 4.0)),
        albedo,
        emission,
        sampling,
        eye=(0.1, -0.2, -1.0),
        name="furnace",
    )


def closed_sphere_scene(albedo: float, emission: float, sampling: str = "cosine") -> Scene:
    """A closed sphere (an icosphere of 1280 triangles) whose inside has ``albedo`` and emits
    ``emission``: the furnace of ``closed_box_scene``, Le / (1 - albedo) everywhere.

    In a sphere, light sampling by area is nearly exact: for two points x, y on a sphere of
    radius R, cos(theta_x) cos(theta_y) / |x - y|^2 = 1 / (4 R^2) whatever they are. In a box
    it is not: points near a shared edge of two faces see each other at distances near 0,
    and the estimator's variance is infinite (measured: values up to 1700 times the mean),
    so a mean over seeds is far from normal and a test in standard errors fails far more
    often than it says, all the more with samplers that stratify the rest of the noise away.
    """
    return _furnace(
        trimesh.creation.icosphere(subdivisions=3, radius=2.0),
        albedo,
        emission,
        sampling,
        eye=(0.1, -0.2, -0.5),
        name="sphere-furnace",
    )


def _furnace(
    mesh: trimesh.Trimesh,
    albedo: float,
    emission: float,
    sampling: str,
    eye: tuple[float, float, float],
    name: str,
) -> Scene:
    """The inside of the closed ``mesh``, every face of one grey that emits ``emission``,
    seen from ``eye`` inside it."""
    mesh.invert()  # outward normals -> inward
    triangles = mesh.vertices[mesh.faces]
    material = Diffuse(albedo=[albedo] * 3, sampling=sampling, emission=[emission] * 3)
    camera = Camera.look_at(eye, (0.3, 0.1, 1.0), fov_y=100.0)
    return Scene(
        triangles=triangles,
        material_ids=np.zeros(len(triangles), dtype=np.intp),
        materials=[material],
        camera=camera,
        name=name,
    )


def furnace_with(inner, albedo: float = 0.5, emission: float = 0.3) -> Scene:
    """``closed_box_scene`` with a sphere of material ``inner`` in the middle.

    A lossless mirror or glass object in a uniform radiance field leaves it uniform, so the
    image must still be Le / (1 - albedo) everywhere.
    """
    box = closed_box_scene(albedo, emission)
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.6)
    sphere_triangles = sphere.vertices[sphere.faces] + np.array([0.2, 0.1, 0.4])
    triangles = np.concatenate([box.triangles, sphere_triangles])
    material_ids = np.concatenate([box.material_ids, np.ones(len(sphere_triangles), dtype=np.intp)])
    return Scene(
        triangles=triangles,
        material_ids=material_ids,
        materials=[box.materials[0], inner],
        camera=box.camera,
        name="furnace-with",
    )


def grazing_cameras(scene) -> dict[str, Camera]:
    """Cameras that look along the floor (the scene's lowest plane, y = min y).

    ``along the floor``: the scene's camera lowered to the floor, looking level the way it
    looked; the rays of the middle rows run in the floor's plane or just off it.
    ``on the floor``: standing on the floor in the middle of the scene, looking along +x:
    every ray starts on a surface, half of them below it.
    """
    low, high = scene.triangles.min(axis=(0, 1)), scene.triangles.max(axis=(0, 1))
    floor = low[1]
    eye = scene.camera.position.copy()
    eye[1] = floor
    level = scene.camera.forward * [1, 0, 1]
    if np.linalg.norm(level) < 1e-6:  # a camera looking straight up or down
        level = np.array([0.0, 0.0, 1.0])
    middle = (low + high) / 2
    middle[1] = floor
    return {
        "along the floor": Camera.look_at(eye, eye + level, (0, 1, 0), fov_y=40),
        "on the floor": Camera.look_at(middle, middle + np.array([1, 0, 0]), (0, 1, 0), fov_y=90),
    }


# -- materials that record their calls -------------------------------------------------------


class Recording:
    """A right material (the library's, called through) that records the wo and n of every
    call: any object with the methods is a material to the graders."""

    def __init__(self, material):
        self.material, self.calls = material, []

    def __getattr__(self, name: str):  # is_delta, eta: the material's
        if name in ("material", "calls"):
            raise AttributeError(name)
        return getattr(self.material, name)

    def _record(self, method: str, wo, n):
        self.calls.append((method, np.array(wo, dtype=np.float64), np.array(n, dtype=np.float64)))
        return getattr(self.material, method)

    def eval(self, wo, wi, n):
        return self._record("eval", wo, n)(wo, wi, n)

    def pdf(self, wo, wi, n):
        return self._record("pdf", wo, n)(wo, wi, n)

    def sample(self, wo, n, u):
        return self._record("sample", wo, n)(wo, n, u)

    def sample_weight(self, wo, n, u, front=None):
        method = self._record("sample_weight", wo, n)
        return method(wo, n, u) if front is None else method(wo, n, u, front)


def assert_every_call_mixes_its_rows(calls):
    """No call of two rows or more has one wo, one n, or one angle between them on every row;
    and some calls have a single row (the row-independence check)."""
    for method, wo, n in calls:
        if len(wo) < 2:
            continue
        assert not (wo == wo[0]).all(), f"{method}: every row has the same wo ({len(wo)} rows)"
        assert not (n == n[0]).all(), f"{method}: every row has the same n ({len(wo)} rows)"
        cos_theta_o = np.sum(wo * n, axis=1)
        assert np.ptp(cos_theta_o) > 1e-6, f"{method}: every row has the same wo . n ({len(wo)} rows)"
    assert any(len(wo) == 1 for _, wo, _ in calls)
    assert {method for method, _, _ in calls} >= {"eval", "pdf", "sample", "sample_weight"}


# -- the library's modules --------------------------------------------------------------------

PACKAGE = Path(__file__).resolve().parent.parent / "ptlab"


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def library_modules() -> dict[str, Path]:
    """Every module of the library (the students' exercise files are not part of it)."""
    return {module_name(p): p for p in PACKAGE.rglob("*.py") if not {"templates", "solutions"} & set(p.parts)}


def load_script(name: str):
    """``scripts/NAME.py`` as a module (the scripts are programs, not a package)."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "scripts" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"{name}_script", path)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
