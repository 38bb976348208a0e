"""Showing what a student controls (file and folder names, what their code prints or
raises) on the grader's terminal, in its tables and in CSV cells, so that it cannot pass
for the grader's own lines.

A newline in a file name would start a forged row of the score table ("  PASSED ... 10/10"),
and an ANSI escape (ESC, a carriage return) in what a student's code prints can move the
cursor and rewrite the verdict lines already on a terminal. ``shown`` writes every such
character as its Python escape (``\\n``, ``\\x1b``, ``\\u202e``), so the text stays on one
line and means nothing to a terminal. ``relay`` passes a student's printed lines on,
each shown and behind a prefix, and never raises (a reader that went away must not stop
the grading, nor turn its verdict into a success).
"""

from __future__ import annotations

import os
import sys
import unicodedata
from collections.abc import Callable
from typing import TextIO

#: Unicode categories a terminal may act on rather than print: controls (ESC, CR, BEL),
#: format characters (right-to-left overrides), surrogates, private and unassigned code
#: points, and the line and paragraph separators.
HIDDEN = frozenset({"Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp"})


def shown(text: object) -> str:
    """``text`` with every character a terminal could act on written as its escape (one
    line, nothing hidden). Printable text, the escapes included, is unchanged, so showing
    twice is showing once."""
    text = str(text)
    if text.isascii() and text.isprintable():  # (the usual case: nothing to look at)
        return text
    return "".join(_escape(c) if unicodedata.category(c) in HIDDEN else c for c in text)


def shown_line(text: object, limit: int = 1000) -> str:
    """``text`` as one shown line of at most ``limit`` characters: runs of white space,
    newlines included, become one space, and the rest is ``shown``."""
    line = shown(" ".join(str(text).split()))
    return line if len(line) <= limit else line[: limit - 3] + "..."


def _escape(character: str) -> str:
    code = ord(character)
    named = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}
    if character in named:
        return named[character]
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}" if code < 0x10000 else f"\\U{code:08x}"


def relay(prefix: str, stream: TextIO | None = None) -> Callable[[str], None]:
    """A function that prints a line of a student's output, shown, after ``prefix``, on
    ``stream`` (default stderr); once the stream is gone (a closed pipe) it drops the rest."""
    gone = False

    def show(line: str) -> None:
        nonlocal gone
        if gone:
            return
        try:
            print(f"{prefix}{shown(line)}", file=stream or sys.stderr, flush=True)
        except (OSError, ValueError):  # (BrokenPipeError; a closed file)
            gone = True

    return show


def print_verdict(text: str) -> bool:
    """Print ``text`` (the grader's table) on stdout and flush it; False if the reader has
    gone (a closed pipe: ``ptlab exercise check ... | true``), in which case stdout is
    pointed at /dev/null so that Python's own flush at exit cannot fail either. The caller
    still returns the verdict's exit code: a lost table never makes a failure a success."""
    try:
        print(text)
        sys.stdout.flush()
        return True
    except BrokenPipeError:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, sys.stdout.fileno())
        os.close(null)
        return False
