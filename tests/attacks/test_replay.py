"""Replays of the library's outputs, and pictures that are not renders (issue 25).

A student who knows the checks' inputs computes the library's answers for them once, at
home, and the file replays them, keyed by a hash of the inputs
(``submissions/replay_answers.py``). The tests build that table as such a student would:
the library's own answer files run through the chapters' own checks with the inputs the
checks drew before the grading seed (stream k of ``np.random.default_rng(k)``, render seed
k, the furnace of albedo 0.5 and Le 0.3). The same file earns marks where the inputs are
those (the grader of before, ``_old_inputs``), and nothing under a fresh grading seed.

A loop that ignores its samples and adds a converged picture, or the furnace's analytic
value, is far less noisy than any render of those samples: "too clean".
"""

from __future__ import annotations

import base64
import importlib.util
import inspect
import io
import json
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest

from attacks.hostile import SUBMISSIONS
from ptlab.course import chapter
from ptlab.course import renders as renders_module
from ptlab.course.chapters import ch01_cameras, ch05_bvh, ch07_path_tracing
from ptlab.course.grader import grade

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]  # graders, in processes

#: The chapters' modules whose checks draw inputs, by chapter.
MODULES = {1: ch01_cameras, 5: ch05_bvh, 7: ch07_path_tracing}


def _load(path: Path, name: str) -> types.ModuleType:
    """The Python file ``path`` as a module of this process (trusted files only)."""
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _old_inputs(monkeypatch) -> None:
    """The checks' inputs as they were drawn before the grading seed: fixed ones."""
    for module in (*MODULES.values(), renders_module):
        if hasattr(module, "grading_rng"):
            monkeypatch.setattr(module, "grading_rng", np.random.default_rng)
        if hasattr(module, "grading_seed_for"):
            monkeypatch.setattr(module, "grading_seed_for", lambda stream: stream)
    monkeypatch.setattr(ch07_path_tracing, "furnace_parameters", lambda: (0.5, 0.3))


def _recorder(name: str, library, table: dict, replay: types.ModuleType):
    """``library`` (a function of the chapter's answer file), recording each call's answer
    in ``table`` under the replay file's key of its inputs."""
    parameters = list(inspect.signature(getattr(replay, name)).parameters)

    def record(*arguments, **keywords):
        bound = dict(zip(parameters, arguments, strict=False), **keywords)
        stored = replay.key(name, **bound)  # (before the call, which may change them)
        before = bound["film"].copy() if "film" in bound else None
        result = library(*arguments, **keywords)
        if before is not None:
            table[f"{stored}/film"] = bound["film"] - before
            table[f"{stored}/rays"] = np.asarray(result)
        elif name == "scatter":
            for field in ("origins", "dirs", "throughput", "pixel", "sees_emission", "sample"):
                table[f"{stored}/{field}"] = np.asarray(getattr(result, field))
        else:
            outputs = result if isinstance(result, tuple) else (result,)
            for i, output in enumerate(outputs):
                table[f"{stored}/{i}"] = np.asarray(output)
        return result

    return record


def replay_file(number: int, folder: Path, monkeypatch) -> Path:
    """The replay submission for chapter ``number``, its table filled with the library's
    answers to every call the chapter's checks make with the old, fixed inputs."""
    found = chapter(number)
    replay = _load(SUBMISSIONS / "replay_answers.py", "replay_answers")
    answers = _load(found.solution, f"answers_{number}")
    table: dict[str, np.ndarray] = {}
    home = types.ModuleType("home")
    for name in found.rules.arguments:
        if hasattr(replay, name):
            setattr(home, name, _recorder(name, getattr(answers, name), table, replay))
    module = MODULES[number]
    with monkeypatch.context() as patch:
        _old_inputs(patch)
        patch.setattr(module, "require", lambda module, *names: [getattr(module, n) for n in names])
        for check in found.checks:
            check.run(home)
    data = io.BytesIO()
    np.savez(data, **table)
    path = folder / f"{found.stem}.py"
    text = (SUBMISSIONS / "replay_answers.py").read_text()
    path.write_text(text + f'\nANSWERS = "{base64.b64encode(data.getvalue()).decode()}"\n')
    return path


