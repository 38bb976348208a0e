"""Rough metals: the GGX (Trowbridge-Reitz) microfacet BRDF, with an optional diffuse base.

A rough surface is a field of tiny mirrors ("microfacets"). Light goes from ``wi`` to ``wo``
off the facets whose normal is the half vector h = normalize(wo + wi), which gives the
Cook-Torrance / Torrance-Sparrow BRDF (Walter et al. 2007, "Microfacet Models for Refraction
through Rough Surfaces", eq. 20; pbrt-v4 section 9.6; GAMES101 lecture 17):

    f_r(wo, wi) = D(h) G2(wo, wi) F(wo . h) / (4 cos_theta_o cos_theta_i)

* ``D``: the GGX / Trowbridge-Reitz normal distribution,
  D(h) = alpha^2 / (pi ((n . h)^2 (alpha^2 - 1) + 1)^2) (Walter et al. 2007 eq. 33;
  pbrt-v4 section 9.6.1), normalised so that the integral of D(h) cos(theta_h) is 1;
* ``G2``: Smith's height-correlated masking-shadowing, G2 = 1 / (1 + Lambda(wo) + Lambda(wi))
  with Lambda(w) = (sqrt(1 + alpha^2 tan^2(theta)) - 1) / 2 (Heitz 2014, "Understanding the
  Masking-Shadowing Function in Microfacet-Based BRDFs", eqs. 72 and 99; pbrt-v4 9.6.2-9.6.3);
  ``G1(w) = 1 / (1 + Lambda(w))`` masks one direction;
* ``F``: Schlick's approximation of the Fresnel reflectance with an RGB F0 (the metal's
  colour at normal incidence), F = F0 + (1 - F0) (1 - wo . h)^5 (Schlick 1994;
  ``ptlab.scattering.F_schlick``).

**Roughness.** Users type a ``roughness`` in (0, 1]; the GGX parameter is
alpha = roughness^2 (Burley 2012, "Physically Based Shading at Disney"; Karis 2013), which
makes equal steps of roughness look like equal steps of blur. (pbrt-v4's ``remaproughness``
takes alpha = sqrt(roughness) instead: its "roughness" is alpha^2, ours is sqrt(alpha), so
scene values do not carry over.) ``alpha=`` sets alpha directly.

**Sampling** (``sampling=``):

* ``"vndf"`` (default): the visible normals of Heitz 2018, drawn with the spherical caps of
  Dupuy and Benyoub 2023 (``ptlab.sampling.ggx_visible_normals``), then wi = reflect(wo, h).
  Its exact pdf is D_wo(h) times the Jacobian 1 / (4 |wo . h|) of the reflection
  (Walter et al. 2007 eq. 14): pdf(wi) = G1(wo) D(h) / (4 cos_theta_o). A wi that lands
  below the surface is a failed sample (pdf 0, weight 0); that happens with probability
  1 - integral of pdf, more often at grazing wo and high alpha. Each sample's weight is
  f cos_theta_i / pdf = F G2 / G1(wo), never more than 1.
* ``"hemisphere"``: the diffuse material's cosine-weighted hemisphere, pdf cos_theta_i / pi
  (what the homework allows). Correct but noisy for smooth metals: most samples miss the lobe.

**Diffuse base.** ``kd`` adds a Lambertian layer under the specular one,
f_r = kd / pi + ks f_spec, with no energy exchanged between the layers (kd + ks <= 1 keeps
it energy conserving). With ``"vndf"`` the sampler picks a lobe with probability
p_specular = mean(ks F0) / (mean(ks F0) + mean(kd)) and the pdf is the mixture
p_specular pdf_vndf + (1 - p_specular) cos_theta_i / pi (one-sample MIS over the lobes, the
balance heuristic: Veach 1997, section 9.2.4).

Reflective only: ``eval`` and ``pdf`` are zero when ``wo`` or ``wi`` is below the surface.
"""

from __future__ import annotations

import math

import numpy as np

from ptlab.materials.base import Material
from ptlab.samplers import largest_below_one
from ptlab.sampling import cosine_hemisphere, ggx_visible_normals, to_world
from ptlab.scattering import F_schlick, reflect
from ptlab.vectors import channels, dot, normalize

SAMPLINGS = ("vndf", "hemisphere")

#: Linear RGB reflectance at normal incidence (F0) of some metals
#: (Real-Time Rendering, 4th edition, table 9.2).
METALS = {
    "gold": (1.000, 0.782, 0.344),
    "copper": (0.955, 0.638, 0.538),
    "aluminium": (0.913, 0.922, 0.924),
    "silver": (0.972, 0.960, 0.915),
    "iron": (0.562, 0.565, 0.578),
}

#: The smallest alpha accepted: below it D is too sharp to be useful (use ``Mirror``).
MIN_ALPHA = 1e-3

