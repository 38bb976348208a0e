"""Images (ptlab/image.py): the sRGB encoding of PNG files, against colour-science."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from ptlab.image import encode_srgb8, srgb_encode


def colour_science():
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*[Mm]atplotlib.*")
        import colour
    return colour


def test_srgb_encoding_is_colour_sciences():
    # IEC 61966-2-1 as colour-science implements it, on a ramp dense enough to cross every
    # 8-bit level many times, and around the break point of the linear toe.
    ramp = np.concatenate([np.linspace(0, 1, 1_000_001), 0.0031308 + np.linspace(-1e-6, 1e-6, 2001)])
    expected = colour_science().cctf_encoding(ramp, function="sRGB")
    np.testing.assert_allclose(srgb_encode(ramp), expected, rtol=0, atol=1e-15)
    image = ramp[:1_000_000].reshape(1000, 1000, 1).repeat(3, axis=2)
    assert np.array_equal(
        encode_srgb8(image),
        np.round(expected[:1_000_000] * 255).astype(np.uint8).reshape(1000, 1000, 1).repeat(3, axis=2),
    )


@pytest.mark.subprocess
def test_writing_a_png_does_not_import_colour_science_or_matplotlib():
    # Start-up: each would cost the PNG a second of imports (colour imports matplotlib.pyplot).
    import subprocess
    import sys

    code = (
        "import sys, numpy as np; from ptlab.image import write_image; "
        "write_image(sys.argv[1], np.zeros((2, 2, 3), np.float32)); "
        "print(sorted({'colour', 'matplotlib'} & set(sys.modules)))"
    )
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        out = subprocess.run(
            [sys.executable, "-c", code, f"{folder}/x.png"], capture_output=True, text=True, check=True
        ).stdout
    assert out.strip() == "[]"
