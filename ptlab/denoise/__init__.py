"""Denoising with Intel Open Image Denoise (optional: ``pip install 'ptlab[denoise]'``), and
an estimate of the denoised image's error that is honest or silent.

* ``inputs``: ``DenoiseInputs``, what a render gives the denoiser (arrays in, arrays out:
  this package knows nothing of the film or the command line);
* ``oidn``: the denoiser itself, with its auxiliary images prefiltered;
* ``pipeline``: ``denoise``, the light seen directly kept out of the denoiser, each half
  image denoised and the error of their mean estimated;
* ``estimate``: that estimate, or its refusal.
"""

from ptlab.denoise.estimate import ErrorEstimate, estimate_error
from ptlab.denoise.inputs import DenoiseInputs
from ptlab.denoise.oidn import denoise_colour, oidn_version, require_oidn
from ptlab.denoise.pipeline import Denoised, denoise

__all__ = [
    "DenoiseInputs",
    "Denoised",
    "ErrorEstimate",
    "denoise",
    "denoise_colour",
    "estimate_error",
    "oidn_version",
    "require_oidn",
]