#: Cosines are clamped to at least this in Lambda and the 4 cos cos denominator, so that
#: grazing directions (cos = 0 exactly, or tiny in float32) give finite values.
COS_EPSILON = 1e-7


def D(cos_theta_h: np.ndarray, alpha) -> np.ndarray:  # noqa: N802 (the papers' name)
    """(N,) GGX normal distribution at microfacet normals with n . h = ``cos_theta_h``."""
    alpha2 = alpha * alpha
    denominator = cos_theta_h * cos_theta_h * (alpha2 - 1.0) + 1.0
    return alpha2 / (math.pi * denominator * denominator)


def Lambda(cos_theta: np.ndarray, alpha) -> np.ndarray:  # noqa: N802 (the papers' name)
    """(N,) Smith's Lambda for GGX, for directions with 0 < cos_theta <= 1 (Heitz 2014 eq. 72)."""
    cos2_theta = cos_theta * cos_theta
    tan2_theta = (1.0 - cos2_theta) / cos2_theta
    return (np.sqrt(1.0 + alpha * alpha * tan2_theta) - 1.0) / 2.0


def G1(cos_theta: np.ndarray, alpha) -> np.ndarray:  # noqa: N802 (the papers' name)
    """(N,) the fraction of microfacets visible from one direction (Smith masking)."""
    return 1.0 / (1.0 + Lambda(cos_theta, alpha))


def G2(cos_theta_o: np.ndarray, cos_theta_i: np.ndarray, alpha) -> np.ndarray:  # noqa: N802 (the papers' name)
    """(N,) height-correlated masking-shadowing (Heitz 2014 eq. 99; pbrt-v4 section 9.6.3)."""
    return 1.0 / (1.0 + Lambda(cos_theta_o, alpha) + Lambda(cos_theta_i, alpha))


def _rows(value, dtype) -> float | np.ndarray:
    """A parameter in the arrays' dtype: a Python float (which never promotes) or an array."""
    if np.ndim(value) == 0:
        return float(value)
    return np.asarray(value).astype(dtype, copy=False)


