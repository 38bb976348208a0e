"""Ray queries through Intel Embree, via the ``embreex`` binding.

Embree is the production-quality path: a highly optimised BVH traversal in C++ that
releases the GIL while it runs. Facts about the binding that shape this module
(measured with embreex 4.4):

* it wants writable float32 arrays of any strides: ptlab's column-major batches go in as
  they are (a copy to row-major costs more than Embree then saves: docs/performance.md);
* the ray start distance is fixed at 0, so ``tmin`` is applied by moving the origin;
* the per-ray far distance goes in through ``dists``, which INTERSECT overwrites;
* OCCLUDED returns 0 for occluded rays and -1 for visible ones.
"""

from __future__ import annotations

import numpy as np
from embreex import rtcore_scene
from embreex.mesh_construction import TriangleMesh

from ptlab.accel.base import Hits

#: Whether this process has built an Embree scene, and so started Embree's threads, after
#: which it must not fork workers (``ptlab.rendering.executors.pool_context``).
threads_started = False


def _as_f32(a: np.ndarray) -> np.ndarray:
    # No copy of a float32 array in any layout; a read-only one (the camera's broadcast
    # origins) is copied, since the binding asks for a writable buffer.
    a = np.asarray(a, dtype=np.float32)
    return a if a.flags.writeable else a.copy()


def _far_distances(tmax: float | np.ndarray, n: int) -> np.ndarray:
    # A fresh array every call: Embree writes the hit distances into it.
    dists = np.empty(n, dtype=np.float32)
    dists[:] = np.minimum(tmax, np.finfo(np.float32).max)
    return dists


class EmbreeAccelerator:
    """The ``Accelerator`` interface on top of an Embree scene.

    Args:
        triangles: (T, 3, 3) array, vertex k of triangle i at ``triangles[i, k]``.
    """

    name = "embree"

    def __init__(self, triangles: np.ndarray):
        global threads_started
        threads_started = True
        self._triangles = _as_f32(triangles)
        self._scene = rtcore_scene.EmbreeScene()
        self._mesh = TriangleMesh(self._scene, self._triangles)

    def __reduce__(self):
        # Embree's scene lives in C++ memory that pickle cannot copy: another process (the
        # graders send accelerators to the process running a student's code) builds it again.
        return (EmbreeAccelerator, (self._triangles,))

    def intersect(
        self,
        origins: np.ndarray,
        dirs: np.ndarray,
        tmin: float | np.ndarray = 0.0,
        tmax: float | np.ndarray = np.inf,
    ) -> Hits:
        origins, dirs = _as_f32(origins), _as_f32(dirs)
        n = len(origins)
        shifted = not (np.isscalar(tmin) and tmin == 0.0)
        if shifted:
            tmin = np.asarray(tmin, dtype=np.float32)
            origins = origins + (tmin[:, None] if tmin.ndim else tmin) * dirs
            tmax = tmax - tmin
        out = self._scene.run(origins, dirs, dists=_far_distances(tmax, n), output=1)
        prim = out["primID"].astype(np.intp)
        missed = prim < 0
        t = out["tfar"]
        if shifted:
            t = t + tmin
        if missed.any():  # (none do in a closed room: spare the masked write)
            t[missed] = np.inf
        return Hits(t=t, prim=prim, u=out["u"], v=out["v"])

    def occluded(self, origins: np.ndarray, dirs: np.ndarray, tmax: float | np.ndarray) -> np.ndarray:
        origins, dirs = _as_f32(origins), _as_f32(dirs)
        result = self._scene.run(origins, dirs, dists=_far_distances(tmax, len(origins)), query="OCCLUDED")
        return result == 0
