"""The progress of a render: samples done, samples per second, time left.

On a terminal, a bar (tqdm); in a Jupyter notebook, tqdm's notebook bar (``tqdm.auto``) and
the image so far, refreshed after each pass; where standard error is a file or a pipe (a CI
log, a script's output), one line per pass finished; with ``--quiet``, nothing.
"""

from __future__ import annotations

import os
import sys
import time

from tqdm import tqdm

from ptlab.rendering.display import in_notebook as running_in_notebook
from ptlab.rendering.film import Film


def _columns_of(stream) -> int:
    """The width of the terminal ``stream`` writes to, 0 where it reports none; 80 where
    ``stream`` is no terminal (the bar is off there anyway)."""
    try:
        return os.get_terminal_size(stream.fileno()).columns
    except (OSError, ValueError, AttributeError):
        return 80


class ProgressBar:
    """Called with the film after every job; ``close()`` when the render ends.

    Args:
        total_samples: camera samples of the whole render.
        passes: passes of the whole render (shown as "pass k/K").
        initial: samples already done (a resumed render).
        target: a render to this target error: the passes and samples are not known
            beforehand; the bar shows the estimated error falling toward the target, and its
            total is the samples of the pass under way.
    """

    def __init__(
        self,
        total_samples: int,
        passes: int,
        initial: int = 0,
        quiet: bool = False,
        target: float | None = None,
        denoise: bool = False,
    ):
        self.passes, self.total, self.initial, self.target = passes, total_samples, initial, target
        self.denoise = denoise  # (a notebook shows each pass's image denoised)
        self.start = time.monotonic()
        self.passes_shown = 0
        in_notebook = running_in_notebook()
        on_terminal = sys.stderr.isatty()
        # Lines per pass where there is neither: a file or a pipe would get a bar's every
        # redraw, carriage returns and all.
        self.lines = not quiet and not in_notebook and not on_terminal
        self.pictures = not quiet and in_notebook
        self.picture = None  # (the notebook's display of the image, once a pass is done)
        if in_notebook:
            from tqdm.auto import tqdm as bar_class
        else:
            bar_class = tqdm
        # A terminal that reports 0 columns (some ptys) would get a bar of no width: 80 then.
        columns = _columns_of(sys.stderr)
        self.bar = bar_class(
            total=total_samples,
            initial=initial,
            unit="sample",
            unit_scale=True,
            dynamic_ncols=columns > 0,
            ncols=None if columns > 0 else 80,
            leave=False,
            file=sys.stderr,
            disable=quiet or self.lines,
        )

    def __call__(self, film: Film) -> None:
        if self.target is not None:
            self._toward_target(film)
            return
        self.bar.update(film.samples - self.bar.n)
        done = int(film.passes_done.min())
        self.bar.set_description(f"pass {min(done + 1, self.passes)}/{self.passes}")
        if done > self.passes_shown:
            self.passes_shown = done
            if self.lines:
                print(self.line(film.samples), file=sys.stderr, flush=True)
            elif self.pictures:
                self.show(film)

    def _toward_target(self, film: Film) -> None:
        """A render to a target error: "relMSE 0.031 -> 0.01, pass 3" and the pass's samples."""
        if film.plan is not None and film.plan_total != self.total:
            self.total = self.bar.total = film.plan_total
        self.bar.update(film.samples - self.bar.n)
        done = int(film.passes_done.min()) + film.adaptive_passes
        estimate = "?" if film.estimate is None else f"{film.estimate:.3g}"
        self.bar.set_description(f"relMSE {estimate} -> {self.target:g}, pass {done + 1}")
        if done > self.passes_shown:
            self.passes_shown = done
            if self.lines:
                print(
                    f"pass {done}: {film.samples / 1e6:.2f} M samples, estimated relMSE {estimate} "
                    f"(target {self.target:g})",
                    file=sys.stderr,
                    flush=True,
                )
            elif self.pictures:
                self.show(film)

    def show(self, film: Film) -> None:
        """Show the image so far below the notebook's cell, in place of the last pass's
        (denoised, for a render that denoises: what it will look like)."""
        from IPython.display import Image, display

        from ptlab.rendering.denoising import preview
        from ptlab.rendering.display import png_bytes

        picture = Image(data=png_bytes(preview(film, self.denoise)[0]))
        if self.picture is None:
            self.picture = display(picture, display_id=True)
        else:
            self.picture.update(picture)

    def line(self, samples: int) -> str:
        """``pass 2/8: 25% of 1.05 M samples, 0.41 M samples/s, 12 s left``."""
        seconds = max(time.monotonic() - self.start, 1e-9)
        rate = (samples - self.initial) / seconds
        left = (self.total - samples) / rate if rate > 0 else float("inf")
        return (
            f"pass {self.passes_shown}/{self.passes}: {samples / max(self.total, 1):.0%} of "
            f"{self.total / 1e6:.2f} M samples, {rate / 1e6:.2f} M samples/s, {left:.0f} s left"
        )

    def close(self) -> None:
        self.bar.close()
