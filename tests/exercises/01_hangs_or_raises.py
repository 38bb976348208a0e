"""Chapter-1 code that hangs on some inputs and raises on others: the grader must report
both as failed checks and go on."""


def generate_rays(camera, width, height, pixel_x, pixel_y, u):
    if len(pixel_x) == 1:
        while True:          # hangs on the single-ray checks
            pass
    return _scale(pixel_x)


def _scale(pixel_x):
    raise ValueError(f"my bug with {len(pixel_x)} rays")
