"""Meshes at scale: how reading an OBJ file, building the NumPy BVH and rendering grow with
the number of triangles (not run in CI; it takes a few minutes).

    python scripts/mesh_scale.py                      # icospheres of 20k to 1.3M triangles
    python scripts/mesh_scale.py --subdivisions 5 6   # only some sizes
    python scripts/mesh_scale.py --repeat 5 --folder /tmp/meshes

For each size it writes a trimesh icosphere (subdivisions 5 to 8: 20 480 to 1 310 720
triangles) as an OBJ file, and a scene file that puts it in the Cornell box under its light
(the two boxes left out), then measures, each in processes of its own and the two sides of
every comparison alternately, ``--repeat`` times:

* reading: ``ptlab.load_scene`` of the scene file (the Cornell box's walls and light too, and
  the scene's own checks) against ``trimesh.load`` of the OBJ file as a user calls it (its
  default processing included), alternately in one process after one of each; and
  ``ptlab.meshes.read_mesh_triangles`` of the OBJ file alone against ``trimesh.load`` of it
  without processing, each in a process of its own (seconds, imports excluded);
* the NumPy BVH: ``NumpyBVH(scene.triangles)``'s seconds, and the peak of memory that
  tracemalloc sees during a second build, per triangle;
* the render: ``ptlab render SCENE --res 128 --spp 4 --workers 1`` with ``--backend embree``
  and ``--backend numpy``, as whole processes (``/usr/bin/time -f "%e %M"``: wall seconds
  and peak resident memory).

It prints every run, then a Markdown table of medians, with ranges where runs differ, for
docs/performance.md; the ratios are medians of the runs' own ratios.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CORNELL = ROOT / "scenes" / "cornell-box"

#: Run in a process of its own: the seconds of ptlab.load_scene(argv[1]) and of
#: trimesh.load(argv[2]), alternately, argv[3] times each (after one of each: both import
#: more of themselves on their first file).
LOAD_SCENE_AGAINST_TRIMESH = """
import sys, time
import ptlab, trimesh
scene, obj, rounds = sys.argv[1], sys.argv[2], int(sys.argv[3])
ptlab.load_scene(scene)
trimesh.load(obj)
for _ in range(rounds):
    start = time.perf_counter()
    ptlab.load_scene(scene)
    middle = time.perf_counter()
    trimesh.load(obj)
    print(middle - start, time.perf_counter() - middle)
"""
#: The seconds of ptlab's OBJ reader alone, read_mesh_triangles(argv[1]).
READ_MESH = """
import sys, time
from ptlab.meshes import read_mesh_triangles
start = time.perf_counter()
read_mesh_triangles(sys.argv[1])
print(time.perf_counter() - start)
"""
#: The seconds of trimesh.load(argv[1]) without processing, as ptlab read OBJ files before it
#: read them itself.
TRIMESH_LOAD = """
import sys, time
import trimesh
start = time.perf_counter()
trimesh.load(sys.argv[1], force="mesh", process=False)
print(time.perf_counter() - start)
"""
#: The seconds of a NumpyBVH's construction, and the peak bytes a triangle of another's.
BUILD = """
import sys, time, tracemalloc
import ptlab
from ptlab.accel.numpy_bvh import NumpyBVH
triangles = ptlab.load_scene(sys.argv[1]).triangles
start = time.perf_counter()
NumpyBVH(triangles)
seconds = time.perf_counter() - start
tracemalloc.start()
NumpyBVH(triangles)
print(seconds, tracemalloc.get_traced_memory()[1] / len(triangles))
"""


def write_scene(folder: Path, subdivisions: int) -> tuple[Path, Path, int]:
    """The icosphere's OBJ file, the scene file around it, and its number of triangles."""
    import trimesh

    obj = folder / f"sphere{subdivisions}.obj"
    sphere = trimesh.creation.icosphere(subdivisions=subdivisions, radius=120)
    sphere.apply_translation([278, 130, 280])
    if not obj.exists():
        sphere.export(obj)
    lines = (CORNELL / "scene.toml").read_text().replace('"meshes/', f'"{CORNELL}/meshes/')
    for box in ("shortbox", "tallbox"):
        lines = lines.replace(f'[[mesh]]\nfile = "{CORNELL}/meshes/{box}.obj"\nmaterial = "white"\n\n', "")
    scene = folder / f"sphere{subdivisions}.toml"
    scene.write_text(lines + f'\n[[mesh]]\nfile = "{obj.name}"\nmaterial = "white"\n')
    return obj, scene, len(sphere.faces)


def python(code: str, *args: str) -> list[float]:
    """The numbers a Python snippet prints, run in a fresh interpreter."""
    out = subprocess.run(
        [sys.executable, "-c", code, *args], check=True, text=True, capture_output=True
    ).stdout
    return [float(x) for x in out.split()]


