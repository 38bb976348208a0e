"""An equal-area grid of cells on the sphere, and adaptive integration over its cells.

The cells are a regular grid over (cos theta, phi) around a normal ``n``: since the solid
angle element is d(cos theta) d(phi), every cell has the same solid angle
4 pi / (n_cos n_phi), and the horizon cos theta = 0 is a cell boundary, so a reflective
material's pdf is smooth inside every cell. (This is the binning of Mitsuba 3's
``chi2`` test and of Nori's; Jakob, "Nori: an educational ray tracer", warptest.)

``SphereGrid.integrate`` computes the integral of a function over every cell (and
``integrate_lobes`` those of several at once, one per lobe, so that one call to a material
serves every lobe) with a tensor 3 x 3 Gauss-Legendre rule in (theta, phi), refining a
region into 2 x 2 children (halving theta and phi) for as long as the children's sum
differs from the parent's estimate by more than a tolerance: peaky lobes (a GGX with
alpha = 0.05 concentrates its pdf in a few cells) get subdivided where they are, and
smooth ones cost 45 evaluations a cell.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ptlab.sampling import to_world
from ptlab.vectors import vec3

#: 3-point Gauss-Legendre nodes and weights on [-1, 1]: exact for polynomials of degree 5.
_NODES = np.array([-math.sqrt(3 / 5), 0.0, math.sqrt(3 / 5)])
_WEIGHTS = np.array([5 / 9, 8 / 9, 5 / 9])


def along(w: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(N,) w . v for the rows of (N, 3) ``w`` and one (3,) vector ``v``.

    Written out rather than ``w @ v``, whose BLAS call may spread over every core: the
    harness is meant to use one.
    """
    return w[:, 0] * v[0] + w[:, 1] * v[1] + w[:, 2] * v[2]


