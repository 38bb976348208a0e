"""Race ptlab against Mitsuba 3 on the same scene: seconds, error, and whether they agree.

Not run in CI, and Mitsuba is not a dependency of ptlab: install it beside ptlab first (the
``llvm_ad_rgb`` variant needs a libLLVM recent enough for Dr.Jit, e.g. Debian's ``libllvm19``;
the script says so, in one line with exit code 2, if Mitsuba cannot render here).

    pip install mitsuba
    python scripts/against_mitsuba.py --workers 2                  # cornell-box, 256x256, 64 spp
    python scripts/against_mitsuba.py --ptlab-reference ref.exr --ptlab-reference-spp 8192

1. Mitsuba's scene is built from ptlab's own (``ptlab.load_scene``): one OBJ mesh per material,
   written from ptlab's triangles; a ``diffuse`` BSDF of the same RGB albedo inside
   ``twosided`` (ptlab's materials are two-sided: it turns the normal toward the viewer,
   Mitsuba's ``diffuse`` alone is black from behind); an ``area`` emitter of the same RGB
   radiance on each emissive material (both emit from the front face only, the side that
   (v1 - v0) x (v2 - v0) points to); a ``perspective`` sensor with the same eye, viewing
   direction, up and *vertical* field of view; a box pixel filter (ptlab jitters each sample
   uniformly inside its pixel); the ``path`` integrator without a depth limit.
2. Both render ``--repeat`` rounds, a new seed each round, alternating the renderers and
   reversing the order every other round: Mitsuba with each of its samplers and Russian
   roulette depths, ptlab with each of its samplers. A render is timed as the wall-clock of
   the call that returns its pixels as a NumPy array (for Mitsuba, ``mi.render`` and the
   conversion, which waits for the kernel), after one untimed warm-up per configuration so
   that just-in-time compilation is not timed. The whole commands (``ptlab render``, and
   ``mitsuba`` on the same scene file) are also timed, as new processes from start to exit:
   that includes starting Python, imports, loading the scene, the worker processes or the
   kernels from Dr.Jit's disk cache, and writing the EXR.
3. Every image is compared with a reference: ``--reference``, or a ``--reference-spp``
   Mitsuba render (independent sampler, cached in ``$PTLAB_CACHE`` or
   ``~/.cache/ptlab/references`` like ``ptlab converge``'s references).
4. The table gives, per renderer and sampler, the median and range over the rounds of the
   seconds, relMSE (``ptlab.measure.metrics``), relMSE without the pixels that see the light
   (reference above 1 in some channel), RMSE and seconds x relMSE (lower is better: an
   unbiased estimator's error falls as 1 / time, so this is its cost for a given error), and
   its speed and efficiency against ptlab with its default sampler, round by round (that
   one's seconds, and seconds x relMSE, over this one's).
5. With ``--ptlab-reference`` (a high-spp ptlab render), the two references are compared:
   per-channel mean ratio with its z-score, and their relMSE beside what their noise alone
   would give. They must agree; a difference beyond noise is a bug in the scene's
   translation or in a renderer, and the script then exits with code 1.

Russian roulette: Mitsuba numbers the first hit depth 1 and plays roulette once depth >=
``rr_depth``, so its ``rr_depth`` R starts roulette at the same vertex as ptlab's ``rr_depth``
R - 1: Mitsuba's 3 matches ptlab's default 2, Mitsuba's 2 starts one bounce earlier. The odds
differ too (Mitsuba: the throughput after this vertex's BSDF weight, at most 0.95; ptlab: before
it, at most 1). Mitsuba's path tracer always combines light and BSDF sampling with MIS
(``--ptlab-strategy mis`` is ptlab's equivalent; its default, ``nee``, the homework's, samples
the light only).
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

import numpy as np

from ptlab.atomic import write_atomically
from ptlab.errors import PtlabError
from ptlab.image import read_image, write_image
from ptlab.integrators.path import STRATEGIES
from ptlab.materials import Diffuse
from ptlab.measure.converge import REFERENCE_SEED_OFFSET, default_cache_dir, load_reference
from ptlab.measure.metrics import relative_squared_error, rmse
from ptlab.rendering import render_result
from ptlab.rendering.checkpoint import scene_digest
from ptlab.rendering.settings import MAX_SPP, parse_resolution
from ptlab.samplers import DEFAULT_SAMPLER, SAMPLERS
from ptlab.scene import Scene
from ptlab.scene_file import load_scene

PROG = "against_mitsuba.py"
MITSUBA_SAMPLERS = ("independent", "stratified", "multijitter", "ldsampler")
#: Mitsuba rounds these samplers' sample counts up to a square or a power of two.
MITSUBA_SPP_RULES: dict[str, tuple[Callable[[int], bool], str]] = {
    "stratified": (lambda n: math.isqrt(n) ** 2 == n, "a square number"),
    "ldsampler": (lambda n: n & (n - 1) == 0, "a power of two"),
}
#: Mitsuba's own default ``rr_depth``; the reference is rendered with it.
MITSUBA_RR_DEPTH = 5
#: The reference is rendered in passes of this many samples (one Dr.Jit kernel launch holds
#: every sample of a pass: 256 x 256 x 256 is 17 million lanes).
REFERENCE_PASS_SPP = 256
#: Pixels whose reference exceeds this in some channel see the light (the Cornell light is
#: about 40; everything lit by it stays below 1).
LIGHT_THRESHOLD = 1.0
#: The warm-up renders' seed, which no round uses.
WARM_UP_SEED = 2**31 - 1
#: |z| above this: the references' means differ by more than noise (for two unbiased
#: renderers a chance of 6e-5 per channel, of a normal variable beyond 4 standard deviations).
AGREEMENT_Z = 4.0
#: Checks Mitsuba in a child process, with a tiny render: a Dr.Jit built for a newer LLVM than
#: the machine's aborts the process while compiling (``LLVM ERROR: Cannot select``), which
#: Python cannot catch. What it finds wrong it prints as one line to stdout.
PROBE = """
import sys
try:
    import mitsuba as mi