def render(scene: Path, backend: str, folder: Path) -> tuple[float, float]:
    """Wall seconds and peak resident MB of a whole ``ptlab render`` process."""
    command = [
        "/usr/bin/time",
        "-f",
        "%e %M",
        sys.executable,
        "-c",
        "import sys; from ptlab.cli import main; sys.exit(main(sys.argv[1:]))",
        "render",
        str(scene),
        "--res",
        "128",
        "--spp",
        "4",
        "--workers",
        "1",
        "--backend",
        backend,
        "--out",
        str(folder / f"{scene.stem}-{backend}.exr"),
        "--quiet",
    ]
    err = subprocess.run(command, check=True, text=True, capture_output=True).stderr
    seconds, kilobytes = err.split()[-2:]
    return float(seconds), float(kilobytes) / 1024


def spread(values: list[float], digits: int = 1) -> str:
    """The median, and the range where the runs differ at that precision."""
    low, mid, high = (round(v, digits) for v in (min(values), statistics.median(values), max(values)))
    return f"{mid:.{digits}f}" if low == high else f"{mid:.{digits}f} ({low:.{digits}f}-{high:.{digits}f})"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--subdivisions",
        type=int,
        nargs="+",
        default=[5, 6, 7, 8],
        help="icosphere subdivisions to measure (default 5 6 7 8)",
    )
    parser.add_argument("--repeat", type=int, default=3, help="runs of each (default 3)")
    parser.add_argument(
        "--folder",
        type=Path,
        default=None,
        help="where to write the meshes and scenes (default: a temporary one)",
    )
    args = parser.parse_args()
    folder = args.folder or Path(tempfile.mkdtemp(prefix="ptlab-mesh-scale-"))
    folder.mkdir(parents=True, exist_ok=True)

    cold = []
    for _ in range(args.repeat):
        err = subprocess.run(
            [
                "/usr/bin/time",
                "-f",
                "%e",
                sys.executable,
                "-c",
                "import ptlab; ptlab.load_scene('cornell-box')",
            ],
            check=True,
            text=True,
            capture_output=True,
        ).stderr
        cold.append(float(err.split()[-1]))
    print(f"cold start, import ptlab + load_scene('cornell-box'): {spread(cold, 2)} s", flush=True)

    rows = []
    for subdivisions in args.subdivisions:
        obj, scene, count = write_scene(folder, subdivisions)
        runs: dict[str, list[float]] = {}
        pairs = python(LOAD_SCENE_AGAINST_TRIMESH, str(scene), str(obj), str(args.repeat))
        runs["load_scene"], runs["trimesh.load(path)"] = pairs[0::2], pairs[1::2]
        load = [p / t for p, t in zip(runs["load_scene"], runs["trimesh.load(path)"], strict=True)]
        print(
            f"{count:8d} triangles  load_scene {runs['load_scene']}, trimesh.load(path) "
            f"{runs['trimesh.load(path)']}: load_scene / trimesh.load {spread(load, 2)}",
            flush=True,
        )
        for _ in range(args.repeat):
            for name, values in (
                ("read_mesh", python(READ_MESH, str(obj))),
                ("trimesh raw", python(TRIMESH_LOAD, str(obj))),
                ("build", python(BUILD, str(scene))),
                ("embree", render(scene, "embree", folder)),
                ("numpy", render(scene, "numpy", folder)),
            ):
                print(f"{count:8d} triangles  {name:12s} {values}", flush=True)
                if name == "build":
                    runs.setdefault("build s", []).append(values[0])
                    runs.setdefault("build B/tri", []).append(values[1])
                elif name in ("embree", "numpy"):
                    runs.setdefault(f"{name} s", []).append(values[0])
                    runs.setdefault(f"{name} MB", []).append(values[1])
                else:
                    runs.setdefault(name, []).append(values[0])
        ratio = [n / e for n, e in zip(runs["numpy s"], runs["embree s"], strict=True)]
        read = [p / t for p, t in zip(runs["read_mesh"], runs["trimesh raw"], strict=True)]
        rows.append(
            f"| {count:,} | {spread(runs['load_scene'], 2)} | {spread(runs['trimesh.load(path)'], 2)} "
            f"| {spread(load, 2)} | {spread(runs['read_mesh'], 2)} "
            f"| {spread(runs['trimesh raw'], 2)} | {spread(read, 2)} "
            f"| {spread(runs['build s'], 2)} "
            f"| {spread(runs['build B/tri'], 0)} | {spread(runs['embree s'])} "
            f"| {spread(runs['numpy s'])} | {spread(ratio, 2)} "
            f"| {spread(runs['embree MB'], 0)} / {spread(runs['numpy MB'], 0)} "
            f"| {spread([m * 2**20 / count for m in runs['numpy MB']], 0)} |"
        )
    print(
        "\n| triangles | load_scene s | trimesh.load(path) s | load_scene / trimesh.load "
        "| read_mesh s | trimesh.load, no processing s | read_mesh / trimesh "
        "| NumPy BVH build s "
        "| build peak B/tri | render embree s | render numpy s | numpy / embree "
        "| render peak MB, embree / numpy | numpy peak B/tri |"
    )
    print("|" + " --- |" * 14)
    print("\n".join(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