class SphereGrid:
    """``n_cos`` x ``n_phi`` equal-area cells around the unit normal ``n`` (3,).

    Cell ``k = row * n_phi + column`` covers cos theta in [-1 + row d_cos, -1 + (row + 1) d_cos]
    and phi in [column d_phi, (column + 1) d_phi], with theta, phi measured from ``n`` in the
    tangent frame of ``ptlab.sampling.to_world``.
    """

    def __init__(self, n: np.ndarray, n_cos: int = 64, n_phi: int = 128):
        self.n = np.asarray(n, dtype=np.float64)
        self.n_cos, self.n_phi = n_cos, n_phi
        self.cells = n_cos * n_phi
        self.d_cos, self.d_phi = 2.0 / n_cos, 2.0 * math.pi / n_phi
        self.cell_solid_angle = self.d_cos * self.d_phi
        frame = to_world(np.eye(3), np.tile(self.n, (3, 1)))
        self.t, self.s = frame[0], frame[1]

    @classmethod
    def for_samples(cls, n: np.ndarray, samples: int) -> SphereGrid:
        """A grid with about ``samples`` / 125 cells (64 x 128 for 10^6 samples), at least 8 x 16.

        A uniform distribution then expects about 125 samples a cell; ``n_cos`` is even, so
        that the horizon is a cell boundary.
        """
        n_cos = int(np.clip(2 * round(math.sqrt(samples / 250) / 2), 8, 64))
        return cls(n, n_cos, 2 * n_cos)

    def local(self, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(N,) cos theta and (N,) phi in [0, 2 pi) of (N, 3) unit vectors."""
        cos_theta = along(w, self.n)
        phi = np.arctan2(along(w, self.s), along(w, self.t))
        return cos_theta, np.where(phi < 0, phi + 2.0 * math.pi, phi)

    def directions(self, cos_theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
        """(N, 3) unit vectors (column-major) at the given (N,) cos theta and phi."""
        sin_theta = np.sqrt(np.maximum(0.0, 1.0 - cos_theta * cos_theta))
        x, y = sin_theta * np.cos(phi), sin_theta * np.sin(phi)
        return vec3(
            x * self.t[0] + y * self.s[0] + cos_theta * self.n[0],
            x * self.t[1] + y * self.s[1] + cos_theta * self.n[1],
            x * self.t[2] + y * self.s[2] + cos_theta * self.n[2],
        )

    def cell_of(self, w: np.ndarray) -> np.ndarray:
        """(N,) intp index of the cell holding each of the (N, 3) unit vectors."""
        cos_theta, phi = self.local(w)
        row = np.clip(((cos_theta + 1.0) / self.d_cos).astype(np.intp), 0, self.n_cos - 1)
        column = np.clip((phi / self.d_phi).astype(np.intp), 0, self.n_phi - 1)
        return row * self.n_phi + column

    def histogram(self, w: np.ndarray) -> np.ndarray:
        """(cells,) number of the (N, 3) unit vectors in each cell."""
        return np.bincount(self.cell_of(w), minlength=self.cells)

    def integrate(
        self,
        f: Callable[[np.ndarray], np.ndarray],
        tolerance: Callable,
        max_levels: int = 7,
        max_regions: int = 100_000,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Integrals of one vector-valued function over every cell, and their error bounds:
        ``integrate_lobes`` with one lobe, ``f`` mapping (P, 3) directions to (P, K) values.

        Returns:
            (cells, K) integrals and (K,) total error estimates.
        """
        totals, errors = self.integrate_lobes(lambda lobe, w: f(w), tolerance, 1, max_levels, max_regions)
        return totals[0], errors[0]

    def integrate_lobes(
        self,
        f: Callable[[np.ndarray, np.ndarray], np.ndarray],
        tolerance: Callable,
        lobes: int,
        max_levels: int = 7,
        max_regions: int = 100_000,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Integrals of ``lobes`` vector-valued functions over every cell, and their error bounds.

        The functions are integrated together, so that each step asks ``f`` about the
        points of all of them at once (one call to a material for every lobe).

        Args:
            f: maps (P,) lobe indices and (P, 3) unit directions to (P, K) values, each row
                the value of its lobe's function.
            tolerance: maps a region's (R, K) integrals and its (R,) solid angles to the
                (R, K) errors accepted for it.
            lobes: how many functions ``f`` holds.
            max_levels: how many times a cell may be halved in each direction.
            max_regions: regions of one lobe refined at once at most; beyond, the rest of
                that lobe is accepted.

        Returns:
            (lobes, cells, K) integrals and (lobes, K) total error estimates (the sum of
            |fine - coarse| over the accepted regions: an overestimate for smooth functions).
        """
        rows, columns = np.divmod(np.arange(self.cells), self.n_phi)
        # Regions are spans of theta (not cos theta) so that halving one near a pole halves its size.
        theta0 = np.arccos(np.clip(-1.0 + (rows + 1) * self.d_cos, -1.0, 1.0))
        d_theta = np.arccos(np.clip(-1.0 + rows * self.d_cos, -1.0, 1.0)) - theta0
        # Every region: theta0, phi0, d_theta, d_phi, its cell and its lobe; the lobes of a
        # cell side by side, so that every call of f has the points of all lobes interleaved.
        regions = (
            np.repeat(theta0, lobes),
            np.repeat(columns * self.d_phi, lobes),
            np.repeat(d_theta, lobes),
            np.full(lobes * self.cells, self.d_phi),
            np.repeat(np.arange(self.cells), lobes),
            np.tile(np.arange(lobes), self.cells),
        )
        coarse = self._rule(f, regions)
        values = coarse.shape[1]
        totals = np.zeros((lobes * self.cells, values))
        error = np.zeros((lobes, values))
        for level in range(max_levels + 1):
            children = _split(*regions)
            fine_parts = self._rule(f, children)
            fine = fine_parts.reshape(-1, 4, values).sum(axis=1)
            difference = np.abs(fine - coarse)
            area = (np.cos(regions[0]) - np.cos(regions[0] + regions[2])) * regions[3]
            done = (difference <= tolerance(fine, area)).all(axis=1)
            lobe = regions[5]
            if level == max_levels:
                done[:] = True
            else:
                done |= (np.bincount(lobe[~done], minlength=lobes) * 4 > max_regions)[lobe]
            slot = lobe[done] * self.cells + regions[4][done]
            for k in range(values):
                totals[:, k] += np.bincount(slot, weights=fine[done, k], minlength=lobes * self.cells)
                error[:, k] += np.bincount(lobe[done], weights=difference[done, k], minlength=lobes)
            if done.all():
                break
            refine = np.repeat(~done, 4)
            regions = tuple(a[refine] for a in children)
            coarse = fine_parts[refine]
        return totals.reshape(lobes, self.cells, values), error

    def _rule(self, f, regions: tuple[np.ndarray, ...]) -> np.ndarray:
        """(R, K) 3 x 3 Gauss-Legendre estimates of the integrals over R ``regions`` (theta0,
        phi0, d_theta, d_phi, cell, lobe: (R,) each), each of the function of its lobe.

        The rule runs over (theta, phi) with the weight sin theta: a function smooth on the
        sphere is smooth in (theta, phi) even at the poles, where as a function of
        cos theta it has a square-root singularity that would need much refining.
        """
        theta0, phi0, d_theta, d_phi, _, lobe = regions
        x = (_NODES + 1.0) / 2.0
        theta = (theta0[:, None, None] + d_theta[:, None, None] * x[None, :, None]).repeat(3, axis=2)
        phi = (phi0[:, None, None] + d_phi[:, None, None] * x[None, None, :]).repeat(3, axis=1)
        values = np.asarray(
            f(np.repeat(lobe, 9), self.directions(np.cos(theta).ravel(), phi.ravel())), dtype=np.float64
        )
        values = values.reshape(len(theta0), 9, -1) * np.sin(theta).reshape(len(theta0), 9, 1)
        weights = np.outer(_WEIGHTS, _WEIGHTS).ravel() / 4.0
        return np.einsum("rpk,p->rk", values, weights) * (d_theta * d_phi)[:, None]


def _split(theta0, phi0, d_theta, d_phi, *labels) -> tuple[np.ndarray, ...]:
    """The 2 x 2 children of each region, the four of region r at rows 4r .. 4r + 3; the
    ``labels`` (the cell, the lobe) are the parent's."""
    half_theta, half_phi = d_theta / 2.0, d_phi / 2.0
    theta_children = np.stack([theta0, theta0, theta0 + half_theta, theta0 + half_theta], axis=1).ravel()
    phi_children = np.stack([phi0, phi0 + half_phi, phi0, phi0 + half_phi], axis=1).ravel()
    return (
        theta_children,
        phi_children,
        np.repeat(half_theta, 4),
        np.repeat(half_phi, 4),
        *(np.repeat(label, 4) for label in labels),
    )
