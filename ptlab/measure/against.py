"""``ptlab bench --against``: ptlab's time against a compiled C++ path tracer.

The GAMES101 Homework 7 framework builds one program, ``RayTracing``, that path-traces the
Cornell box (784x784 in its ``main.cpp``) and writes ``binary.ppm`` into the folder it runs
in, reading its meshes from ``../models/cornellbox/``. This module runs that program and
``ptlab render`` with the homework's estimator (uniform hemisphere sampling, Russian roulette
0.8) at the resolution of the C++ image, alternately, ``repeat`` times, each as a whole
process timed by wall clock, so that start-up, scene loading and the BVH build count on both
sides and a drift of the machine's speed falls on both alike.

The C++ program runs in a fresh scratch folder (so that it never overwrites a
``binary.ppm`` of the user's); beside that folder a link ``models`` points at the
``models`` folder next to the program's build folder, where the framework's ``main.cpp``
looks for the meshes.
"""

from __future__ import annotations

import os
import shlex
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from ptlab.errors import PtlabError
from ptlab.image import read_image
from ptlab.rendering.settings import MAX_SPP, check_workers

#: ``ptlab render``'s options for the homework's estimator: uniform hemisphere sampling,
#: Russian roulette with survival probability 0.8 from the first bounce on.
HOMEWORK_OPTIONS = ("--sampling", "uniform", "--rr", "0.8")

#: The C++ program's arguments: its samples per pixel (``{spp}`` is replaced).
DEFAULT_CPP_ARGS = "{spp}"

CPP_IMAGE = "binary.ppm"


@dataclass
class AgainstResult:
    """Wall seconds of each C++ run and of the ptlab run that followed it."""

    resolution: tuple[int, int]
    cpp_seconds: list[float] = field(default_factory=list)
    ptlab_seconds: list[float] = field(default_factory=list)

    @property
    def ratios(self) -> list[float]:
        """C++ seconds / ptlab seconds, pair by pair (above 1: ptlab is faster)."""
        return [c / p for c, p in zip(self.cpp_seconds, self.ptlab_seconds, strict=True)]

    def summary(self) -> str:
        """The median ratio and, over several pairs, its range."""
        ratios = self.ratios
        spread = (
            "1 pair"
            if len(ratios) == 1
            else (f"median of {len(ratios)} pairs, range {min(ratios):.2f}-{max(ratios):.2f}")
        )
        return f"C++ / ptlab time: {statistics.median(ratios):.2f}x ({spread}; above 1, ptlab is faster)"


def reject_options(given: dict[str, object]) -> None:
    """A one-line error for the first of ``ptlab bench``'s other options that was given:
    with ``--against`` they would be silently ignored."""
    for option, value in given.items():
        if value:
            raise PtlabError(
                f"{option} does not go with --against: it times ptlab render at "
                "the C++ image's size with the homework's estimator"
            )


def check_program(binary: str | Path) -> Path:
    """The absolute path of an executable file, or a one-line error saying what it is not."""
    path = Path(binary).expanduser()
    if not path.exists():
        raise PtlabError(f"--against {binary}: no such file")
    if path.is_dir():
        raise PtlabError(
            f"--against {binary}: is a folder; give the compiled program (for the homework: build/RayTracing)"
        )
    if not os.access(path, os.X_OK):
        raise PtlabError(f"--against {binary}: is not executable")
    return path.resolve()


