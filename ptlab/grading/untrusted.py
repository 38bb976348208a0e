"""Loading a student's Python file, for the graders (``ptlab grade``, ``ptlab exercise check``).

Both graders import the student's file through ``import_file``, so that a missing file, a
syntax error or an exception at import is one clear ``GradeLoadError`` for either.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

from ptlab.errors import PtlabError


class GradeLoadError(PtlabError):
    """The material to grade cannot be loaded: a missing file, a syntax error, no such name."""


def import_file(path: Path):
    """Import a Python file as a module of its own; its folder is importable while it loads."""
    module_name = f"ptlab_graded_{abs(hash(str(path.resolve())))}"
    spec = importlib.util.spec_from_file_location(module_name, path)
    if spec is None or spec.loader is None:
        raise GradeLoadError(f"{path}: not a Python file")
    module = importlib.util.module_from_spec(spec)
    folder = str(path.resolve().parent)
    sys.path.insert(0, folder)
    sys.modules[module_name] = module   # (dataclasses and pickling look modules up there)
    try:
        spec.loader.exec_module(module)
    except SyntaxError as error:
        del sys.modules[module_name]
        raise GradeLoadError(f"{path}:{error.lineno}: syntax error: {error.msg}") from None
    except (Exception, SystemExit) as error:  # anything the student's module raises on import
        del sys.modules[module_name]
        raise GradeLoadError(f"{path}: importing it raised {type(error).__name__}: {error}") from None
    finally:
        sys.path.remove(folder)
    return module
