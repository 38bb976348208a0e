"""How far an image is from a reference: the error measures renderers are compared with.

* ``rmse``: the root of the mean squared difference over pixels and channels, in the
  image's own units (radiance);
* ``relmse``: the mean *relative* squared error, each pixel's squared difference divided by
  the squared reference value, so that dark and bright regions count alike. As pbrt-v4
  defines it (``Image::MRSE``, used by ``imgtool diff --metric MRSE``):

      relMSE = mean over pixels and channels of (I - R)^2 / (R + 0.01)^2

  The 0.01 keeps black reference pixels from dividing by zero.

For an unbiased Monte Carlo estimator both fall as 1 / samples (MSE = variance / N), so on a
log-log chart of error against time every unbiased method is a line of slope -1, and the
better method is the lower line (Veach 1997, section 2.4; pbrt-v4 section 2.1.4).
"""

from __future__ import annotations

import numpy as np

#: Added to the reference before dividing (pbrt-v4's ``Image::MRSE``).
RELMSE_EPSILON = 0.01


def relative_squared_error(image: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """(H, W) per-pixel relative squared error, the mean over the channels."""
    image, reference = np.asarray(image, np.float64), np.asarray(reference, np.float64)
    return ((image - reference) ** 2 / (reference + RELMSE_EPSILON) ** 2).mean(axis=-1)


def relmse(image: np.ndarray, reference: np.ndarray) -> float:
    """Mean relative squared error of ``image`` against ``reference`` (both (H, W, 3))."""
    return float(relative_squared_error(image, reference).mean())


def rmse(image: np.ndarray, reference: np.ndarray) -> float:
    """Root mean squared error of ``image`` against ``reference``."""
    difference = np.asarray(image, np.float64) - np.asarray(reference, np.float64)
    return float(np.sqrt(np.mean(difference * difference)))