def _timed(command: list[str], cwd: Path, env: dict[str, str]) -> tuple[float, int, str]:
    """Run ``command`` in ``cwd``: its wall seconds, exit code and last line on stderr."""
    start = time.perf_counter()
    done = subprocess.run(
        command, cwd=cwd, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    seconds = time.perf_counter() - start
    lines = done.stderr.decode(errors="replace").strip().splitlines()
    return seconds, done.returncode, lines[-1] if lines else ""


def _exit_reason(code: int, last_line: str) -> str:
    reason = (
        f"was killed by {signal.Signals(-code).name}"
        if code < 0 and -code in signal.valid_signals()
        else f"failed with exit code {code}"
    )
    return f"{reason}: {last_line}" if last_line else reason


def models_folder(binary: Path) -> Path:
    """Where the homework keeps the meshes its ``main.cpp`` reads as ``../models/...``: beside
    the build folder that holds the program."""
    return binary.parent.parent / "models"


def run_cpp(
    binary: Path, args: list[str], folder: Path, env: dict[str, str], expected: tuple[int, int] | None = None
) -> tuple[float, tuple[int, int]]:
    """Run the C++ program once in ``folder`` (emptied of an old image first): its wall
    seconds and the (width, height) of the image it wrote, which must be ``expected``."""
    image = folder / CPP_IMAGE
    image.unlink(missing_ok=True)
    try:
        seconds, code, last_line = _timed([str(binary), *args], folder, env)
    except OSError as error:
        raise PtlabError(f"--against {binary}: cannot run it: {error.strerror}") from None
    if code != 0:
        models = models_folder(binary)
        hint = "" if models.is_dir() else f" (there is no {models} to give it as ../models)"
        raise PtlabError(f"--against {binary} {_exit_reason(code, last_line)}{hint}")
    if not image.is_file():
        raise PtlabError(f"--against {binary} wrote no {CPP_IMAGE} into the folder it ran in")
    try:
        pixels, _ = read_image(image)
    except PtlabError as error:
        raise PtlabError(f"--against {binary} wrote an unreadable {CPP_IMAGE}: {error}") from None
    size = pixels.shape[1], pixels.shape[0]
    if expected is not None and size != expected:
        raise PtlabError(
            f"--against {binary} wrote a {size[0]}x{size[1]} image after a {expected[0]}x{expected[1]} one"
        )
    return seconds, size


def ptlab_args(resolution: tuple[int, int], spp: int, workers: int, out: Path) -> list[str]:
    """``ptlab render cornell-box``'s arguments with the homework's estimator."""
    width, height = resolution
    return [
        "render",
        "cornell-box",
        "--res",
        f"{width}x{height}",
        "--spp",
        str(spp),
        *HOMEWORK_OPTIONS,
        "--workers",
        str(workers),
        "--quiet",
        "--out",
        str(out),
    ]


def run_ptlab(args: list[str], folder: Path, env: dict[str, str]) -> float:
    """Run ``ptlab ARGS`` once, with the Python and ptlab of this process: its wall seconds."""
    seconds, code, last_line = _timed([sys.executable, "-m", "ptlab.cli", *args], folder, env)
    if code != 0:
        raise PtlabError(f"ptlab {args[0]} {_exit_reason(code, last_line)}")
    return seconds


def scratch_folders(scratch: Path, binary: Path) -> Path:
    """The C++ program's working folder inside ``scratch``, with ``../models`` linked to
    ``models_folder(binary)``."""
    models = models_folder(binary)
    if models.is_dir():
        (scratch / "models").symlink_to(models, target_is_directory=True)
    folder = scratch / "run"
    folder.mkdir()
    return folder


def run_against(
    binary: str | Path,
    cpp_args: str = DEFAULT_CPP_ARGS,
    spp: int = 16,
    repeat: int = 3,
    workers: int | None = None,
    echo=print,
) -> AgainstResult:
    """Time the C++ program ``binary`` and ``ptlab render``, alternately, ``repeat`` times.

    ``cpp_args`` is the C++ program's command line after its name (split like a shell's,
    ``{spp}`` replaced by ``spp``); ``workers`` are ptlab's processes (``None``: one per
    core), and both programs get ``OMP_NUM_THREADS=workers``, so that an OpenMP program
    runs as many threads. Prints each pair's seconds, the medians and the ratio C++ / ptlab
    with its range over the pairs.
    """
    if os.name != "posix":
        raise PtlabError("--against runs on Linux and macOS only")
    if not 1 <= repeat <= 100:
        raise PtlabError(f"--repeat {repeat}: must be from 1 to 100")
    if not 1 <= spp <= MAX_SPP:
        raise PtlabError(f"--spp {spp}: must be from 1 to {MAX_SPP}")
    workers = check_workers(workers)
    program = check_program(binary)
    try:
        args = shlex.split(cpp_args.replace("{spp}", str(spp)))
    except ValueError as error:
        raise PtlabError(f"--cpp-args {cpp_args!r}: {error}") from None
    env = dict(os.environ, OMP_NUM_THREADS=str(workers))
    echo(f"C++:   {shlex.join([str(program), *args])}  (in a scratch folder, OMP_NUM_THREADS={workers})")
    with tempfile.TemporaryDirectory(prefix="ptlab-against-") as scratch_name:
        scratch = Path(scratch_name)
        cpp_folder = scratch_folders(scratch, program)
        cpp, resolution = run_cpp(program, args, cpp_folder, env)
        ptlab = ptlab_args(resolution, spp, workers, scratch / "ptlab.png")
        echo(f"ptlab: {shlex.join(['ptlab', *ptlab])}")
        echo(
            f"{resolution[0]}x{resolution[1]} (the C++ image's size), {spp} spp; wall seconds "
            "of whole processes, run alternately"
        )
        echo(f"{'run':6} {'C++':>8} {'ptlab':>8} {'C++ / ptlab':>12}")
        result = AgainstResult(resolution)
        for k in range(repeat):
            if k > 0:
                cpp, _ = run_cpp(program, args, cpp_folder, env, expected=resolution)
            result.cpp_seconds.append(cpp)
            result.ptlab_seconds.append(run_ptlab(ptlab, scratch, env))
            echo(f"{k + 1:<6} {cpp:8.2f} {result.ptlab_seconds[-1]:8.2f} {result.ratios[-1]:12.2f}")
    echo(
        f"{'median':6} {statistics.median(result.cpp_seconds):8.2f} "
        f"{statistics.median(result.ptlab_seconds):8.2f}"
    )
    echo(result.summary())
    return result