except ImportError as error:
    sys.exit(print(f"cannot import mitsuba ({error}): pip install mitsuba "
                   f"(it is not a dependency of ptlab)") or 1)
if sys.argv[1] not in mi.variants():
    sys.exit(print(f"mitsuba {mi.__version__} has no variant {sys.argv[1]!r} "
                   f"(it has {', '.join(mi.variants())})") or 1)
import numpy as np
mi.set_variant(sys.argv[1])
scene = mi.cornell_box()
scene["sensor"]["film"].update(width=8, height=8)
np.asarray(mi.render(mi.load_dict(scene), spp=1))
"""


class RenderError(Exception):
    """A renderer or a command failed (not the user's mistake): exit code 1."""


# ---------------------------------------------------------------------------------------------
# Mitsuba's scene, written from ptlab's


def _xml_vector(values) -> str:
    return ", ".join(repr(float(v)) for v in values)


def write_mitsuba_scene(scene: Scene, folder: Path, width: int, height: int) -> Path:
    """Write ``scene.xml`` and one OBJ mesh per material into ``folder``; return the XML's path.

    The XML takes the parameters ``$sampler``, ``$spp``, ``$seed`` and ``$rr_depth``
    (``mi.load_file(path, sampler=...)``, or ``mitsuba -D sampler=...``).
    """
    shapes = []
    for k, material in enumerate(scene.materials):
        name = scene.material_names[k]
        if not isinstance(material, Diffuse):
            raise PtlabError(
                f"scene {scene.name}: material {name!r} is a "
                f"{type(material).__name__}; only diffuse materials have a "
                f"Mitsuba counterpart here"
            )
        triangles = scene.triangles[scene.material_ids == k]
        if not len(triangles):
            continue
        mesh = folder / f"material{k}.obj"
        with open(mesh, "w") as out:
            out.write(f"# ptlab scene {scene.name}, material {name}\n")
            # Every triangle has its own three vertices, so the normals are ptlab's face normals.
            np.savetxt(out, triangles.reshape(-1, 3), fmt="v %.17g %.17g %.17g")
            np.savetxt(out, np.arange(1, 3 * len(triangles) + 1).reshape(-1, 3), fmt="f %d %d %d")
        emitter = (
            ""
            if material.emission is None
            else (
                f'<emitter type="area"><rgb name="radiance" value="{_xml_vector(material.emission)}"/>'
                f"</emitter>"
            )
        )
        shapes.append(
            f'  <shape type="obj"><string name="filename" value="{mesh.name}"/>'
            f'<boolean name="face_normals" value="true"/>\n'
            f'    <bsdf type="twosided"><bsdf type="diffuse">'
            f'<rgb name="reflectance" value="{_xml_vector(material.albedo)}"/></bsdf></bsdf>'
            f"{emitter}</shape>"
        )
    camera = scene.camera
    # Nothing may lie beyond the far clipping plane (ptlab has none).
    far = 2 * float(np.linalg.norm(scene.triangles - camera.position, axis=-1).max()) + 1
    # Mitsuba's look_at puts cross(up, forward) on the image's left, and ptlab's camera puts
    # right = forward x up on its right: the same side, so the images need no flip (in the
    # Cornell box both have the red wall, at x = 556, on the left).
    xml = f"""<scene version="3.0.0">
  <default name="sampler" value="independent"/>
  <default name="spp" value="64"/>
  <default name="seed" value="0"/>
  <default name="rr_depth" value="{MITSUBA_RR_DEPTH}"/>
  <integrator type="path">
    <integer name="max_depth" value="-1"/><integer name="rr_depth" value="$rr_depth"/>
  </integrator>
  <sensor type="perspective">
    <float name="fov" value="{camera.fov_y!r}"/><string name="fov_axis" value="y"/>
    <float name="far_clip" value="{far!r}"/>
    <transform name="to_world">
      <lookat origin="{_xml_vector(camera.position)}"
              target="{_xml_vector(camera.position + camera.forward)}"
              up="{_xml_vector(camera.up)}"/>
    </transform>
    <sampler type="$sampler">
      <integer name="sample_count" value="$spp"/><integer name="seed" value="$seed"/>
    </sampler>
    <film type="hdrfilm">
      <integer name="width" value="{width}"/><integer name="height" value="{height}"/>
      <string name="pixel_format" value="rgb"/><rfilter type="box"/>
    </film>
  </sensor>
{chr(10).join(shapes)}
</scene>
"""
    path = folder / "scene.xml"
    path.write_text(xml)
    return path


# ---------------------------------------------------------------------------------------------
# Mitsuba in this process


def import_mitsuba(variant: str) -> tuple[ModuleType, ModuleType]:
    """``mitsuba`` and ``drjit`` with ``variant`` set, once a child process has rendered with it.

    Raises ``PtlabError`` (one line) if Mitsuba is missing or cannot render with the variant.
    """
    probe = subprocess.run([sys.executable, "-c", PROBE, variant], capture_output=True, text=True)
    if probe.returncode != 0:
        if probe.stdout.strip():
            raise PtlabError(probe.stdout.strip().splitlines()[-1])
        lines = [line.strip() for line in probe.stderr.splitlines() if line.strip()]
        cause = next(
            (line for line in lines if "error" in line.lower()),
            lines[-1] if lines else f"exit code {probe.returncode}",
        )
        hint = (
            " (Dr.Jit needs a libLLVM recent enough for it: install one, and point "
            "DRJIT_LIBLLVM_PATH at it if Dr.Jit does not find it)"
            if "LLVM" in cause
            else ""
        )
        raise PtlabError(f"mitsuba cannot render with variant {variant!r} here: {cause[:160]}{hint}")
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(variant)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    return mi, dr


@dataclass
class KernelReport:
    """What Dr.Jit did for the kernels launched since the last report."""

    compiled: int = 0  # compiled now (not in memory, not in the disk cache)
    from_disk: int = 0  # loaded from Dr.Jit's disk cache (~/.drjit)
    cached: int = 0  # already in memory
    codegen_ms: float = 0.0

    def __str__(self) -> str:
        return (
            f"{self.compiled} kernels compiled, {self.from_disk} loaded from the disk cache, "
            f"{self.cached} in memory, code generation {self.codegen_ms:.0f} ms"
        )


class Mitsuba:
    """Mitsuba 3 in this process, rendering the scene file ``scene_xml``.

    Every (sampler, rr_depth) scene is loaded at once, up front: Dr.Jit's kernels depend on
    the objects alive (one more scene changes them), so a kernel compiled while warming up
    would otherwise be compiled again in a timed render.
    """

    def __init__(
        self, mi: ModuleType, dr: ModuleType, scene_xml: Path, configurations: list[tuple[str, int]]
    ):
        self.mi, self.dr, self.scene_xml = mi, dr, scene_xml
        self._scenes = {
            (sampler, depth): mi.load_file(str(scene_xml), sampler=sampler, rr_depth=depth)
            for sampler, depth in dict.fromkeys(configurations)
        }

    def render(self, sampler: str, rr_depth: int, spp: int, seed: int) -> tuple[np.ndarray, float]:
        """(H, W, 3) float32 linear RGB and the wall-clock seconds it took."""
        scene = self._scenes[sampler, rr_depth]
        start = time.perf_counter()
        image = np.array(self.mi.render(scene, spp=spp, seed=seed), dtype=np.float32)
        return image, time.perf_counter() - start

    def kernels(self) -> KernelReport:
        """The kernels launched since the last call (Dr.Jit's kernel history)."""
        report = KernelReport()
        for kernel in self.dr.kernel_history():
            if kernel["type"] != self.dr.KernelType.JIT:
                continue
            if not kernel["cache_hit"]:
                report.compiled += 1
            elif kernel["cache_disk"]:
                report.from_disk += 1
            else:
                report.cached += 1
            report.codegen_ms += kernel["codegen_time"]
        return report


# ---------------------------------------------------------------------------------------------
# What is measured


@dataclass
class Contender:
    """One renderer with one configuration: a row of the table."""

    label: str
    render: Callable[[int], tuple[np.ndarray, float]]  # seed -> image, seconds
    warm_up: Callable[[], object] | None = None
    runs: list[Run] = field(default_factory=list)


@dataclass
class Run:
    """One timed render and its errors against the reference."""

    round: int
    seed: int
    seconds: float
    relmse: float
    relmse_unlit: float
    rmse: float
    image: np.ndarray

    @property
    def cost(self) -> float:
        """seconds x relMSE: the same for any spp of an unbiased estimator."""
        return self.seconds * self.relmse


def measure(contender: Contender, round_: int, seed: int, reference: np.ndarray, unlit: np.ndarray) -> Run:
    image, seconds = contender.render(seed)
    if image.shape != reference.shape:
        raise RenderError(f"{contender.label}: the image is {image.shape}, the reference {reference.shape}")
    errors = relative_squared_error(image, reference)
    run = Run(
        round_,
        seed,
        seconds,
        float(errors.mean()),
        float(errors[unlit].mean()),
        rmse(image, reference),
        image,
    )
    contender.runs.append(run)
    return run


def run_command(command: list[str], label: str) -> float:
    """Run ``command`` to the end; its wall-clock seconds. Raises ``RenderError``."""
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        lines = [line for line in (done.stderr + done.stdout).splitlines() if line.strip()]
        raise RenderError(
            f"{label} failed (exit code {done.returncode}): {lines[-1] if lines else 'no output'}"
        )
    return seconds


def command_contender(label: str, command: Callable[[int, Path], list[str]], output: Path) -> Contender:
    """A whole process that writes ``output`` (an EXR), timed from start to exit."""

    def render(seed: int) -> tuple[np.ndarray, float]:
        seconds = run_command(command(seed, output), label)
        return read_image(output)[0], seconds

    return Contender(label, render)


def interleave(first: list, second: list) -> list:
    """Both lists in one, each spread evenly over the whole (a1 b1 a2 a3 b2 a4 ...)."""

    def place(items: list) -> list[tuple[float, object]]:
        return [((k + 0.5) / len(items), item) for k, item in enumerate(items)]

    return [item for _, item in sorted(place(first) + place(second), key=lambda p: p[0])]


# ---------------------------------------------------------------------------------------------
# The reference


def mitsuba_reference(
    mitsuba: Mitsuba,
    scene: Scene,
    res: tuple[int, int],
    spp: int,
    seed: int,
    cache_dir: Path,
    echo: Callable[[str], None],
) -> tuple[np.ndarray, int]:
    """An ``spp``-sample Mitsuba render (independent sampler), from the cache if it is there."""
    mi = mitsuba.mi
    identity = (
        mi.__version__,
        mi.variant(),
        scene_digest(scene),
        res,
        spp,
        seed,
        MITSUBA_RR_DEPTH,
        "independent",
        REFERENCE_PASS_SPP,
    )
    key = hashlib.sha256(repr(identity).encode()).hexdigest()[:16]
    cached = cache_dir / f"mitsuba-{scene.name}-{key}.exr"
    if cached.is_file():
        echo(f"reference: {cached} (cached)")
        return read_image(cached)[0], spp
    passes = [min(REFERENCE_PASS_SPP, spp - done) for done in range(0, spp, REFERENCE_PASS_SPP)]
    echo(f"reference: rendering {spp} spp with Mitsuba in {len(passes)} passes ...")
    total, seconds = np.zeros((res[1], res[0], 3)), 0.0
    for k, pass_spp in enumerate(passes):
        image, took = mitsuba.render(
            "independent", MITSUBA_RR_DEPTH, pass_spp, seed + REFERENCE_SEED_OFFSET + k
        )
        total += image.astype(np.float64) * pass_spp
        seconds += took
        if (k + 1) % 4 == 0 or k + 1 == len(passes):
            echo(f"reference: {k + 1}/{len(passes)} passes, {seconds:.0f} s")
    reference = (total / spp).astype(np.float32)
    cached.parent.mkdir(parents=True, exist_ok=True)
    write_image(
        cached,
        reference,
        dict(spp=spp, renderer=f"mitsuba {mi.__version__}", variant=mi.variant(), seconds=seconds),
    )
    echo(f"reference: wrote {cached}")
    return reference, spp


# ---------------------------------------------------------------------------------------------
# The report


def _summary(values: list[float], digits: int = 3) -> str:
    """median [min, max] with ``digits`` significant digits."""

    def fmt(v: float) -> str:
        return f"{v:.{digits}g}"

    if len(values) == 1:
        return fmt(values[0])
    return f"{fmt(statistics.median(values))} [{fmt(min(values))}, {fmt(max(values))}]"


def table(contenders: list[Contender], baseline: Contender) -> str:
    """The Markdown table of every contender, medians and ranges over the rounds."""
    header = [
        "renderer",
        "seconds",
        "relMSE",
        "relMSE w/o light",
        "RMSE",
        "s x relMSE",
        f"speed vs {baseline.label}",
        f"efficiency vs {baseline.label}",
    ]
    rows = [header, ["---"] * len(header)]
    by_round = {run.round: run for run in baseline.runs}
    for contender in contenders:
        runs = contender.runs
        rows.append(
            [
                contender.label,
                _summary([r.seconds for r in runs]),
                _summary([r.relmse for r in runs]),
                _summary([r.relmse_unlit for r in runs]),
                _summary([r.rmse for r in runs]),
                _summary([r.cost for r in runs]),
                _summary([by_round[r.round].seconds / r.seconds for r in runs]),
                _summary([by_round[r.round].cost / r.cost for r in runs]),
            ]
        )
    legend = (
        f"median [min, max] over the rounds; speed: {baseline.label}'s seconds / this "
        f"one's, efficiency: {baseline.label}'s s x relMSE / this one's, in the same round "
        f"(above 1: better than {baseline.label})"
    )
    return "\n".join("| " + " | ".join(row) + " |" for row in rows) + "\n" + legend


def _mean_standard_error(run: Run, reference: np.ndarray, spp: int, reference_spp: int) -> np.ndarray:
    """(3,) standard error of the image mean of a ``reference_spp`` render, per channel.

    From an independent-sampler ``spp`` render: its per-pixel squared errors estimate each
    pixel's variance at ``spp``, which falls as 1 / samples.
    """
    squared = ((run.image.astype(np.float64) - reference) ** 2).reshape(-1, 3)
    return np.sqrt(squared.sum(axis=0)) / len(squared) * math.sqrt(spp / reference_spp)


def agreement(
    reference: np.ndarray,
    reference_spp: int | None,
    ptlab_reference: np.ndarray,
    ptlab_spp: int | None,
    unlit: np.ndarray,
    mitsuba_independent: Contender | None,
    ptlab_independent: Contender | None,
    spp: int,
    echo: Callable[[str], None],
) -> bool:
    """Compare ptlab's reference with the reference; echo the verdict; True if they agree
    within noise (or if there is nothing to tell the noise by)."""
    errors = relative_squared_error(ptlab_reference, reference)
    ratio = ptlab_reference.reshape(-1, 3).mean(axis=0) / reference.reshape(-1, 3).mean(axis=0)
    echo(f"ptlab's reference / the reference, mean of each channel: {', '.join(f'{r:.5f}' for r in ratio)}")
    echo(
        f"relMSE of ptlab's reference against the reference: {errors.mean():.3g} "
        f"(without the light's pixels {errors[unlit].mean():.3g})"
    )
    known = None not in (reference_spp, ptlab_spp, mitsuba_independent, ptlab_independent)
    if not known:
        echo("(no noise estimate: it needs both references' spp and the independent samplers)")
        return True
    # What their noise alone gives: each reference's relMSE is about that of its renderer's
    # independent spp-sample render times spp / its own spp (variance falls as 1 / samples;
    # a reference made with a QMC sampler is less noisy, so this is an upper estimate).
    noise = (
        statistics.median(r.relmse for r in mitsuba_independent.runs) * spp / reference_spp
        + statistics.median(r.relmse for r in ptlab_independent.runs) * spp / ptlab_spp
    )
    echo(f"relMSE that the references' noise alone gives: about {noise:.3g} or less")
    error = np.hypot(
        _mean_standard_error(mitsuba_independent.runs[-1], reference, spp, reference_spp),
        _mean_standard_error(ptlab_independent.runs[-1], reference, spp, ptlab_spp),
    )
    z = (ptlab_reference - reference).reshape(-1, 3).mean(axis=0) / error
    echo(f"difference of the means in standard errors (z), per channel: {', '.join(f'{v:+.1f}' for v in z)}")
    agree = bool(np.all(np.abs(z) < AGREEMENT_Z)) and errors.mean() < 2 * noise
    echo(
        "the references agree within noise"
        if agree
        else "the references DIFFER by more than noise: a bug in the scene translation or a renderer"
    )
    return agree


# ---------------------------------------------------------------------------------------------
# The command line


def _names(text: str, allowed: tuple[str, ...], option: str) -> list[str]:
    names = [name.strip() for name in text.split(",") if name.strip()]
    wrong = [name for name in names if name not in allowed]
    if wrong or not names:
        raise PtlabError(f"{option} {text!r}: give a comma-separated list of {', '.join(allowed)}")
    return list(dict.fromkeys(names))


def _depths(text: str) -> list[int]:
    try:
        depths = [int(part) for part in text.split(",")]
    except ValueError:
        depths = []
    if not depths or min(depths) < 0:
        raise PtlabError(f"--rr-depth {text!r}: give non-negative integers, e.g. 5,3")
    return list(dict.fromkeys(depths))


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (and still exit code 2)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--scene",
        default="cornell-box",
        help="built-in scene name or scene file, diffuse materials only (default cornell-box)",
    )
    parser.add_argument("--res", default="256", help="N (square) or WxH (default 256)")
    parser.add_argument("--spp", type=int, default=64, help="samples per pixel (default 64)")
    parser.add_argument("--repeat", type=int, default=3, help="rounds, each with its own seed (default 3)")
    parser.add_argument("--seed", type=int, default=0, help="the first round's seed (default 0)")
    parser.add_argument(
        "--samplers",
        default=",".join(MITSUBA_SAMPLERS),
        help=f"Mitsuba's samplers, of {', '.join(MITSUBA_SAMPLERS)} (default all)",
    )
    parser.add_argument(
        "--rr-depth",
        default="5,3,2",
        help="Mitsuba's Russian roulette depths (default 5,3,2: Mitsuba's "
        "default, the one that matches ptlab's default, and 2)",
    )
    parser.add_argument(
        "--ptlab-samplers",
        default=",".join(SAMPLERS),
        help=f"ptlab's samplers (default {','.join(SAMPLERS)})",
    )
    parser.add_argument(
        "--ptlab-target-error",
        type=float,
        metavar="E",
        help="also time the whole process 'ptlab render --target-error E' (e.g. the relMSE "
        "of Mitsuba's multijitter render at --spp, from a first run: the time ptlab needs "
        "to reach its error)",
    )
    parser.add_argument(
        "--ptlab-strategy",
        choices=STRATEGIES,
        default="nee",
        help="ptlab's path tracer: light sampling (nee, its default) or MIS (mis, as Mitsuba's path tracer)",
    )
    parser.add_argument(
        "--workers",
        type=int,
        help="ptlab's worker processes (default one per core); Mitsuba uses Dr.Jit's default thread count",
    )
    parser.add_argument(
        "--variant", default="llvm_ad_rgb", help="Mitsuba's variant, an RGB one (default llvm_ad_rgb)"
    )
    parser.add_argument(
        "--reference",
        metavar="FILE.exr",
        help="the reference, a linear EXR of the same resolution "
        "(default: a Mitsuba render of --reference-spp samples, cached)",
    )
    parser.add_argument(
        "--reference-spp",
        type=int,
        default=4096,
        help="samples per pixel of the Mitsuba reference (default 4096)",
    )
    parser.add_argument(
        "--ptlab-reference", metavar="FILE.exr", help="a high-spp ptlab render to check against the reference"
    )
    parser.add_argument(
        "--ptlab-reference-spp",
        type=int,
        help="its samples per pixel, for the noise estimate (default: from its metadata)",
    )
    parser.add_argument(
        "--no-process", action="store_true", help="skip the whole-process runs of ptlab render and mitsuba"
    )
    parser.add_argument(
        "--csv", metavar="FILE", help="also write every run (label, round, seed, seconds, errors)"
    )
    return parser


