"""Chapter 1's checks: cameras and primary rays (``generate_rays``).

Known answers come from the pinhole model itself (the centre ray is ``forward``, the edge of
the image is fov_y / 2 off it, pixel (0, 0) is top left), then the student's rays render the
Cornell box's normals, which must match the library's picture. The camera, the image sizes
and the pixels come from the grading seed (``ptlab.course.chapter.grading_rng``): new
for every grading, so no rays computed beforehand match.
"""

from __future__ import annotations

import copy
import math

import numpy as np

from ptlab.course.chapter import Chapter, ChapterCheck, ChapterRender, CheckFailed, grading_rng, require
from ptlab.course.finite import require_finite
from ptlab.course.messages import aside, text
from ptlab.rendering.pieces import Pieces


def _camera():
    """The grading run's camera: somewhere, looking somewhere, leaning a little, 30 to 80
    degrees of vertical field of view."""
    from ptlab.camera import Camera

    rng = grading_rng(0)
    position = rng.uniform(-3, 3, 3)
    target = position + rng.normal(size=3)
    up = np.array([0.0, 1.0, 0.0]) + rng.uniform(-0.3, 0.3, 3)
    return Camera.look_at(tuple(position), tuple(target), up=tuple(up), fov_y=float(rng.uniform(30, 80)))


def _size(stream: int, even: bool) -> tuple[int, int]:
    """(width, height) of the grading run's image for one check: even or odd both."""
    rng = grading_rng(stream)
    width, height = (int(2 * rng.integers(2, 21) + (0 if even else 1)) for _ in range(2))
    return width, height


def _rays(module, camera, width, height, pixel_x, pixel_y, u):
    """The student's rays, checked for shape, type, length and NaN. The student's function
    gets copies of the camera and the arrays: what the check computes from them afterwards
    is the grader's own."""
    (generate_rays,) = require(module, "generate_rays")
    pixel_x, pixel_y = np.atleast_1d(pixel_x), np.atleast_1d(pixel_y)
    result = generate_rays(
        copy.deepcopy(camera), width, height, pixel_x.copy(), pixel_y.copy(), np.array(u, dtype=np.float32)
    )
    if not (isinstance(result, tuple) and len(result) == 2):
        raise CheckFailed(text("ch01.two_arrays"))
    origins, dirs = (np.asarray(a, dtype=np.float64) for a in result)
    n = len(pixel_x)
    if origins.shape != (n, 3) or dirs.shape != (n, 3):
        raise CheckFailed(text("ch01.shapes", n=n, origins=origins.shape, dirs=dirs.shape))

    def ray(index, shape) -> str:
        return text("ch01.row", row=index[0], x=pixel_x[index[0]], y=pixel_y[index[0]])

    require_finite(origins, text("ch01.origins"), ray)
    require_finite(dirs, text("ch01.dirs"), ray)
    return origins, dirs


