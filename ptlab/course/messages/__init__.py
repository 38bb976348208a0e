"""The graders' texts in every language they speak: one catalogue per language.

``en`` and ``zh`` each hold ``MESSAGES``, {message id: text with ``str.format`` fields}; a
test holds that both have the same ids and the same fields, so no message exists in one
language only. The checks build what they say with ``text(id, **fields)``, which uses the
active language: ``language(lang)`` sets it for a ``with`` block (``ptlab exercise check
--lang``), and outside one it comes from the locale (``language_from_locale``). The fields
are numbers and the student's own values: they are shown as they are, in every language.

The Chinese texts use the terms of the Chinese pages (docs/zh/), which follow the GAMES101
lectures (光线, 包围盒, 俄罗斯轮盘赌, 重要性采样, 辐射亮度, 置乱).
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from contextvars import ContextVar

from ptlab.course.messages import en, zh

#: The languages, by code; the first is the default.
LANGUAGES = ("en", "zh")
CATALOGUES: dict[str, dict[str, str]] = {"en": en.MESSAGES, "zh": zh.MESSAGES}

#: The language set by ``language``; None: the locale's.
_LANGUAGE: ContextVar[str | None] = ContextVar("grader_language", default=None)


def language_from_locale(environ: Mapping[str, str] = os.environ) -> str:
    """ "zh" where the locale's messages are Chinese, else "en": the first of LC_ALL,
    LC_MESSAGES and LANG that is set decides (POSIX's order), as ``zh_CN.UTF-8`` or ``zh_TW``."""
    for name in ("LC_ALL", "LC_MESSAGES", "LANG"):
        value = environ.get(name, "")
        if value:
            return "zh" if value.lower().startswith("zh") else "en"
    return LANGUAGES[0]


def active_language() -> str:
    """The language the graders speak now: ``language``'s, or the locale's."""
    return _LANGUAGE.get() or language_from_locale()


@contextmanager
def language(lang: str | None) -> Iterator[str]:
    """A ``with`` block in which ``text`` speaks ``lang`` ("en", "zh"; None: the one active)."""
    lang = lang or active_language()
    if lang not in CATALOGUES:
        raise ValueError(f"language {lang!r}: one of {', '.join(LANGUAGES)}")
    token = _LANGUAGE.set(lang)
    try:
        yield lang
    finally:
        _LANGUAGE.reset(token)


def text(message_id: str, /, **fields: object) -> str:
    """The message ``message_id`` in the active language, its fields filled in."""
    return CATALOGUES[active_language()][message_id].format(**fields)


def aside(hint: str) -> str:
    """``hint`` in brackets after what it explains, " (hint)" or "（hint）"; "" for no hint."""
    return text("aside", hint=hint) if hint else ""


def check_name(chapter: int, name: str) -> str:
    """A check's name (``ChapterCheck.name``, English: the key of ``requires`` and of the
    JSON) in the active language; the name itself for a check the catalogues do not know
    (a chapter made by a test: every chapter of ``ptlab.course`` has its names in both,
    tests/course/test_exercise_messages.py)."""
    return CATALOGUES[active_language()].get(f"ch{chapter:02d}.check.{name}", name)