def check_options(args: argparse.Namespace) -> None:
    """Raise ``PtlabError`` for an option that cannot work."""
    if not 1 <= args.spp <= MAX_SPP:
        raise PtlabError(f"--spp {args.spp}: must be from 1 to {MAX_SPP}")
    if not 1 <= args.repeat <= 100:
        raise PtlabError(f"--repeat {args.repeat}: must be from 1 to 100")
    if not 1 <= args.reference_spp <= MAX_SPP:
        raise PtlabError(f"--reference-spp {args.reference_spp}: must be from 1 to {MAX_SPP}")
    if args.seed < 0:
        raise PtlabError(f"--seed {args.seed}: must be a non-negative integer")
    if args.workers is not None and args.workers < 1:
        raise PtlabError(f"--workers {args.workers}: must be at least 1")
    if "_rgb" not in args.variant:
        raise PtlabError(
            f"--variant {args.variant}: ptlab's colours are RGB; use an RGB variant such as llvm_ad_rgb"
        )
    for sampler in args.samplers:
        rule = MITSUBA_SPP_RULES.get(sampler)
        if rule and not rule[0](args.spp):
            raise PtlabError(
                f"--spp {args.spp}: Mitsuba's {sampler} sampler needs {rule[1]} "
                f"(it would round it up and render more samples)"
            )
    if args.ptlab_reference_spp is not None and args.ptlab_reference_spp < 1:
        raise PtlabError(f"--ptlab-reference-spp {args.ptlab_reference_spp}: must be positive")
    if args.csv and not Path(args.csv).resolve().parent.is_dir():
        raise PtlabError(f"--csv {args.csv}: folder {Path(args.csv).parent} does not exist")