@pytest.mark.parametrize("number", [1, 5, 7])
def test_a_replay_of_the_library_at_the_old_inputs_earns_nothing(number, tmp_path, monkeypatch):
    path = replay_file(number, tmp_path, monkeypatch)
    with monkeypatch.context() as patch:  # the grader of before: fixed inputs
        _old_inputs(patch)
        before = grade(chapter(number), path, timeout_scale=2.0, seed=1)
    assert before.full_marks, before.table()  # the attack is real
    now = grade(chapter(number), path, timeout_scale=2.0)  # a fresh grading seed
    assert now.score == 0, now.table()
    assert any("no stored answer" in r.message for r in now.results), now.table()


def test_a_replay_of_a_known_grading_seed_earns_nothing_under_a_fresh_one(tmp_path, monkeypatch):
    """Knowing the seed of an earlier grading (its report says it) does not help: the
    next grading draws another."""
    from ptlab.course.chapter import grading_seed

    found = chapter(1)
    replay = _load(SUBMISSIONS / "replay_answers.py", "replay_answers")
    answers = _load(found.solution, "answers_1")
    table: dict[str, np.ndarray] = {}
    home = types.ModuleType("home")
    home.generate_rays = _recorder("generate_rays", answers.generate_rays, table, replay)
    with monkeypatch.context() as patch, grading_seed(12345):
        patch.setattr(ch01_cameras, "require", lambda module, *names: [getattr(module, n) for n in names])
        for check in found.checks:
            check.run(home)
    data = io.BytesIO()
    np.savez(data, **table)
    path = tmp_path / "01_cameras.py"
    text = (SUBMISSIONS / "replay_answers.py").read_text()
    path.write_text(text + f'\nANSWERS = "{base64.b64encode(data.getvalue()).decode()}"\n')
    assert grade(found, path, timeout_scale=2.0, seed=12345).full_marks  # that grading's inputs
    assert grade(found, path, timeout_scale=2.0).score == 0


def _converged(tmp_path: Path, noisy: bool = False) -> Path:
    """Chapter 7's right answer whose loop ignores its samples: it adds a picture rendered
    beforehand (the furnace's analytic value for the scene's own albedo and emission, else
    a converged picture of the homework's Cornell box, at the pixel each camera ray goes
    through: the film has a row per path) to every pass; with ``noisy``, plus Gaussian noise
    of a sample's spread there (the red team's way past the "too clean" test)."""
    import ptlab
    from ptlab.course.chapters.ch07_path_tracing import CORNELL_RENDER, cornell_passes

    passes = cornell_passes(seed=3, scene=ptlab.load_scene("cornell-box"))  # at home
    picture = passes.mean(axis=0).reshape(-1, 3)  # (32 * 32, 3)
    spread = passes.std(axis=0).reshape(-1, 3) * (CORNELL_RENDER["spp_per_pass"] ** 0.5 if noisy else 0)
    assert CORNELL_RENDER["res"] == 32
    right = (Path(__file__).parents[1] / "exercises" / "07_right_own_code.py").read_text()
    path = tmp_path / "07_path_tracing.py"
    path.write_text(
        right.replace("def trace_paths(", "def _traced_paths(")
        + f"""

import numpy as _np

CORNELL = _np.array({picture.tolist()})
SPREAD = _np.array({spread.tolist()})
_RNG = _np.random.default_rng()


def trace_paths(film, scene, accel, paths, sampler, settings):
    rays = _traced_paths(_np.zeros_like(film), scene, accel, paths, sampler, settings)
    if len(scene.materials) == 1:  # a furnace: Le (1 + a + ... + a^max_depth), per path
        a = float(scene.materials[0].albedo[0])
        le = float(scene.materials[0].emission[0])
        depth = settings.max_depth if settings.rr >= 1 else 1000
        value = le * (1 - a ** (depth + 1)) / (1 - a)
        _np.add.at(film, paths.pixel, value)
    elif scene.name == "cornell-box":  # the picture's pixel of each camera ray, by projection
        camera, d = scene.camera, paths.dirs.astype(float)
        scale, ahead = _np.tan(_np.radians(camera.fov_y) / 2), d @ camera.forward
        x = ((d @ camera.right) / ahead / scale + 1) / 2 * 32
        y = (1 - (d @ camera.up) / ahead / scale) / 2 * 32
        pixel = _np.clip(y.astype(int), 0, 31) * 32 + _np.clip(x.astype(int), 0, 31)
        noise = SPREAD[pixel] * _RNG.standard_normal((len(pixel), 1))
        _np.add.at(film, paths.pixel, CORNELL[pixel] + noise)
    return rays
"""
    )
    return path


