"""Checking render options: every absurd value becomes one clear ``PtlabError``."""

from __future__ import annotations

import numpy as np

from ptlab.errors import PtlabError, is_integer
from ptlab.integrators import INTEGRATORS
from ptlab.integrators.path import HEURISTICS, STRATEGIES
from ptlab.materials.diffuse import SAMPLINGS
from ptlab.rendering.executors import default_workers
from ptlab.samplers import DEFAULT_SAMPLER, SAMPLERS

MAX_SPP = 1 << 20
MAX_PIXELS = 1 << 28
MAX_WORKERS = 1024
#: Russian roulette compares float32 uniforms, multiples of 2^-24, with the survival
#: probability: a smaller one would survive more often than it says (and then divide the
#: throughput by almost nothing, to infinity).
MIN_SURVIVAL = 2.0 ** -24


def parse_resolution(res: int | tuple[int, int] | str) -> tuple[int, int]:
    """``512``, ``(640, 480)`` or ``"640x480"`` -> (width, height), checked."""
    if isinstance(res, str):
        try:
            numbers = [int(p) for p in res.lower().split("x")]
        except ValueError:
            raise PtlabError(f"resolution {res!r}: expected N or WxH, e.g. 512 or 640x480") from None
        res = numbers[0] if len(numbers) == 1 else tuple(numbers)
    if isinstance(res, int | np.integer):
        res = (int(res), int(res))
    if len(res) != 2 or not all(isinstance(r, int | np.integer) for r in res):
        raise PtlabError(f"resolution {res!r}: expected N or (width, height)")
    width, height = int(res[0]), int(res[1])
    if width <= 0 or height <= 0:
        raise PtlabError(f"resolution {width}x{height}: width and height must be positive")
    if width * height > MAX_PIXELS:
        raise PtlabError(f"resolution {width}x{height}: more than {MAX_PIXELS} pixels")
    return width, height


def check_settings(spp: int, seed: int, sampling: str, rr, max_depth: int,
                   integrator: str, strategy: str = "nee", heuristic: str = "power",
                   rr_depth: int | None = None, sampler: str = DEFAULT_SAMPLER) -> float | str:
    """Raise ``PtlabError`` for an absurd option; return the roulette setting, parsed."""
    if not is_integer(spp) or not 1 <= spp <= MAX_SPP:
        raise PtlabError(f"spp {spp!r}: must be an integer from 1 to {MAX_SPP}")
    check_seed(seed)
    if sampler not in SAMPLERS:
        raise PtlabError(f"sampler {sampler!r}: choose one of {', '.join(SAMPLERS)}")
    if sampling not in SAMPLINGS:
        raise PtlabError(f"sampling {sampling!r}: choose one of {', '.join(SAMPLINGS)}")
    if not is_integer(max_depth) or max_depth < 0:
        raise PtlabError(f"max depth {max_depth!r}: must be a non-negative integer")
    if integrator not in INTEGRATORS:
        raise PtlabError(f"integrator {integrator!r}: choose one of {', '.join(INTEGRATORS)}")
    if strategy not in STRATEGIES:
        raise PtlabError(f"strategy {strategy!r}: choose one of {', '.join(STRATEGIES)}")
    if heuristic not in HEURISTICS:
        raise PtlabError(f"heuristic {heuristic!r}: choose one of {', '.join(HEURISTICS)}")
    if integrator != "path" and (strategy, heuristic) != ("nee", "power"):
        raise PtlabError(f"strategy {strategy!r} / heuristic {heuristic!r}: these choose how the "
                         f"path integrator finds light; {integrator!r} has no such choice")
    if rr_depth is not None and (not is_integer(rr_depth) or rr_depth < 0):
        raise PtlabError(f"russian roulette depth {rr_depth!r}: must be a non-negative integer")
    if rr == "throughput":
        return rr
    try:
        probability = float(rr)
    except (TypeError, ValueError):
        raise PtlabError(f"russian roulette {rr!r}: give 'throughput' or a probability") from None
    if not MIN_SURVIVAL <= probability <= 1:
        raise PtlabError(f"russian roulette {rr!r}: the survival probability must be in "
                         f"[2^-24, 1] (the uniforms it is drawn against are float32)")
    return probability


def check_seed(seed: int) -> int:
    """A random seed: any non-negative integer."""
    if not is_integer(seed) or seed < 0:
        raise PtlabError(f"seed {seed!r}: must be a non-negative integer")
    return int(seed)


def check_workers(workers: int | None) -> int:
    """``None`` -> every core; otherwise a positive integer, checked."""
    if workers is None:
        return default_workers()
    if not is_integer(workers) or not 1 <= workers <= MAX_WORKERS:
        raise PtlabError(f"workers {workers!r}: must be an integer from 1 to {MAX_WORKERS}")
    return int(workers)


def check_tile_size(tile_size: int) -> int:
    """A tile edge in pixels, from 8 to 4096."""
    if not is_integer(tile_size) or not 8 <= tile_size <= 4096:
        raise PtlabError(f"tile size {tile_size!r}: must be an integer from 8 to 4096")
    return int(tile_size)