def write_csv(path: Path, contenders: list[Contender]) -> None:
    def write(temporary: str) -> None:
        with open(temporary, "w", newline="") as out:
            rows = csv.writer(out)
            rows.writerow(["renderer", "round", "seed", "seconds", "relmse", "relmse_unlit", "rmse"])
            for contender in contenders:
                for r in contender.runs:
                    rows.writerow(
                        [
                            contender.label,
                            r.round,
                            r.seed,
                            f"{r.seconds:.4f}",
                            f"{r.relmse:.6g}",
                            f"{r.relmse_unlit:.6g}",
                            f"{r.rmse:.6g}",
                        ]
                    )

    write_atomically(path, write)


def _executable(name: str) -> str | None:
    """The command ``name`` installed beside this Python, else on the PATH."""
    beside = Path(sys.executable).with_name(name)
    return str(beside) if beside.is_file() else shutil.which(name)


def _load_average() -> str:
    return ", ".join(f"{v:.2f}" for v in os.getloadavg())


def mitsuba_contenders(mitsuba: Mitsuba, args: argparse.Namespace) -> list[Contender]:
    """Mitsuba with every sampler and Russian roulette depth, in this process."""

    def contender(sampler: str, depth: int) -> Contender:
        return Contender(
            f"mitsuba {sampler} rr_depth {depth}",
            lambda seed: mitsuba.render(sampler, depth, args.spp, seed),
            lambda: mitsuba.render(sampler, depth, args.spp, WARM_UP_SEED),
        )

    return [contender(sampler, depth) for depth in args.rr_depth for sampler in args.samplers]


