"""Chapter 10: multiple importance sampling.

The chapter's page: ``ptlab exercise docs 10`` (中文: ``--zh``).

Write Veach's two heuristics, ``balance_heuristic`` and ``power_heuristic``, and
``mis_weight``, the function the path tracer calls to weigh each sample of its two
strategies for direct light:

* a **light sample** (``direct_light``): the point was drawn on a light with solid-angle
  density ``pdf_light``; the material would have drawn the same direction with ``pdf_bsdf``.
  Its weight is ``mis_weight(pdf_light, pdf_bsdf, heuristic)``;
* a **BSDF sample that hits a light** (``add_emission``): the direction was drawn by the
  material with ``pdf_bsdf``; light sampling would have picked that point with ``pdf_light``.
  Its weight is ``mis_weight(pdf_bsdf, pdf_light, heuristic)``.

Check your work with

    ptlab exercise check 10 10_mis.py

Everything is whole arrays: ``pdf`` holds the densities of every sample at once. Write it
with NumPy operations, never a Python loop over samples.
"""

import numpy as np


def balance_heuristic(pdf, other):
    """Veach's balance heuristic: w = pdf / (pdf + other).

    Args:
        pdf: (N,) densities with which *this* strategy drew each sample (>= 0).
        other: (N,) densities with which the other strategy would have drawn it (>= 0).

    Returns:
        (N,) weights in [0, 1].

    Hints:
        * Veach 1997, section 9.2.2; pbrt-v4 section 2.2.3 (``BalanceHeuristic``).
        * Where both are 0, pdf / (pdf + other) is 0 / 0 = NaN: the sample cannot happen;
          return 0 there (``np.where``, or ``np.nan_to_num``).
    """
    raise NotImplementedError("balance_heuristic")


def power_heuristic(pdf, other):
    """Veach's power heuristic with exponent 2: w = pdf^2 / (pdf^2 + other^2).

    Args:
        pdf, other: (N,) densities as for ``balance_heuristic``.

    Returns:
        (N,) weights in [0, 1]; 0 where both are 0.

    Hints:
        * Veach 1997, section 9.2.3 (pbrt-v4's ``PowerHeuristic``): it trusts the better
          strategy more than the balance heuristic does, which lowers the variance where one
          strategy is much better (the sharp highlights and the small lights of veach-mis).
    """
    raise NotImplementedError("power_heuristic")


def mis_weight(pdf, other, heuristic="power"):
    """The MIS weight of a sample drawn with density ``pdf`` when the other strategy would
    have drawn it with density ``other``.

    Args:
        pdf, other: (N,) float32 densities (>= 0).
        heuristic: ``"power"`` or ``"balance"``.

    Returns:
        (N,) weights in [0, 1], never NaN. For any sample,
        mis_weight(p, q) + mis_weight(q, p) == 1 (or both 0 when p = q = 0): the two
        strategies together count each light path exactly once.

    Hints:
        * Where ``other`` is 0 the other strategy can never produce this sample (a mirror's
          BSDF pdf is 0 at a sampled light point): the weight must be 1.
        * The path tracer calls this as ``mis_weight(a, b, settings.heuristic)``: keep the
          argument order.
    """
    raise NotImplementedError("mis_weight")
