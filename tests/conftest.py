"""Shared fixtures: small scenes built in Python, and the built-in Cornell box; cameras that
graze a scene's floor and a record of NaN contributions; the Hypothesis profiles."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
import trimesh
from hypothesis import HealthCheck, settings

import ptlab
import ptlab.integrators.path
from ptlab.camera import Camera
from ptlab.materials import Diffuse
from ptlab.scene import Scene

# Property-based tests (tests/test_fuzz.py) run a fixed, derandomized set of examples by
# default, so that the suite's time and verdict are the same on every run, and keep no
# example database; Hypothesis's other files (caches) go to the temporary folder, not the
# checkout. HYPOTHESIS_PROFILE=long searches afresh, far longer.
os.environ.setdefault("HYPOTHESIS_STORAGE_DIRECTORY",
                      str(Path(tempfile.gettempdir()) / "ptlab-hypothesis"))
_FUZZ = dict(database=None, deadline=None, print_blob=True,
             suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
settings.register_profile("fixed", max_examples=100, derandomize=True, **_FUZZ)
settings.register_profile("long", max_examples=2000, **_FUZZ)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "fixed"))


def closed_box_scene(albedo: float, emission: float, sampling: str = "cosine") -> Scene:
    """A closed unit-ish box whose every inner face has ``albedo`` and emits ``emission``.

    Its normals point inward, so every face emits into the box. The exact radiance
    everywhere inside is Le / (1 - albedo) (the "furnace").
    """
    return _furnace(trimesh.creation.box(extents=(2.0, 3.0, 4.0)), albedo, emission, sampling,
                    eye=(0.1, -0.2, -1.0), name="furnace")


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
    return _furnace(trimesh.creation.icosphere(subdivisions=3, radius=2.0), albedo, emission,
                    sampling, eye=(0.1, -0.2, -0.5), name="sphere-furnace")


def _furnace(mesh: trimesh.Trimesh, albedo: float, emission: float, sampling: str,
             eye: tuple[float, float, float], name: str) -> Scene:
    """The inside of the closed ``mesh``, every face of one grey that emits ``emission``,
    seen from ``eye`` inside it."""
    mesh.invert()                                   # outward normals -> inward
    triangles = mesh.vertices[mesh.faces]
    material = Diffuse(albedo=[albedo] * 3, sampling=sampling, emission=[emission] * 3)
    camera = Camera.look_at(eye, (0.3, 0.1, 1.0), fov_y=100.0)
    return Scene(triangles=triangles, material_ids=np.zeros(len(triangles), dtype=np.intp),
                 materials=[material], camera=camera, name=name)


@pytest.fixture(autouse=True)
def private_state_folder(tmp_path_factory, monkeypatch) -> None:
    """Keep 'ptlab exercise start' from recording the tests' folders in the user's own
    ~/.local/state/ptlab (where 'ptlab exercise list' would then look for them)."""
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path_factory.mktemp("state")))


@pytest.fixture(scope="session")
def cornell() -> Scene:
    return ptlab.load_scene("cornell-box")


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
    return Scene(triangles=triangles, material_ids=material_ids,
                 materials=[box.materials[0], inner], camera=box.camera, name="furnace-with")


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
    if np.linalg.norm(level) < 1e-6:          # a camera looking straight up or down
        level = np.array([0.0, 0.0, 1.0])
    middle = (low + high) / 2
    middle[1] = floor
    return {
        "along the floor": Camera.look_at(eye, eye + level, (0, 1, 0), fov_y=40),
        "on the floor": Camera.look_at(middle, middle + [1, 0, 0], (0, 1, 0), fov_y=90),
    }


@pytest.fixture
def bad_contributions(monkeypatch) -> list[int]:
    """Counts of path contributions that are NaN or infinite, as the renderer makes them.

    The film drops such contributions (``ptlab.integrators.path.add_to_film``) so that one
    bad sample cannot spoil a pixel for good; that would also hide the bug that made it.
    This records them on the way in (rendering in this process: ``workers=1``).
    """
    bad = []
    add_to_film = ptlab.integrators.path.add_to_film

    def recording_add_to_film(film, pixel, radiance):
        finite = np.isfinite(radiance).all(axis=1)
        if not finite.all():
            bad.append(int(np.count_nonzero(~finite)))
        add_to_film(film, pixel, radiance)

    monkeypatch.setattr(ptlab.integrators.path, "add_to_film", recording_add_to_film)
    return bad


def _is_multiprocessing_helper(pid: int) -> bool:
    """The fork server and resource tracker that the graders share for the whole session."""
    try:
        command = Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return True        # gone meanwhile
    return b"multiprocessing.forkserver" in command or b"multiprocessing.resource_tracker" in command


@pytest.fixture
def nothing_left_behind():
    """After the test: no process below this one but multiprocessing's own helpers."""
    from ptlab.untrusted.processes import descendants, process_table

    yield
    below = descendants({os.getpid()}, process_table(alive_only=True)) - {os.getpid()}
    left = [pid for pid in below if not _is_multiprocessing_helper(pid)]
    assert left == [], [Path(f"/proc/{pid}/cmdline").read_bytes()[:200] for pid in left]