def ptlab_contenders(scene: Scene, args: argparse.Namespace) -> list[Contender]:
    """ptlab with every sampler, in this process (its workers are processes of their own)."""
    options = dict(
        spp=args.spp, res=parse_resolution(args.res), workers=args.workers, strategy=args.ptlab_strategy
    )

    def contender(sampler: str) -> Contender:
        def render(seed: int) -> tuple[np.ndarray, float]:
            start = time.perf_counter()
            image = render_result(scene, seed=seed, sampler=sampler, **options).image
            return image, time.perf_counter() - start

        return Contender(
            f"ptlab {sampler} {args.ptlab_strategy}",
            render,
            lambda: render_result(scene, seed=WARM_UP_SEED, sampler=sampler, **dict(options, spp=1)),
        )

    return [contender(sampler) for sampler in args.ptlab_samplers]


def warm_up(contenders: list[Contender], mitsuba: Mitsuba, echo: Callable[[str], None]) -> None:
    """One untimed render of each contender that has a warm-up; say what Dr.Jit compiled."""
    for contender in contenders:
        if contender.warm_up is None:
            continue
        mitsuba.kernels()
        start = time.perf_counter()
        contender.warm_up()
        seconds = time.perf_counter() - start
        kernels = mitsuba.kernels()
        echo(
            f"warm-up {contender.label}: {seconds:.1f} s"
            + (f"; {kernels}" if kernels.compiled + kernels.from_disk + kernels.cached else "")
        )


