"""Fixtures of the attack tests: every test here leaves no process behind, and runs its
hostile submission from a fresh folder of its own. They try the students' sandbox: where
bubblewrap cannot make it, they are skipped (the graders then mark every result not for
credit, which ``tests/course/test_sandbox.py`` checks)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from attacks.hostile import SUBMISSIONS


def pytest_collection_modifyitems(config, items) -> None:
    from ptlab.course.sandbox.sandbox import missing

    why = missing()
    if why is not None:
        for item in items:
            if "attacks" in item.nodeid.split("/"):
                item.add_marker(pytest.mark.skip(reason=f"no sandbox here: {why}"))


@pytest.fixture(autouse=True)
def _nothing_left_behind(nothing_left_behind):
    return


@pytest.fixture
def attack(tmp_path):
    """Copy a hostile submission into a fresh folder (where it writes its markers) and
    return its path."""

    def copy(name: str, as_name: str | None = None) -> Path:
        target = tmp_path / (as_name or name)
        shutil.copyfile(SUBMISSIONS / name, target)
        return target

    return copy
