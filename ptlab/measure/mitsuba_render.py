"""Mitsuba 3 in this process: rendering a scene file that ``mitsuba_export`` wrote, timed.

Mitsuba is not a dependency of ptlab (``pip install mitsuba``); this module imports without it
and ``import_mitsuba`` says in one line what is missing. Its ``llvm_ad_rgb`` variant also needs
a libLLVM recent enough for Dr.Jit (e.g. Debian's ``libllvm19``); a Dr.Jit built for a newer
LLVM than the machine's aborts the process while compiling (``LLVM ERROR: Cannot select``),
which Python cannot catch, so Mitsuba is first tried in a child process with a tiny render.

Dr.Jit compiles a kernel the first time a render needs it, which ``MitsubaRenderer.kernels``
reports (Dr.Jit's kernel history), so that a timed render can be told from one that compiled.
"""

from __future__ import annotations

import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numpy as np

from ptlab.errors import PtlabError

#: What to install when Mitsuba is missing.
INSTALL_HINT = "pip install mitsuba (it is not a dependency of ptlab)"
#: Renders an 8x8 Cornell box (Mitsuba's own) in a child process with the variant given as its
#: argument; what it finds wrong it prints as one line to stdout, exit code 1.
PROBE = f"""
import sys
try:
    import mitsuba as mi
except ImportError as error:
    sys.exit(print(f"cannot import mitsuba ({{error}}): {INSTALL_HINT}") or 1)
if sys.argv[1] not in mi.variants():
    sys.exit(print(f"mitsuba {{mi.__version__}} has no variant {{sys.argv[1]!r}} "
                   f"(it has {{', '.join(mi.variants())}})") or 1)
import numpy as np
mi.set_variant(sys.argv[1])
scene = mi.cornell_box()
scene["sensor"]["film"].update(width=8, height=8)
np.asarray(mi.render(mi.load_dict(scene), spp=1))
"""


def import_mitsuba(variant: str) -> tuple[ModuleType, ModuleType]:
    """``mitsuba`` and ``drjit`` with ``variant`` set, once a child process has rendered with it.

    Raises ``PtlabError`` (one line) if Mitsuba is missing or cannot render with the variant.
    """
    probe = subprocess.run([sys.executable, "-c", PROBE, variant], capture_output=True, text=True)
    if probe.returncode != 0:
        raise PtlabError(_probe_failure(probe, variant))
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(variant)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    return mi, dr


def _probe_failure(probe: subprocess.CompletedProcess[str], variant: str) -> str:
    """One line on why the probe failed: what it printed, else the first error in its stderr
    (an abort prints no Python error), with a hint when it is LLVM's."""
    if probe.stdout.strip():
        return probe.stdout.strip().splitlines()[-1]
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
    return f"mitsuba cannot render with variant {variant!r} here: {cause[:160]}{hint}"


@dataclass
class KernelReport:
    """What Dr.Jit did for the kernels launched since the last report.

    Attributes:
        compiled: kernels compiled now (in neither memory nor the disk cache).
        from_disk: kernels loaded from Dr.Jit's disk cache (``~/.drjit``).
        cached: kernels already in memory.
        codegen_ms: milliseconds of code generation, all of them together.
    """

    compiled: int = 0
    from_disk: int = 0
    cached: int = 0
    codegen_ms: float = 0.0

    def __str__(self) -> str:
        return (
            f"{self.compiled} kernels compiled, {self.from_disk} loaded from the disk cache, "
            f"{self.cached} in memory, code generation {self.codegen_ms:.0f} ms"
        )

    @property
    def launched(self) -> int:
        """Every kernel launched, however it was found."""
        return self.compiled + self.from_disk + self.cached


class MitsubaRenderer:
    """Mitsuba 3 in this process, rendering the scene file ``scene_xml``.

    Every (sampler, rr_depth) scene is loaded at once, up front: Dr.Jit's kernels depend on
    the objects alive (one more scene changes them), so a kernel compiled while warming up
    would otherwise be compiled again in a timed render.

    Args:
        mi, dr: ``mitsuba`` and ``drjit``, from ``import_mitsuba``.
        scene_xml: a scene file that takes ``$sampler`` and ``$rr_depth``
            (``mitsuba_export.write_mitsuba_scene``).
        configurations: every (sampler, rr_depth) that ``render`` will be asked for.
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
        """(H, W, 3) float32 linear RGB and the wall-clock seconds it took: ``mi.render`` and the
        conversion to NumPy, which waits for the kernel."""
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