def run_rounds(
    order: list[Contender],
    args: argparse.Namespace,
    reference: np.ndarray,
    unlit: np.ndarray,
    echo: Callable[[str], None],
) -> None:
    """Every contender once per round, a new seed each round, every other round backwards."""
    for round_ in range(args.repeat):
        seed = args.seed + round_
        for contender in order if round_ % 2 == 0 else order[::-1]:
            run = measure(contender, round_, seed, reference, unlit)
            echo(
                f"round {round_ + 1}/{args.repeat}  {contender.label:42} {run.seconds:7.2f} s  "
                f"relMSE {run.relmse:.4g}"
            )


def compare(args: argparse.Namespace, folder: Path, echo: Callable[[str], None]) -> int:
    """The whole comparison; 0 if it ran (and the references agree, when there are two)."""
    scene = load_scene(args.scene)
    width, height = res = parse_resolution(args.res)
    reference = load_reference(args.reference, res) if args.reference else None
    ptlab_reference = load_reference(args.ptlab_reference, res) if args.ptlab_reference else None
    mi, dr = import_mitsuba(args.variant)
    configurations = [(sampler, depth) for depth in args.rr_depth for sampler in args.samplers]
    mitsuba = Mitsuba(
        mi,
        dr,
        write_mitsuba_scene(scene, folder, width, height),
        [*configurations, ("independent", MITSUBA_RR_DEPTH)],
    )
    echo(f"{scene.summary()}; {width}x{height}, {args.spp} spp, {args.repeat} rounds")
    echo(
        f"mitsuba {mi.__version__} ({args.variant}, {dr.thread_count()} threads), ptlab with "
        f"{args.workers or 'one per core'} workers; load average {_load_average()} "
        f"on {os.cpu_count()} cores"
    )
    if reference is None:
        reference, reference_spp = mitsuba_reference(
            mitsuba, scene, res, args.reference_spp, args.seed, default_cache_dir(), echo
        )
    else:
        reference_spp = _spp_from_metadata(args.reference)
    unlit = reference.max(axis=-1) <= LIGHT_THRESHOLD
    echo(f"{(~unlit).sum()} of {unlit.size} pixels see the light")

    mitsuba_runs, ptlab_runs = mitsuba_contenders(mitsuba, args), ptlab_contenders(scene, args)
    ptlab_process, mitsuba_process = (
        ([], []) if args.no_process else process_contenders(args, mitsuba.scene_xml, folder, echo)
    )
    warm_up(mitsuba_runs + ptlab_runs, mitsuba, echo)
    run_rounds(
        interleave(mitsuba_runs + mitsuba_process, ptlab_runs + ptlab_process), args, reference, unlit, echo
    )
    echo(f"timed Mitsuba renders in this process: {mitsuba.kernels()}")
    echo(f"load average after: {_load_average()}")

    contenders = mitsuba_runs + ptlab_runs + ptlab_process + mitsuba_process
    baseline = next((c for c in ptlab_runs if c.label.startswith(f"ptlab {DEFAULT_SAMPLER} ")), ptlab_runs[0])
    echo(f"\n{table(contenders, baseline)}\n")
    if args.csv:
        write_csv(Path(args.csv), contenders)
        echo(f"wrote {Path(args.csv).resolve()}")
    if ptlab_reference is None:
        return 0

    def independent(runs: list[Contender], renderer: str) -> Contender | None:
        return next((c for c in runs if c.label.startswith(f"{renderer} independent ")), None)

    agree = agreement(
        reference,
        reference_spp,
        ptlab_reference,
        args.ptlab_reference_spp or _spp_from_metadata(args.ptlab_reference),
        unlit,
        independent(mitsuba_runs, "mitsuba"),
        independent(ptlab_runs, "ptlab"),
        args.spp,
        echo,
    )
    return 0 if agree else 1


