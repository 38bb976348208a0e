"""What ``ptlab exercise inspect 9`` shows at a vertex on a metal, beyond the student's
``eval`` and ``pdf`` beside the library's there (``ptlab.course.inspection``).

* ``terms``: where ``eval`` differs, the terms of the Cook-Torrance BRDF
  f_r = D(h) G2(wo, wi) F(wo . h) / (4 cos_theta_o cos_theta_i) (Walter et al. 2007, eq. 20)
  from the student's own ``D``, ``G1``, ``G2`` and ``fresnel_schlick``, beside the library's,
  and the first of them that differs. If none does, ``eval`` puts them together otherwise:
  which of a few typical ways (``assemblies``) it matches, if one.
* ``drawn``: what the student's ``sample`` draws at the vertex's wo against what the
  student's ``pdf`` says it draws there. Comparing ``eval`` and ``pdf`` at the library's
  directions cannot see a sampler that draws other directions than its pdf describes.
  ``DRAWS`` directions are binned by a coordinate s in [0, 1) in which the library's
  sampling is uniform (``HalfVectors``: Walter et al.'s inverse CDF of theta_h, eq. 35;
  ``Cosines``: 1 - cos^2 theta_i), and each bin's count is set against ``DRAWS`` times the
  pdf's integral over the bin (a midpoint quadrature in (s, phi)); the directions that fail
  (below the surface, pdf 0) are a category of their own, expecting 1 - the integral of
  pdf. Pearson's chi-square with pooling (``ptlab.grading.checks``) decides; the same draws
  against the library's samplings' densities say which side, sample or pdf, differs.

The student's functions are the ``RemoteModule``'s: they run in the student's process, as
``check`` runs them; everything else is computed here.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ptlab.course.chapter import CheckFailed
from ptlab.course.inspect_values import same, shown_value
from ptlab.course.messages import text
from ptlab.course.sandbox.proxies import StudentError
from ptlab.materials import microfacet as library
from ptlab.sampling import to_world
from ptlab.scattering import F_schlick, reflect
from ptlab.vectors import dot, normalize

#: A term from the student's function is the library's to this relative difference: both
#: are computed in float64 from the same cosines (``inspect_values.same``'s default is for
#: the renderer's float32).
TERM_RTOL = 1e-5

#: Directions the student's ``sample`` draws at a vertex (the chi-square's sample size).
DRAWS = 20_000
#: Bins of the coordinate s (equally likely for the library's sampling), and the quadrature's
#: cells per bin in s and in phi.
BINS, ROWS_PER_BIN, AZIMUTHS = 20, 8, 256
#: A quadrature cell that the horizon crosses is cut into SPLIT x SPLIT parts; the last bin
#: has LAST_ROWS rows, down to CLOSEST of the horizon (``_quadrature``).
SPLIT, LAST_ROWS, CLOSEST = 2, 20, 1e-7
#: The draws and the pdf disagree below this p-value: a right answer's p is uniform, so it
#: is told it differs once in a million vertices; the samplers of the typical wrong answers
#: reach p < 1e-100 (tests/course/test_inspect_exercises.py).
ALPHA_DRAWN = 1e-6
#: The student's pdf is one of the library's when its integral over every bin (and over
#: the failures) is within this of that sampling's: quadratures of one density agree to
#: rounding, while a different density moves some bin by a percent or more.
SAME_SHARE = 2e-3


@dataclass
class Term:
    """One factor of f_r at a vertex: the student's function's value (None where it is
    missing or raised) and the library's."""

    name: str
    yours: Any
    expected: Any

    def agrees(self) -> bool:
        return same(self.yours, self.expected, TERM_RTOL, 1e-12)


@dataclass
class Terms:
    """The factors of f_r at one vertex, the student's beside the library's.

    Attributes:
        alpha: the metal's roughness.
        cosines: the arguments (n . wo, n . wi, n . h, wo . h) by name.
        terms: D(h), G1(wo), G1(wi), G2(wo, wi), F(wo . h) in that order.
        differs: the first term that differs (None: they all agree).
        assembly: if they all agree, the formula of the library's terms that the student's
            eval equals (``assemblies``), or None.
    """

    alpha: float
    cosines: dict[str, float]
    terms: list[Term]
    differs: str | None
    assembly: str | None


