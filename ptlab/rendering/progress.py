"""The progress bar of a render: samples done, samples per second, time left (tqdm).

It shows on the terminal only: when standard error is a file or a pipe (a CI log, a
script) or with ``--quiet``, it stays silent.
"""

from __future__ import annotations

import sys

from tqdm import tqdm

from ptlab.rendering.film import Film


class ProgressBar:
    """Called with the film after every job; ``close()`` when the render ends.

    Args:
        total_samples: camera samples of the whole render.
        passes: passes of the whole render (shown as "pass k/K").
        initial: samples already done (a resumed render).
    """

    def __init__(self, total_samples: int, passes: int, initial: int = 0, quiet: bool = False):
        self.passes = passes
        self.bar = tqdm(
            total=total_samples,
            initial=initial,
            unit="sample",
            unit_scale=True,
            dynamic_ncols=True,
            leave=False,
            file=sys.stderr,
            disable=quiet or not sys.stderr.isatty(),
        )

    def __call__(self, film: Film) -> None:
        self.bar.update(film.samples - self.bar.n)
        current = min(int(film.passes_done.min()) + 1, self.passes)
        self.bar.set_description(f"pass {current}/{self.passes}")

    def close(self) -> None:
        self.bar.close()