def _spp_from_metadata(path: str) -> int | None:
    spp = read_image(path)[1].get("spp")
    return int(spp) if spp is not None else None


def process_contenders(
    args: argparse.Namespace, scene_xml: Path, folder: Path, echo: Callable[[str], None]
) -> tuple[list[Contender], list[Contender]]:
    """``ptlab render`` (its default sampler) and ``mitsuba`` (the scene file's defaults:
    sampler independent, rr_depth 5) as whole processes."""
    ptlab_command = _executable("ptlab")
    if ptlab_command is None:
        raise PtlabError("the ptlab command is not installed: pip install -e . from the repository")
    workers = [] if args.workers is None else ["--workers", str(args.workers)]

    def ptlab_render(seed: int, out: Path) -> list[str]:
        return [
            ptlab_command,
            "render",
            args.scene,
            "--res",
            args.res,
            "--spp",
            str(args.spp),
            "--seed",
            str(seed),
            "--strategy",
            args.ptlab_strategy,
            "--quiet",
            "--out",
            str(out),
            *workers,
        ]

    ptlab = command_contender(
        f"ptlab render {DEFAULT_SAMPLER} {args.ptlab_strategy} [process]", ptlab_render, folder / "ptlab.exr"
    )
    contenders = [ptlab]
    if args.ptlab_target_error is not None:
        # (the same command, to a noise target instead of a number of samples)
        target = args.ptlab_target_error

        def to_target(seed: int, out: Path) -> list[str]:
            command = ptlab_render(seed, out)
            at = command.index("--spp")  # (its first pass: the default)
            return [*command[:at], "--target-error", str(target), *command[at + 2 :]]

        contenders.append(
            command_contender(
                f"ptlab render {DEFAULT_SAMPLER} {args.ptlab_strategy} to {target:g} [process]",
                to_target,
                folder / "ptlab-target.exr",
            )
        )
    mitsuba_command = _executable("mitsuba")
    if mitsuba_command is None:
        echo("no mitsuba command beside this Python or on the PATH: its process is not timed")
        return contenders, []
    mitsuba = command_contender(
        f"mitsuba independent rr_depth {MITSUBA_RR_DEPTH} [process]",
        lambda seed, out: [
            mitsuba_command,
            "-m",
            args.variant,
            "-o",
            str(out),
            "-D",
            f"spp={args.spp}",
            "-D",
            f"seed={seed}",
            str(scene_xml),
        ],
        folder / "mitsuba.exr",
    )
    return contenders, [mitsuba]


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    echo = lambda line: print(line, flush=True)  # noqa: E731
    try:
        args.samplers = _names(args.samplers, MITSUBA_SAMPLERS, "--samplers")
        args.ptlab_samplers = _names(args.ptlab_samplers, SAMPLERS, "--ptlab-samplers")
        args.rr_depth = _depths(args.rr_depth)
        check_options(args)
        with tempfile.TemporaryDirectory(prefix="against-mitsuba-") as folder:
            return compare(args, Path(folder), echo)
    except PtlabError as error:
        print(f"{PROG}: error: {error}", file=sys.stderr)
        return 2
    except RenderError as error:
        print(f"{PROG}: error: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