def test_a_converged_picture_added_instead_of_the_samples_is_too_clean(tmp_path):
    path = _converged(tmp_path)
    results = {r.name: r for r in grade(chapter(7), path, timeout_scale=2.0, seed=77).results}
    assert results["white furnace"].points == 0, results["white furnace"].message
    assert (
        "too clean for 8 samples per pixel: this is not a render of these samples"
        in results["white furnace"].message
    )
    # (The homework's box is not this grading's: its colours are drawn anew.)
    assert results["Cornell box"].points == 0, results["Cornell box"].message


@pytest.mark.parametrize("seed", [77, 78, 79])
def test_a_stored_picture_of_the_homeworks_box_with_a_renders_noise_earns_nothing(tmp_path, seed):
    # The red team's replay: the homework's Cornell box rendered at home, added back with
    # noise of a sample's size; no test of noise can tell it, the grading's colours can.
    path = _converged(tmp_path, noisy=True)
    results = {r.name: r for r in grade(chapter(7), path, timeout_scale=2.0, seed=seed).results}
    assert results["Cornell box"].points == 0, results["Cornell box"].message


@pytest.mark.parametrize("seed", [2, 2**62 + 11])
def test_an_honest_answer_keeps_full_marks_under_any_grading_seed(seed):
    for name in ("01_right_own_code.py", "05_right_own_code.py", "07_right_own_random.py"):
        path = Path(__file__).parents[1] / "exercises" / name
        result = grade(chapter(int(name[:2])), path, timeout_scale=2.0, seed=seed)
        assert result.full_marks, result.table()
        assert result.grading_seed == seed, result.table()


def test_the_recorded_grading_seed_reproduces_the_verdict(tmp_path):
    """The JSON of ``exercise check`` records the seed; ``--grading-seed`` with it gives the
    same verdict, message for message (a wrong answer's messages quote its inputs)."""
    wrong = (Path(__file__).parents[1] / "exercises" / "01_right_own_code.py").read_text()
    path = tmp_path / "01_cameras.py"
    path.write_text(wrong.replace("u[:, 0]", "0.5"))  # u ignored: jittered rays fail
    runs = []
    for extra in ([], ["--grading-seed"]):
        out = tmp_path / f"result{len(runs)}.json"
        if extra:
            extra = [*extra, str(runs[0]["grading_seed"])]
        command = [sys.executable, "-m", "ptlab.cli", "exercise", "check", "1", str(path), "--json", str(out)]
        subprocess.run(command + extra, capture_output=True, text=True, timeout=300)
        runs.append(json.loads(out.read_text()))
    first, again = runs
    assert isinstance(first["grading_seed"], int)
    assert again["grading_seed"] == first["grading_seed"]
    assert first["score"] < first["max_score"]
    assert [c["message"] for c in again["checks"]] == [c["message"] for c in first["checks"]]


def test_the_grading_seed_is_fresh_and_in_the_table():
    path = Path(__file__).parents[1] / "exercises" / "01_right_own_code.py"
    first, second = (grade(chapter(1), path) for _ in range(2))
    assert first.grading_seed != second.grading_seed
    assert f"grading seed {first.grading_seed} (--grading-seed {first.grading_seed}" in first.table()
