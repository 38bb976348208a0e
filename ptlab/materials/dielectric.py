"""Smooth glass: a delta material that reflects or refracts by the Fresnel equations.

At a smooth boundary between air (outside, index 1) and glass (inside, index ``eta``) light
either reflects, wi = reflect(wo, n), or refracts by Snell's law, wi = refract(wo, n, eta_rel)
(pbrt-v4 sections 9.3 and 9.5; GAMES101 lecture 13, Whitted ray tracing). The fraction
reflected is the exact Fresnel reflectance of unpolarised light, ``fresnel_dielectric``; from
inside beyond the critical angle it is 1: total internal reflection. (The three formulas are
``ptlab.scattering``'s, and so is the split between the two directions, ``FresnelSplit``:
this material picks one of them at random, the Whitted tracer follows both.)

Like ``Mirror`` this is a delta material (pbrt-v4's convention for specular BxDFs): ``eval``
and ``pdf`` return 0 and ``sample_weight`` does the work. It picks reflection with
probability R = fresnel_dielectric(cos_theta_o) using u[:, 0], so the Fresnel factor and the
choice's probability cancel: a reflected sample weighs 1, a refracted one
``transmittance / eta_rel^2``.

**The 1 / eta_rel^2 factor.** eta_rel = eta_t / eta_o is the relative index across the
boundary, eta entering the glass and 1 / eta leaving it. Radiance is squeezed into a smaller
solid angle as it enters a denser medium, so the BTDF carries 1 / eta_rel^2 when it transports
radiance (pbrt-v4 section 9.5, ``TransportMode::Radiance``), as ptlab's camera paths do.
With the camera and the lights both outside the glass, every path enters as often as it
leaves and the factors cancel; they matter when a light or the camera is inside.

**Which side is outside.** The glass's outside is the side its geometric normal points to:
where ``sample`` and ``sample_weight`` are given ``front`` (``ptlab.materials.base``), ``n``
may face either way (the renderer turns it toward ``wo``). Without ``front``, ``n`` must be
the outward normal and ``wo . n > 0`` means ``wo`` is outside (pbrt's convention).
"""

from __future__ import annotations

import numpy as np

from ptlab.materials.base import DeltaMaterial
from ptlab.scattering import FresnelSplit
from ptlab.vectors import dot


class Dielectric(DeltaMaterial):
    """Smooth glass (or water, diamond...): Fresnel reflection and Snell refraction.

    Args:
        eta: index of refraction inside over outside (default 1.5, glass in air).
        transmittance: (3,) colour of refracted light, in [0, 1] (default 1: clear).
    """

    batched = ("eta", "transmittance")
    #: Real indices lie between 1 and about 4; relative ones (an air bubble in water, 0.75)
    #: a little beyond. Refraction scales radiance by eta^2, which this range keeps far
    #: inside float32.
    ETA_RANGE = (0.01, 100.0)

    def __init__(self, eta: float = 1.5, transmittance=(1.0, 1.0, 1.0)):
        lowest, highest = self.ETA_RANGE
        if not lowest <= eta <= highest:
            raise ValueError(
                f"eta must be an index of refraction from {lowest:g} to {highest:g}, got {eta!r}"
            )
        self.eta = float(eta)
        self.transmittance = np.asarray(transmittance, dtype=np.float64)
        if (
            self.transmittance.shape != (3,)
            or not np.isfinite(self.transmittance).all()
            or (self.transmittance < 0).any()
            or (self.transmittance > 1).any()
        ):
            raise ValueError(f"transmittance must be three numbers in [0, 1], got {transmittance!r}")

    def __repr__(self) -> str:
        if np.ndim(self.eta) != 0:
            return f"Dielectric(stacked, {np.size(self.eta)} rows)"
        return f"Dielectric(eta={self.eta:g}, transmittance={self.transmittance.tolist()})"

    def sample(
        self, wo: np.ndarray, n: np.ndarray, u: np.ndarray, front: np.ndarray | None = None
    ) -> np.ndarray:
        """(N, 3) reflected or refracted directions, chosen by Fresnel with u[:, 0]."""
        return self.sample_weight(wo, n, u, front)[0]

    def sample_weight(
        self, wo: np.ndarray, n: np.ndarray, u: np.ndarray, front: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """(N, 3) directions and (N, 3) weights: 1 reflected, transmittance / eta_rel^2 refracted.

        Args:
            wo: (N, 3) unit directions toward the viewer.
            n: (N, 3) unit normals: outward when ``front`` is None, else either way.
            u: (N, 2) uniforms in [0, 1); only u[:, 0] is used.
        """
        cos_theta_o = dot(wo, n)
        outside = cos_theta_o > 0 if front is None else np.asarray(front, dtype=bool)
        # Work with the normal on the side of wo.
        facing = np.where(cos_theta_o >= 0, 1, -1).astype(n.dtype)
        n = n * facing[:, None]
        return FresnelSplit.at(wo, n, self.eta, outside).choose(u[:, 0], self.transmittance)

    def batch_key(self) -> object:
        return "dielectric"