def _call(function, *arguments, sizes: tuple[int, ...] = (1,)) -> Any:
    """The student's function's value at one row (a number, or a colour where ``sizes``
    allows 3), so that the student's other functions can still be shown when this one fails:
    None if it raised or returned no numbers, "shape (...)" for a value of another size (its
    values are not shown: a function may return millions)."""
    try:
        value = np.asarray(function(*arguments), dtype=np.float64)
    except (StudentError, ValueError, TypeError):  # (raised, or strings, ragged lists, dicts)
        return None
    if value.size not in sizes:
        return f"shape {value.shape}"
    return value.reshape(-1).tolist()[0] if value.size == 1 else value.reshape(-1).tolist()


def _cosines(wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> dict[str, np.ndarray]:
    """(rows,) cosines of f_r's arguments, float64, h the unit half vector."""
    wo, wi, n = (np.asarray(a, np.float64) for a in (wo, wi, n))
    h = normalize(wo + wi)
    return {"n . wo": dot(n, wo), "n . wi": dot(n, wi), "n . h": dot(n, h), "wo . h": dot(wo, h)}


def terms(module, f0, alpha: float, at: tuple, differing: tuple) -> Terms:
    """D, G1, G2 and F at a vertex from the student's functions of ``module`` and from the
    library's, and if they all agree, the way the student's eval puts them together
    (``assembly_of``).

    Args:
        module: the student's module (a stand-in).
        f0, alpha: the metal's.
        at: (wo, wi, n) of the vertex, (3,) each, both directions above the surface.
        differing: (wo, wi, n, f) (R, 3) each: the rows where the student's eval, f, is not
            the library's.
    """
    c = {k: v[0] for k, v in _cosines(*(np.asarray(a)[None] for a in at)).items()}
    f0 = np.asarray(f0, dtype=np.float64)

    def student(name: str, *cosines: str) -> Any:
        """The student's function ``name`` at the vertex's ``cosines`` (and alpha, or f0)."""
        function = getattr(module, name, None)
        last, sizes = (f0, (1, 3)) if name == "fresnel_schlick" else (alpha, (1,))
        if not callable(function):
            return None
        return _call(function, *(np.array([c[k]]) for k in cosines), last, sizes=sizes)

    found = [
        Term("D(h)", student("D", "n . h"), float(library.D(c["n . h"], alpha))),
        Term("G1(wo)", student("G1", "n . wo"), float(library.G1(c["n . wo"], alpha))),
        Term("G1(wi)", student("G1", "n . wi"), float(library.G1(c["n . wi"], alpha))),
        Term(
            "G2(wo, wi)",
            student("G2", "n . wo", "n . wi"),
            float(library.G2(c["n . wo"], c["n . wi"], alpha)),
        ),
        Term(
            "F(wo . h)",
            student("fresnel_schlick", "wo . h"),
            F_schlick(np.array([c["wo . h"]]), f0)[0].tolist(),
        ),
    ]
    differs = next((t.name for t in found if not t.agrees()), None)
    assembly = assembly_of(f0, alpha, *differing) if differs is None else None
    return Terms(alpha, {k: float(v) for k, v in c.items()}, found, differs, assembly)


def assemblies(f0, alpha: float, wo, wi, n) -> dict[str, np.ndarray]:
    """(R, 3) f_r at the rows (wo, wi, n) (R, 3) put together from the library's terms in
    typical ways, by their formula (the library's own first)."""
    c = _cosines(wo, wi, n)
    cos_o, cos_i = np.maximum(c["n . wo"], 1e-7), np.maximum(c["n . wi"], 1e-7)
    d, g2 = library.D(c["n . h"], alpha), library.G2(cos_o, cos_i, alpha)
    separable = library.G1(cos_o, alpha) * library.G1(cos_i, alpha)
    f0 = np.asarray(f0, dtype=np.float64)
    F = {k: F_schlick(c[k], f0) for k in ("wo . h", "n . wi", "n . wo", "n . h")}  # noqa: N806 (the papers' name)
    rest = d * g2 / (4 * cos_o * cos_i)
    raw = np.asarray(wo, np.float64) + np.asarray(wi, np.float64)  # (h not normalised)
    unnormalised = library.D(dot(np.asarray(n, np.float64), raw), alpha) * g2 / (4 * cos_o * cos_i)
    return {
        "D G2 F(wo . h) / (4 cos_o cos_i)": F["wo . h"] * rest[:, None],
        "D G1(wo) G1(wi) F(wo . h) / (4 cos_o cos_i)": F["wo . h"]
        * (d * separable / (4 * cos_o * cos_i))[:, None],
        "D G1(wo) F(wo . h) / (4 cos_o cos_i)": F["wo . h"] * (rest * library.G1(cos_o, alpha) / g2)[:, None],
        "D F(wo . h) / (4 cos_o cos_i)": F["wo . h"] * (rest / g2)[:, None],
        "D G2 F(n . wi) / (4 cos_o cos_i)": F["n . wi"] * rest[:, None],
        "D G2 F(n . wo) / (4 cos_o cos_i)": F["n . wo"] * rest[:, None],
        "D G2 F(n . h) / (4 cos_o cos_i)": F["n . h"] * rest[:, None],
        "D G2 F0 / (4 cos_o cos_i)": f0 * rest[:, None],
        "D G2 / (4 cos_o cos_i)": np.repeat(rest[:, None], 3, axis=1),
        "D G2 F(wo . h) / (cos_o cos_i)": F["wo . h"] * (4 * rest)[:, None],
        "D G2 F(wo . h) / (4 cos_o)": F["wo . h"] * (rest * cos_i)[:, None],
        "D(n . (wo + wi)) G2 F(wo . (wo + wi)) / (4 cos_o cos_i)": F_schlick(
            dot(np.asarray(wo, np.float64), raw), f0
        )
        * unnormalised[:, None],
    }


def assembly_of(f0, alpha: float, wo, wi, n, f) -> str | None:
    """The formula of ``assemblies`` (not the library's) that ``f`` (R, 3) equals on every
    row (wo, wi, n) (R, 3), or None."""
    for formula, value in list(assemblies(f0, alpha, wo, wi, n).items())[1:]:
        if same(np.asarray(f, np.float64), value):
            return formula
    return None


def terms_lines(found: Terms) -> list[str]:
    """``Terms`` as ``inspect`` prints them: a header, a line per term, a verdict. Six
    digits: terms that differ beyond ``TERM_RTOL`` show it."""

    def shown(value: Any) -> str:
        return text("inspect.term_missing") if value is None else shown_value(value, 6)

    arguments = ", ".join(f"{name} {value:.4g}" for name, value in found.cosines.items())
    lines = [text("inspect.terms", alpha=f"{found.alpha:.4g}", cosines=arguments)]
    width = max(len(t.name) for t in found.terms)
    for t in found.terms:
        mark = "" if t.agrees() else "  <-"
        lines.append(f"    {t.name:<{width}}  {shown(t.yours)} | {shown(t.expected)}{mark}")
    if found.differs is not None:
        first = next(t for t in found.terms if t.name == found.differs)
        verdict = text(
            "inspect.term_differs", term=first.name, yours=shown(first.yours), expected=shown(first.expected)
        )
        agree = [t.name for t in found.terms if t.agrees()]
        if agree:
            verdict += text("inspect.terms_agree", terms=text("inspect.list").join(agree))
        lines.append("  " + verdict)
    elif found.assembly is not None:
        lines.append("  " + text("inspect.assembly", formula=found.assembly))
    else:
        lines.append("  " + text("inspect.assembly_unknown"))
    return lines


# -- what sample draws ------------------------------------------------------------------------


class HalfVectors:
    """Directions wi = reflect(wo, h) by the coordinates (s, v) of their half vector h: s
    Walter et al.'s CDF of theta_h, tan^2 theta_h = alpha^2 s / (1 - s) (2007, eq. 35), v =
    phi / (2 pi). Walter's sampling (h with density D(h) cos theta_h) is uniform in (s, v).
    """

    angle = "theta_h"

    def __init__(self, wo: np.ndarray, n: np.ndarray, alpha: float):
        self.wo, self.n, self.alpha = wo, n, alpha

    def coordinate(self, wi: np.ndarray) -> np.ndarray:
        """(M,) s of directions (M, 3) above the surface."""
        cos2 = np.clip(dot(normalize(self.wo + wi), self.n), 0.0, 1.0) ** 2
        return np.clip((1 - cos2) / ((1 - cos2) + self.alpha**2 * cos2), 0.0, 1.0)

    def cosine(self, s):
        """cos theta_h at the coordinates s (a float or an array)."""
        return np.sqrt((1 - s) / (1 - s + s * self.alpha**2))

    def directions(self, s: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(P, 3) directions at (s, v) and d omega_i / (ds dv) there: the Jacobian
        1 / (D(h) cos theta_h) of Walter's map to h times 4 |wo . h| (eq. 14)."""
        cos_h = self.cosine(s)
        sin_h = np.sqrt(np.maximum(0.0, 1 - cos_h * cos_h))
        phi = 2 * math.pi * v
        local = np.stack([sin_h * np.cos(phi), sin_h * np.sin(phi), cos_h], axis=1)
        h = to_world(local, np.broadcast_to(self.n, local.shape).copy())
        wo = np.broadcast_to(self.wo, h.shape)
        with np.errstate(divide="ignore"):
            jacobian = 4 * np.abs(dot(wo, h)) / (library.D(cos_h, self.alpha) * cos_h)
        return reflect(wo, h), jacobian


class Cosines:
    """Directions wi by s = 1 - cos^2 theta_i and v = phi / (2 pi), in which the cosine-weighted
    hemisphere is uniform."""

    angle = "theta_i"

    def __init__(self, n: np.ndarray):
        self.n = n

    def coordinate(self, wi: np.ndarray) -> np.ndarray:
        """(M,) s of directions (M, 3)."""
        return np.clip(1 - dot(normalize(wi), self.n) ** 2, 0.0, 1.0)

    def cosine(self, s):
        """cos theta_i at the coordinates s."""
        return np.sqrt(1 - s)

    def directions(self, s: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(P, 3) directions and d omega / (ds dv) = pi / cos theta_i."""
        cos_i = np.sqrt(1 - s)
        phi = 2 * math.pi * v
        local = np.stack([np.sqrt(s) * np.cos(phi), np.sqrt(s) * np.sin(phi), cos_i], axis=1)
        return to_world(local, np.broadcast_to(self.n, local.shape).copy()), math.pi / cos_i


def reference_pdfs(alpha: float, sampling: str, wo, wi, n) -> dict[str, np.ndarray]:
    """(R,) the densities of the library's samplings that the student's ``sampling`` may
    rightly have, at the rows (wo, wi, n) (R, 3) each: the cosine hemisphere for
    "hemisphere"; for "ggx" Walter et al.'s normals, D(h) cos theta_h / (4 |wo . h|) (2007,
    eqs. 14 and 38), and the library's visible normals, G1(wo) D(h) / (4 cos_theta_o)
    (Heitz 2018, eq. 17)."""
    wo, wi, n = np.broadcast_arrays(*(np.asarray(a, np.float64) for a in (wo, wi, n)))
    cos_o, cos_i = dot(wo, n), dot(wi, n)
    above = (cos_o > 0) & (cos_i > 0)
    if sampling == "hemisphere":
        return {"cosine": np.where(above, cos_i / math.pi, 0.0)}
    h = normalize(wo + wi)
    cos_h = dot(h, n)
    with np.errstate(all="ignore"):
        walter = library.D(cos_h, alpha) * cos_h / (4 * np.abs(dot(wo, h)))
    visible = library.Microfacet((1.0, 1.0, 1.0), alpha=alpha, sampling="vndf").pdf(wo, wi, n)
    return {"walter": np.where(above, np.nan_to_num(walter), 0.0), "visible": visible}


def references_line(values: dict[str, float]) -> str:
    """The library's densities at a vertex, named, for the line under a pdf that differs."""
    named = text("inspect.list").join(
        f"{text('inspect.sampling.' + k)} {shown_value(v)}" for k, v in values.items()
    )
    return "  " + text("inspect.references", references=named)


@dataclass
class Drawn:
    """What the student's ``sample`` drew at one vertex against its ``pdf``.

    Attributes:
        draws: directions drawn (``DRAWS``).
        cos_theta_o: n . wo at the vertex.
        angle: the angle the bins are ranges of ("theta_h", "theta_i").
        low, high: its range in degrees where draws and pdf part most (None: the failed
            draws).
        drawn: the share of the draws there.
        pdf: the share the student's pdf integrates to there.
        references: the share each of the library's samplings integrates to there.
        bins: the categories tested (bins and failures, before pooling).
        integral: the integral of the student's pdf over the directions above the surface.
        p: the chi-square p-value of the draws against the pdf.
        agrees: p >= ``ALPHA_DRAWN``.
        like: the library's sampling the draws follow, if one (then the pdf differs).
        pdf_of: the library's sampling whose density the student's pdf is, if one.
    """

    draws: int
    cos_theta_o: float
    angle: str
    low: float | None
    high: float | None
    drawn: float
    pdf: float
    references: dict[str, float]
    bins: int
    integral: float
    p: float
    agrees: bool
    like: str | None
    pdf_of: str | None


def _t_edges() -> np.ndarray:
    """The quadrature's rows in t = 1 - sqrt(1 - s): ``ROWS_PER_BIN`` even rows per bin; the
    last bin's then close in on t = 1 geometrically, ``LAST_ROWS`` more down to ``CLOSEST``
    of it (at a grazing wo the horizon of wi runs within alpha cos_theta_o / 2 of it)."""
    bins = 1 - np.sqrt(1 - np.linspace(0, 1, BINS + 1))
    even = [np.linspace(a, b, ROWS_PER_BIN + 1)[:-1] for a, b in itertools.pairwise(bins)]
    closer = 1 - (1 - bins[-2]) * np.geomspace(1 / ROWS_PER_BIN, CLOSEST, LAST_ROWS)[1:]
    return np.concatenate([*even, closer, [1.0]])


def _parts(edges: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The midpoints of the k equal parts of each cell between ``edges``, (cells * k,) in
    order, and their widths."""
    width = np.repeat(np.diff(edges) / k, k)
    return np.repeat(edges[:-1], k) + (np.tile(np.arange(k), len(edges) - 1) + 0.5) * width, width


def _points(lobe, t: np.ndarray, v: np.ndarray, area: np.ndarray) -> tuple[np.ndarray, ...]:
    """(P, 3) directions at (t, v), their solid angles (``area`` in (t, v) times
    d omega / dt = d omega / ds 2 (1 - t); 0 below the surface) and their s."""
    s = 1 - (1 - t) ** 2
    with np.errstate(all="ignore"):
        wi, jacobian = lobe.directions(s, v)
    return wi, np.where(dot(wi, lobe.n) > 0, jacobian * 2 * (1 - t) * area, 0.0), s


def _quadrature(lobe) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points of a midpoint quadrature over the directions above the surface: (P, 3)
    directions, (P,) their solid angles and (P,) their bins of s.

    The cells are even in v and in t = 1 - sqrt(1 - s) (``_t_edges``): both lobes'
    d omega / ds grows as 1 / sqrt(1 - s) towards s = 1 (h or wi at the horizon), which a
    grid even in s integrates badly near grazing wo; d omega / dt stays finite. A cell
    wholly above the surface is one point, its middle; one that the horizon crosses, where
    the integrand jumps to 0, is ``SPLIT`` x ``SPLIT`` parts, those above kept.
    """
    t_edges, v_edges = _t_edges(), np.linspace(0, 1, AZIMUTHS + 1)
    (t, dt), (v, dv) = _parts(t_edges, SPLIT), _parts(v_edges, SPLIT)
    wi, weight, s = _points(lobe, np.repeat(t, len(v)), np.tile(v, len(t)), np.outer(dt, dv).ravel())
    cells = (len(t_edges) - 1, AZIMUTHS)
    above = (weight > 0).reshape(cells[0], SPLIT, cells[1], SPLIT).sum(axis=(1, 3))
    whole = above == SPLIT * SPLIT
    crossed = np.repeat(np.repeat(~whole & (above > 0), SPLIT, axis=0), SPLIT, axis=1).ravel()
    kept = crossed & (weight > 0)
    (t, dt), (v, dv) = _parts(t_edges, 1), _parts(v_edges, 1)
    i, j = np.nonzero(whole)
    middles = _points(lobe, t[i], v[j], dt[i] * dv[j])
    wi, weight, s = (np.concatenate([m, a[kept]]) for m, a in zip(middles, (wi, weight, s), strict=True))
    return wi, weight, np.minimum((s * BINS).astype(np.intp), BINS - 1)


def _shares(density: np.ndarray, weight: np.ndarray, bins: np.ndarray) -> np.ndarray:
    """(BINS + 1,) the integral of ``density`` (at ``_quadrature``'s points) over each bin
    above the surface, and 1 - their sum: the share left for failures."""
    with np.errstate(all="ignore"):
        values = np.nan_to_num(np.asarray(density, np.float64) * weight, nan=0.0, posinf=0.0, neginf=0.0)
    per_bin = np.bincount(bins, weights=values, minlength=BINS)
    return np.append(per_bin, 1 - per_bin.sum())


def _p_value(observed: np.ndarray, shares: np.ndarray) -> float:
    from ptlab.grading.checks import chi2_sf, pooled_chi_square

    statistic, dof = pooled_chi_square(observed, observed.sum() * np.maximum(shares, 0.0))
    return chi2_sf(statistic, dof)


def _returned(value, name: str, shape: tuple) -> np.ndarray:
    """What the student's ``name`` returned, as float64, if of ``shape``; else the comparison
    stops with the check's message (NaN stays: a direction that is not finite is a failed
    sample)."""
    result = np.asarray(value, dtype=np.float64)
    if result.shape != shape:
        raise CheckFailed(text("array.shape", name=name, expected=shape, shape=result.shape))
    return result


def _drawn_counts(material, wo, n, lobe, rng: np.random.Generator) -> np.ndarray:
    """(BINS + 1,) how many of ``DRAWS`` directions from ``material.sample`` at (wo, n) ((3,)
    float32 each, asked as the renderer asks: float32 rows) fall in each bin of s above the
    surface with a positive pdf, and how many fail."""
    wo_rows, n_rows = (np.tile(np.asarray(a, np.float32), (DRAWS, 1)) for a in (wo, n))
    u = np.minimum(rng.random((DRAWS, 2), dtype=np.float32), np.float32(1 - 2**-24))
    wi = _returned(material.sample(wo_rows, n_rows, u), "sample", (DRAWS, 3))
    pdf = _returned(material.pdf(wo_rows, wi.astype(np.float32), n_rows), "pdf", (DRAWS,))
    with np.errstate(invalid="ignore"):
        landed = np.isfinite(wi).all(axis=1) & np.isfinite(pdf) & (pdf > 0) & (dot(wi, lobe.n) > 0)
    where = np.minimum((lobe.coordinate(wi[landed]) * BINS).astype(np.intp), BINS - 1)
    return np.append(np.bincount(where, minlength=BINS), DRAWS - landed.sum()).astype(np.float64)


def drawn(material, wo, n, alpha: float, sampling: str, rng: np.random.Generator) -> Drawn:
    """``DRAWS`` directions from the student's ``material.sample`` at (wo, n) ((3,) each)
    against its ``pdf`` and the library's samplings' densities."""
    wo64, n64 = np.asarray(wo, np.float64), np.asarray(n, np.float64)
    lobe = HalfVectors(wo64, n64, alpha) if sampling == "ggx" else Cosines(n64)
    observed = _drawn_counts(material, wo, n, lobe, rng)
    wi, weight, bins = _quadrature(lobe)
    rows = (len(wi), 3)
    # (In float64: near wi = -wo, a half vector from float32 directions is rounding noise.)
    pdf = material.pdf(np.broadcast_to(wo64, rows).copy(), wi, np.broadcast_to(n64, rows).copy())
    yours = _shares(_returned(pdf, "pdf", rows[:1]), weight, bins)
    references = {
        k: _shares(v, weight, bins) for k, v in reference_pdfs(alpha, sampling, wo64, wi, n64).items()
    }
    p = _p_value(observed, yours)
    parting = np.abs(observed - DRAWS * yours) / np.sqrt(np.maximum(DRAWS * yours, 1.0))
    if yours[BINS] < 0:  # (a pdf integrating to more than 1 expects fewer than no failures:
        parting[BINS] = -1.0  # not the place to show what differs)
    worst = int(np.argmax(parting))
    low = high = None
    if worst < BINS:  # (s grows as the cosine falls: the bin's high cosine is at its low s)
        low, high = (math.degrees(math.acos(lobe.cosine(b / BINS))) for b in (worst, worst + 1))
    fits = {k: _p_value(observed, shares) for k, shares in references.items()}
    apart = {k: float(np.abs(shares - yours).max()) for k, shares in references.items()}
    return Drawn(
        draws=DRAWS,
        cos_theta_o=float(dot(wo64, n64)),
        angle=lobe.angle,
        low=low,
        high=high,
        drawn=float(observed[worst] / DRAWS),
        pdf=float(yours[worst]),
        references={k: float(v[worst]) for k, v in references.items()},
        bins=BINS + 1,
        integral=float(1 - yours[BINS]),
        p=p,
        agrees=p >= ALPHA_DRAWN,
        like=max(fits, key=fits.__getitem__) if max(fits.values()) >= ALPHA_DRAWN else None,
        pdf_of=min(apart, key=apart.__getitem__) if min(apart.values()) <= SAME_SHARE else None,
    )


def drawn_line(found: Drawn) -> str:
    """What ``inspect`` says of ``Drawn``: agreeing (under a pdf that differs) or not."""
    if found.agrees:
        cos_o = f"{found.cos_theta_o:.4g}"
        return text(
            "inspect.drawn_agrees", draws=found.draws, cos_o=cos_o, bins=found.bins, p=f"{found.p:.2g}"
        )
    percent = "{:.1%}".format
    if found.low is None:
        where = text("inspect.drawn_failed")
    else:
        where = text(
            "inspect.drawn_range", angle=found.angle, low=f"{found.low:.3g}", high=f"{found.high:.3g}"
        )
    references = text("inspect.list").join(
        f"{text('inspect.sampling.' + k)} {percent(v)}" for k, v in found.references.items()
    )
    if found.like is not None:
        verdict = text("inspect.drawn_pdf_differs", sampling=text("inspect.sampling." + found.like))
    elif found.pdf_of is not None:
        verdict = text("inspect.drawn_sample_differs", sampling=text("inspect.sampling." + found.pdf_of))
    else:
        verdict = text("inspect.drawn_both_differ")
    if found.integral > 1 + SAME_SHARE:
        verdict += text("inspect.drawn_integral", integral=f"{found.integral:.4g}")
    return text(
        "inspect.drawn",
        draws=found.draws,
        cos_o=f"{found.cos_theta_o:.4g}",
        drawn=percent(found.drawn),
        where=where,
        pdf=percent(found.pdf),
        references=references,
        bins=found.bins,
        p=f"{found.p:.2g}",
        verdict=verdict,
    )