class Microfacet(Material):
    """GGX rough conductor, optionally over a Lambertian base.

    Args:
        f0: (3,) linear RGB reflectance at normal incidence (Schlick's F0), or the name of
            one of ``METALS`` ("gold", "copper", "aluminium", "silver", "iron").
        roughness: perceptual roughness in (0, 1]; alpha = roughness^2. Default 0.5.
        alpha: the GGX alpha itself, in [1e-3, 1], instead of ``roughness``.
        kd: (3,) albedo of the diffuse base (default 0: a bare metal).
        ks: weight of the specular layer, a number or (3,) (default 1); kd + ks <= 1.
        sampling: ``"vndf"`` (default) or ``"hemisphere"`` (cosine-weighted).
    """

    samplings = SAMPLINGS
    batched = ("f0", "kd", "ks", "alpha", "p_specular")

    def __init__(
        self,
        f0="gold",
        roughness: float | None = None,
        alpha: float | None = None,
        kd=(0.0, 0.0, 0.0),
        ks=1.0,
        sampling: str = "vndf",
    ):
        if sampling not in SAMPLINGS:
            raise ValueError(f"unknown sampling {sampling!r}; choose one of {', '.join(SAMPLINGS)}")
        if roughness is not None and alpha is not None:
            raise ValueError("give roughness or alpha, not both (alpha = roughness ** 2)")
        if alpha is None:
            roughness = 0.5 if roughness is None else float(roughness)
            if not roughness >= 0:  # (squaring would hide the sign)
                raise ValueError(f"roughness must be in (0, 1] (alpha = roughness ** 2), got {roughness}")
            alpha = roughness * roughness
        if not MIN_ALPHA <= alpha <= 1:
            raise ValueError(
                f"alpha must be in [{MIN_ALPHA}, 1] (roughness in "
                f"[{math.sqrt(MIN_ALPHA):.3f}, 1]), got {alpha}; "
                "use Mirror for a perfect mirror"
            )
        if isinstance(f0, str):
            if f0 not in METALS:
                raise ValueError(f"unknown metal {f0!r}; choose one of {', '.join(METALS)} or give an RGB F0")
            f0 = METALS[f0]
        self.f0 = _colour("f0", f0)
        self.kd = _colour("kd", kd)
        self.ks = _colour("ks", np.broadcast_to(np.asarray(ks, dtype=np.float64), (3,)))
        if (self.kd + self.ks > 1 + 1e-12).any():
            raise ValueError(
                f"kd + ks must be at most 1 in every channel, got {(self.kd + self.ks).tolist()}"
            )
        self.alpha = float(alpha)
        self.sampling = sampling
        specular, diffuse = float(np.mean(self.ks * self.f0)), float(np.mean(self.kd))
        self.p_specular = specular / (specular + diffuse) if specular + diffuse > 0 else 1.0

    def __repr__(self) -> str:
        if np.ndim(self.alpha) != 0:
            return f"Microfacet(stacked, {np.size(self.alpha)} rows, sampling={self.sampling!r})"
        text = f"Microfacet(f0={self.f0.tolist()}, alpha={self.alpha:g}"
        if self.kd.any():
            text += f", kd={self.kd.tolist()}, ks={self.ks.tolist()}"
        return text + f", sampling={self.sampling!r})"

    def eval(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        """(N, 3) f_r(wo, wi), cosine not included; wo, wi, n: (N, 3) unit vectors."""
        alpha = _rows(self.alpha, wi.dtype)
        cos_theta_o, cos_theta_i = dot(wo, n), dot(wi, n)
        above = (cos_theta_o > 0) & (cos_theta_i > 0)
        cos_o = np.maximum(cos_theta_o, COS_EPSILON)
        cos_i = np.maximum(cos_theta_i, COS_EPSILON)
        h = normalize(wo + wi)
        F = F_schlick(dot(wo, h), self.f0.astype(wi.dtype, copy=False))  # noqa: N806
        # Divide by cos_o and cos_i one after the other: their product can underflow in float32.
        specular = D(dot(h, n), alpha) * G2(cos_o, cos_i, alpha) / (4.0 * cos_o) / cos_i * above
        diffuse = above.astype(wi.dtype) / math.pi
        ks, kd = (channels(c.astype(wi.dtype, copy=False)) for c in (self.ks, self.kd))
        return (ks * F.T * specular + kd * diffuse).T

    def pdf(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        """(N,) solid-angle density with which ``sample`` picks ``wi``."""
        cos_theta_o, cos_theta_i = dot(wo, n), dot(wi, n)
        above = (cos_theta_o > 0) & (cos_theta_i > 0)
        pdf_diffuse = np.maximum(cos_theta_i, 0.0) / math.pi
        if self.sampling == "hemisphere":
            return above * pdf_diffuse
        alpha = _rows(self.alpha, wi.dtype)
        p_specular = _rows(self.p_specular, wi.dtype)
        cos_o = np.maximum(cos_theta_o, COS_EPSILON)
        h = normalize(wo + wi)
        # D_wo(h) / (4 wo.h) with D_wo(h) = G1(wo) (wo.h) D(h) / cos_theta_o: wo.h cancels.
        pdf_specular = G1(cos_o, alpha) * D(dot(h, n), alpha) / (4.0 * cos_o)
        return above * (p_specular * pdf_specular + (1.0 - p_specular) * pdf_diffuse)

    def sample(
        self, wo: np.ndarray, n: np.ndarray, u: np.ndarray, front: np.ndarray | None = None
    ) -> np.ndarray:
        """(N, 3) unit directions with density ``pdf``; u: (N, 2) uniforms in [0, 1)."""
        u = u.astype(n.dtype, copy=False)
        if self.sampling == "hemisphere":
            return to_world(cosine_hemisphere(u), n)
        alpha = _rows(self.alpha, n.dtype)
        p_specular = _rows(self.p_specular, n.dtype)
        if np.all(p_specular == 1):
            return reflect(wo, ggx_visible_normals(wo, n, alpha, u))
        # Choose a lobe with u[:, 0], then stretch the part of u[:, 0] that chose it back to
        # [0, 1) so that it can sample the lobe too.
        u0 = u[:, 0]
        specular = u0 < p_specular
        u0 = np.where(
            specular,
            u0 / _at_least(p_specular, 1e-30),
            (u0 - p_specular) / _at_least(1.0 - p_specular, 1e-30),
        )
        u = np.stack([np.minimum(u0, largest_below_one(u.dtype)), u[:, 1]], axis=1)
        wi_specular = reflect(wo, ggx_visible_normals(wo, n, alpha, u))
        wi_diffuse = to_world(cosine_hemisphere(u), n)
        return np.where(specular[:, None], wi_specular, wi_diffuse)

    # Every Microfacet with the same sampling shades in one vectorized call.
    def batch_key(self) -> object:
        return ("microfacet", self.sampling)


def _at_least(value, floor: float):
    """max(value, floor) for a Python float (staying one, so it never promotes) or an array."""
    return np.maximum(value, floor) if isinstance(value, np.ndarray) else max(value, floor)


def _colour(name: str, value) -> np.ndarray:
    colour = np.asarray(value, dtype=np.float64)
    if colour.shape != (3,) or not np.isfinite(colour).all() or (colour < 0).any() or (colour > 1).any():
        raise ValueError(f"{name} must be three numbers in [0, 1], got {value!r}")
    return colour