def check_centre_ray(module) -> str:
    camera = _camera()
    width, height = _size(2, even=False)
    origins, dirs = _rays(module, camera, width, height, [width // 2], [height // 2], [[0.5, 0.5]])
    if not np.allclose(origins[0], camera.position, atol=1e-5):
        raise CheckFailed(text("ch01.eye", eye=camera.position, yours=origins[0]))
    if not np.allclose(dirs[0], camera.forward, atol=1e-5):
        raise CheckFailed(
            text("ch01.centre", forward=np.round(camera.forward, 4), yours=np.round(dirs[0], 4))
        )
    _require_fan(module, camera)
    return text("ch01.centre_ok")


def _require_fan(module, camera) -> None:
    """The rays through the four corner pixels leave the centre ray, each its own way: a
    constant forward direction (which has the centre ray right) fails here."""
    from ptlab.camera import generate_rays

    width, height = 5, 3
    pixel_x, pixel_y, u = np.array([0, 4, 0, 4]), np.array([0, 0, 2, 2]), np.full((4, 2), 0.5)
    _, dirs = _rays(module, camera, width, height, pixel_x, pixel_y, u)
    _, expected = generate_rays(camera, width, height, pixel_x, pixel_y, u.astype(np.float32))
    unit = dirs / np.maximum(np.linalg.norm(dirs, axis=1, keepdims=True), 1e-300)
    off_forward = np.arccos(np.clip(unit @ camera.forward, -1, 1))
    want = np.arccos(np.clip(expected @ camera.forward, -1, 1))
    spread = np.arccos(np.clip(unit @ unit.T, -1, 1))[np.triu_indices(4, 1)]
    # A tenth of the pinhole's angles: a wrong field of view passes, the same ray everywhere does not.
    if not (np.all(off_forward >= want / 10) and np.all(spread >= want.min() / 10)):
        raise CheckFailed(text("ch01.fan"))


def check_unit_length(module) -> str:
    rng = grading_rng(1)
    width, height = _size(3, even=True)
    _, dirs = _rays(
        module,
        _camera(),
        width,
        height,
        rng.integers(0, width, 500),
        rng.integers(0, height, 500),
        rng.random((500, 2)),
    )
    length = np.linalg.norm(dirs, axis=1)
    worst = np.argmax(np.abs(length - 1))
    if not abs(length[worst] - 1) <= 1e-5:
        raise CheckFailed(text("ch01.length", length=length[worst]))
    return text("ch01.length_ok")


def check_field_of_view(module) -> str:
    camera = _camera()
    width, height = _size(4, even=True)
    # The middle of the top edge and the middle of the left edge.
    middle = [width // 2, 0], [0, height // 2]
    _, dirs = _rays(module, camera, width, height, *middle, [[0.0, 0.0], [0.0, 0.0]])
    half_fov = math.radians(camera.fov_y) / 2
    top_angle = math.acos(np.clip(dirs[0] @ camera.forward, -1, 1))
    if not abs(top_angle - half_fov) <= 1e-4:
        raise CheckFailed(
            text("ch01.top_edge", expected=math.degrees(half_fov), yours=math.degrees(top_angle))
            + _field_of_view_hint(top_angle, camera.fov_y, width / height)
        )
    expected_side = math.atan(math.tan(half_fov) * width / height)
    side_angle = math.acos(np.clip(dirs[1] @ camera.forward, -1, 1))
    if not abs(side_angle - expected_side) <= 1e-4:
        raise CheckFailed(
            text("ch01.left_edge", expected=math.degrees(expected_side), yours=math.degrees(side_angle))
        )
    return text("ch01.fov_ok")


def _field_of_view_hint(top_angle: float, fov_y: float, aspect: float) -> str:
    """Which typical mistake gives the top edge the angle ``top_angle`` (radians), if one does."""
    half = math.radians(fov_y) / 2
    mistakes = {
        "ch01.hint.degrees": math.atan(abs(math.tan(fov_y / 2))),
        "ch01.hint.whole_fov": math.atan(math.tan(2 * half)),
        "ch01.hint.aspect_on_y": math.atan(math.tan(half) * aspect),
        "ch01.hint.aspect_divides_y": math.atan(math.tan(half) / aspect),
    }
    for hint, angle in mistakes.items():
        if abs(top_angle - angle) <= 1e-4:
            return aside(text(hint))
    return ""


def check_orientation(module) -> str:
    camera = _camera()
    width, height = _size(5, even=True)
    _, dirs = _rays(module, camera, width, height, [0], [0], [[0.0, 0.0]])
    if not dirs[0] @ camera.up > 0:
        hint = text("ch01.hint.rows_down")
        if math.tan(camera.fov_y / 2) < 0:  # (degrees taken as radians can turn tan negative)
            _, top = _rays(module, camera, width, height, [width // 2], [0], [[0.0, 0.0]])
            below = math.acos(np.clip(top[0] @ camera.forward, -1, 1))
            if abs(below - math.atan(abs(math.tan(camera.fov_y / 2)))) <= 1e-4:
                hint = text("ch01.hint.turned_over", half=camera.fov_y / 2)
        raise CheckFailed(text("ch01.top", hint=hint))
    if not dirs[0] @ camera.right < 0:
        raise CheckFailed(text("ch01.left"))
    return text("ch01.orientation_ok")


def check_known_rays(module) -> str:
    from ptlab.camera import generate_rays

    camera = _camera()
    rng = grading_rng(7)
    width, height = _size(6, even=True)
    pixel_x, pixel_y = rng.integers(0, width, 200), rng.integers(0, height, 200)
    u = rng.random((200, 2))
    _, expected = generate_rays(camera, width, height, pixel_x, pixel_y, u.astype(np.float32))
    _, dirs = _rays(module, camera, width, height, pixel_x, pixel_y, u)
    worst = np.abs(dirs - expected).max()
    if not worst <= 1e-4:
        raise CheckFailed(
            text("ch01.jittered", worst=worst)
            + _jitter_hint(dirs, camera, width, height, pixel_x, pixel_y, u)
        )
    return text("ch01.jittered_ok")


def _jitter_hint(dirs, camera, width, height, pixel_x, pixel_y, u) -> str:
    """Which handling of the jitter ``u`` the student's rays ``dirs`` match, if a typical
    mistake's: each is the pinhole model with u changed."""
    from ptlab.camera import generate_rays

    mistakes = {
        "ch01.hint.u_ignored": np.full_like(u, 0.5),
        "ch01.hint.extra_half": u + 0.5,
        "ch01.hint.u_swapped": u[:, ::-1],
        "ch01.hint.u_subtracted": -u,
    }
    for hint, changed in mistakes.items():
        _, wrong = generate_rays(camera, width, height, pixel_x, pixel_y, changed.astype(np.float32))
        if np.abs(dirs - wrong).max() <= 1e-4:
            return aside(text(hint))
    return aside(text("ch01.hint.jitter"))


def _student_rays(module) -> Pieces:
    """A render's pieces with the student's ``generate_rays`` for the primary rays."""

    def student_rays(camera, width, height, pixel_x, pixel_y, u):
        origins, dirs = _rays(module, camera, width, height, pixel_x, pixel_y, u)
        return (np.asfortranarray(origins, dtype=np.float32), np.asfortranarray(dirs, dtype=np.float32))

    return Pieces(generate_rays=student_rays)


def check_render(module) -> str:
    from ptlab.course.renders import check_render_through

    return check_render_through(text("ch01.yours"), _student_rays(module), nan_hint=text("ch01.nan_hint"))


def render_yours(module, scene, options: dict) -> np.ndarray:
    """``scene`` rendered through the student's rays (``ptlab exercise render``)."""
    from ptlab.course.side_by_side import render_with_pieces

    return render_with_pieces(scene, options, _student_rays(module))


CHAPTER = Chapter(
    number=1,
    slug="cameras",
    title="Cameras and primary rays",
    functions=("generate_rays",),
    answers=("ptlab.camera.generate_rays",),
    # The render's camera samples are primary rays too.
    also_left_out=("ptlab.rendering.jobs.CameraSamples", "ptlab.inspector"),
    checks=(
        ChapterCheck("centre ray", 2, check_centre_ray, timeout=30),
        # Any constant unit direction has length 1, and a constant one up and to the left
        # has pixel (0, 0)'s signs: these score only once the rays fan out from the centre.
        ChapterCheck("unit directions", 1, check_unit_length, timeout=30, requires=("centre ray",)),
        ChapterCheck("field of view", 2, check_field_of_view, timeout=30),
        ChapterCheck("image orientation", 1, check_orientation, timeout=30, requires=("centre ray",)),
        ChapterCheck("jittered rays", 2, check_known_rays, timeout=30),
        ChapterCheck("render", 2, check_render, timeout=60),
    ),
    render=ChapterRender(render_yours),
)
