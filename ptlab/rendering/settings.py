"""Checking render options: every absurd value becomes one clear ``PtlabError``.

Each check returns the value it was given, made plain (a Python ``int``, a parsed resolution
or roulette setting). ``RenderOptions`` (``options``) says which check each option gets.
(No NumPy here: ``ptlab.cli`` reads the limits before it imports NumPy.)
"""

from __future__ import annotations

from ptlab.errors import PtlabError, is_integer
from ptlab.rendering.executors import default_workers

MAX_SPP = 1 << 20
MAX_PIXELS = 1 << 28
MAX_WORKERS = 1024
#: Russian roulette compares float32 uniforms, multiples of 2^-24, with the survival
#: probability: a smaller one would survive more often than it says (and then divide the
#: throughput by almost nothing, to infinity).
MIN_SURVIVAL = 2.0**-24


def parse_resolution(res: object) -> tuple[int, int]:
    """``512``, ``(640, 480)`` or ``"640x480"`` -> (width, height), checked."""
    given = res
    if isinstance(given, str):
        try:
            numbers = [int(p) for p in given.lower().split("x")]
        except ValueError:
            raise PtlabError(f"resolution {given!r}: expected N or WxH, e.g. 512 or 640x480") from None
        given = numbers[0] if len(numbers) == 1 else tuple(numbers)
    if is_integer(given):
        given = (given, given)
    if not (isinstance(given, tuple | list) and len(given) == 2 and all(map(is_integer, given))):
        raise PtlabError(f"resolution {given!r}: expected N or (width, height)")
    width, height = int(given[0]), int(given[1])
    if width <= 0 or height <= 0:
        raise PtlabError(f"resolution {width}x{height}: width and height must be positive")
    if width * height > MAX_PIXELS:
        raise PtlabError(f"resolution {width}x{height}: more than {MAX_PIXELS} pixels")
    return width, height


def check_integer(label: str, value: object, low: int, high: int | None = None) -> int:
    """``value``, an integer from ``low`` to ``high`` (None: no upper bound), as an ``int``."""
    if is_integer(value) and low <= value and (high is None or value <= high):
        return int(value)
    if high is not None:
        wanted = f"an integer from {low} to {high}"
    else:
        wanted = {0: "a non-negative integer", 1: "a positive integer"}.get(
            low, f"an integer of at least {low}"
        )
    raise PtlabError(f"{label} {value!r}: must be {wanted}")


def check_positive_number(label: str, value: object) -> float:
    """``value``, a finite number above 0, as a ``float``."""
    if not isinstance(value, bool):
        try:
            number = float(value)  # type: ignore[arg-type]  # (anything else: the error below)
        except (TypeError, ValueError):
            number = float("nan")
        if 0 < number < float("inf"):
            return number
    raise PtlabError(f"{label} {value!r}: must be a number above 0")


def check_choice(label: str, value: object, choices: tuple[str, ...]) -> str:
    """``value``, one of the names ``choices``."""
    if not (isinstance(value, str) and value in choices):
        raise PtlabError(f"{label} {value!r}: choose one of {', '.join(choices)}")
    return value


def check_roulette(rr: object) -> float | str:
    """Russian roulette: ``"throughput"``, or a survival probability (a number, or its text
    from the command line) in [2^-24, 1], as a float."""
    if rr == "throughput":
        return rr
    try:
        probability = float(rr)  # type: ignore[arg-type]  # (anything else: the error below)
    except (TypeError, ValueError):
        raise PtlabError(f"russian roulette {rr!r}: give 'throughput' or a probability") from None
    if not MIN_SURVIVAL <= probability <= 1:
        raise PtlabError(
            f"russian roulette {rr!r}: the survival probability must be in "
            f"[2^-24, 1] (the uniforms it is drawn against are float32)"
        )
    return probability


def check_seed(seed: object) -> int:
    """A random seed: any non-negative integer."""
    return check_integer("seed", seed, 0)


def check_workers(workers: object) -> int:
    """``None`` -> every core; otherwise an integer from 1 to ``MAX_WORKERS``, checked."""
    if workers is None:
        return default_workers()
    return check_integer("workers", workers, 1, MAX_WORKERS)


def check_flag(label: str, value: object) -> bool:
    """``value`` if it is True or False, else ``PtlabError`` naming ``label``."""
    if value is True or value is False or type(value).__name__ == "bool_":  # (NumPy's too)
        return bool(value)
    raise PtlabError(f"{label}: {value!r} is not True or False")
