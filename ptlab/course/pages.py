"""The chapters' pages and tutorials, wherever ptlab is: a checkout or an installed package.

A checkout keeps them in ``docs/`` beside ``ptlab/``; the wheel ships the same folder inside
the package as ``ptlab/docs`` (``pyproject.toml``), so a student who installed ptlab with
pip has every page (English ``docs/NN-name.md``, Chinese ``docs/zh/NN-name.md``), its
pictures and its tutorial script (``docs/tutorials/NN_name.py``).
``ptlab exercise docs NN [--zh]`` prints a page and says where they are.
"""

from __future__ import annotations

from pathlib import Path

from ptlab.course.chapter import HERE, Chapter
from ptlab.errors import PtlabError

#: The index of the chapters, in ``docs/`` (and ``docs/zh/``).
INDEX = "exercises.md"


def docs_folder() -> Path:
    """The ``docs`` folder: inside the installed package, or the checkout's."""
    package = HERE.parent
    for candidate in (package / "docs", package.parent / "docs"):
        if (candidate / INDEX).is_file():
            return candidate
    raise PtlabError(
        f"the chapters' pages are not installed (looked in {package / 'docs'} and "
        f"{package.parent / 'docs'}): reinstall ptlab"
    )


def page(chapter: Chapter | None = None, chinese: bool = False) -> Path:
    """The page of ``chapter`` (the chapters' index for None), in English or in Chinese."""
    folder = docs_folder() / "zh" if chinese else docs_folder()
    return folder / (chapter.doc if chapter is not None else INDEX)


def tutorial(chapter: Chapter) -> Path:
    """The chapter's tutorial script, which renders its pictures with the library's code."""
    return docs_folder() / "tutorials" / f"{chapter.stem}.py"
