"""The denoiser and its error estimate, measured against references (issue 40).

Not run in CI (about 10 minutes at ``nice -n 10`` once the references are cached; rendering
them first takes about as long again). Per scene (cornell-box 256x256, veach-mis 128x128 with
MIS, cornell-box-glossy 256x256, games101-hw5 with its glass sphere 256x256), per spp (4, 16,
64) and seed, it prints:

* the true relMSE of the noisy image, of the denoised image (``ptlab.denoise.denoise``: the
  mean of the two halves' denoised images, light seen directly kept out), of the same with the
  direct light given to the denoiser ("plain"), and of the whole image denoised in one run
  ("whole": a preview's image), each as a ratio to the denoised image's;
* each estimator's value over the truth: the "variance part" (the halves' denoised images
  compared with each other), cross-validation (``ptlab.denoise.estimate``) with the true
  brightness in relMSE's denominator (what its numerator alone is worth) and with the
  stand-in it must use, and Stein's unbiased risk estimate for the whole image denoised in
  one run, with a Monte Carlo divergence (Ramani, Blu and Unser 2008) and the true
  denominator; then the estimate's standard error, the estimate with the alternative
  brightness over it ("alt.") and its verdict;
* OIDN's seconds for the denoised image and its estimate (prefilter and two runs).

Then what the options buy (features, prefiltering, quality) at 16 spp, and the denoiser's
seconds per megapixel on 1 and 2 threads, alternating, several runs, median and spread.

The truth is the relMSE against a reference: the mean of two ``path:mis`` renders of other
seeds (``ptlab.measure.converge.reference_image``, cached), whose own noise, estimated from
their difference, is printed and taken off each measured relMSE.

The inputs are a denoised render's (``render_result(..., denoise=True)``: its film after the
last pass, as ``ptlab.rendering.denoising`` reads it). With ``--interim`` they are built from
separate renders, as before the renderer gathered them: the two halves are renders of spp / 2
with seeds s and s + 1000, their directly seen light ``max_depth=0`` renders of the same seeds
(what camera rays see: mirrors and glass are not followed), and the features the ``albedo``
and ``normals`` debug views.

    nice -n 10 python scripts/denoise_study.py
    nice -n 10 python scripts/denoise_study.py --scenes veach-mis --seeds 0,1,2,3
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

import ptlab
from ptlab.denoise import DenoiseInputs, denoise
from ptlab.denoise.estimate import squared_error
from ptlab.denoise.oidn import denoise_colour, prefilter
from ptlab.measure.converge import default_cache_dir, reference_image
from ptlab.measure.metrics import RELMSE_EPSILON

#: Scene -> (resolution, render options).
SCENES = {
    "cornell-box": ((256, 256), {}),
    "veach-mis": ((128, 128), {"strategy": "mis"}),
    "cornell-box-glossy": ((256, 256), {}),
    "games101-hw5": ((256, 256), {}),
}
#: The second half's seed is the first's plus this.
HALF_SEED_OFFSET = 1000
#: Samples per pixel of each of the two reference renders, by scene (default 2048).
REFERENCE_SPP = {"veach-mis": 4096}

_made: dict[tuple[str, int, int], DenoiseInputs] = {}
#: Whether ``study_inputs`` builds the inputs from separate renders (``--interim``).
INTERIM = False


def study_inputs(
    scene: ptlab.Scene, res: tuple[int, int], spp: int, seed: int, options: dict
) -> DenoiseInputs:
    """The denoiser's inputs for one render (module docstring), made once."""
    key = (scene.name, spp, seed)
    if key not in _made:
        make = interim_inputs if INTERIM else render_inputs
        _made[key] = make(scene, res, spp, seed, options)
    return _made[key]


def render_inputs(
    scene: ptlab.Scene, res: tuple[int, int], spp: int, seed: int, options: dict
) -> DenoiseInputs:
    """What a denoised render gives the denoiser: its film after the last pass, read as
    ``ptlab.rendering.denoising`` reads it."""
    from ptlab.rendering.denoising import film_inputs

    films: list = []
    ptlab.render_result(scene, res=res, spp=spp, seed=seed, denoise=True, on_pass=films.append, **options)
    inputs, why_not = film_inputs(films[-1])
    assert not why_not, why_not
    return inputs


def interim_inputs(
    scene: ptlab.Scene, res: tuple[int, int], spp: int, seed: int, options: dict
) -> DenoiseInputs:
    """The denoiser's inputs built from separate renders (module docstring)."""

    def image(**extra) -> np.ndarray:
        return np.asarray(ptlab.render_result(scene, res=res, **{**options, **extra}).image, np.float64)

    def feature(view: str) -> np.ndarray:
        return np.asarray(
            ptlab.render_result(scene, res=res, spp=spp, seed=seed, integrator=view).image, np.float64
        )

    seeds = (seed, seed + HALF_SEED_OFFSET)
    half_a, half_b = (image(spp=spp // 2, seed=s) for s in seeds)
    direct_a, direct_b = (image(spp=spp // 2, seed=s, max_depth=0) for s in seeds)
    shown = feature("normals")  # (n + 1) / 2 where a ray hit, 0 where it escaped
    hit = (shown > 0).any(axis=-1, keepdims=True)
    normal = np.where(hit, 2 * shown - 1, 0.0)
    return DenoiseInputs(half_a, half_b, direct_a, direct_b, np.clip(feature("albedo"), 0, 1), normal)


def _quiet(line: str) -> None:
    """Says nothing (``reference_image``'s messages)."""


def reference(scene: ptlab.Scene, res: tuple[int, int], say: bool = True) -> tuple[np.ndarray, float]:
    """The mean of two cached references and its own relMSE, estimated from their difference."""
    spp = REFERENCE_SPP.get(scene.name, 2048)
    first, second = (
        np.asarray(
            reference_image(scene, res, spp, seed, default_cache_dir(), _quiet, quiet=True), np.float64
        )
        for seed in (0, 1)
    )
    mean = (first + second) / 2
    own = float(np.mean((first - second) ** 2 / 4 / (mean + RELMSE_EPSILON) ** 2))
    if say:
        print(f"  reference: 2 x {spp} spp path:mis, its own relMSE about {own:.1e} (taken off each truth)")
    return mean, own


def relmse_against(image: np.ndarray, truth: np.ndarray, own: float) -> float:
    """relMSE of ``image`` against the reference ``truth``, less the reference's own."""
    return float(np.mean((image - truth) ** 2 / (truth + RELMSE_EPSILON) ** 2)) - own


def sure(inputs: DenoiseInputs, truth: np.ndarray, seed: int) -> float:
    """Stein's unbiased risk estimate of the whole image denoised in one run (light seen
    directly kept out), with a Monte Carlo divergence (one more run, the colour moved by
    ``EPSILON`` of each pixel's standard deviation in random directions), per-pixel
    variances from the halves, and the true denominator."""
    epsilon = 0.05
    albedo, normal = prefilter(inputs.albedo, inputs.normal)
    direct = inputs.direct
    colour = np.maximum(inputs.image - direct, 0.0)
    sigma = np.abs((inputs.half_a - inputs.direct_a) - (inputs.half_b - inputs.direct_b)) / 2
    signs = np.random.default_rng(seed).choice([-1.0, 1.0], size=colour.shape)

    def run(image: np.ndarray) -> np.ndarray:
        return np.asarray(
            denoise_colour(np.maximum(image, 0.0), albedo, normal, features="clean"), np.float64
        )

    out = run(colour)
    divergence = signs * (run(colour + epsilon * sigma * signs) - out) * sigma / epsilon
    risk = (out - colour) ** 2 - sigma**2 + 2 * divergence
    return float(np.mean(risk / (truth + RELMSE_EPSILON) ** 2))


#: A refusal's reason (``ptlab.denoise.estimate``) -> its column in the table.
VERDICTS = (
    ("not positive", "refused: not positive"),
    ("brightness", "refused: brightness"),
    ("too far", "refused: too large"),
    ("standard error", "refused: s.e."),
)


def measure(scene_name: str, spps: list[int], seeds: list[int]) -> list[tuple[float, float | None]]:
    """Print the table for one scene; return (truth, estimate or None) per row."""
    res, options = SCENES[scene_name]
    scene = ptlab.load_scene(scene_name)
    print(f"\n{scene_name} {res[0]}x{res[1]} {options or ''}")
    truth, own = reference(scene, res)
    print(
        "   spp seed   noisy  denoised  plain whole |  var    CV(R)  SURE(R) | estimate  s.e.  alt.   verdict"
        "                OIDN s"
    )
    verdicts = []
    for spp in spps:
        for seed in seeds:
            inputs = study_inputs(scene, res, spp, seed, options)
            result = denoise(inputs)
            assert result.halves is not None
            assert result.estimate is not None
            plain = denoise(inputs, keep_direct=False)
            whole = denoise(inputs, estimate=False)
            true = relmse_against(result.image, truth, own)
            weights = (truth + RELMSE_EPSILON) ** 2
            half_a, half_b = result.halves
            variance_part = float(np.mean((half_a - half_b.astype(np.float64)) ** 2 / 4 / weights))
            cross_validation = float(np.mean(squared_error(inputs, half_a, half_b) / weights))
            estimate = result.estimate
            verdict = "trusted"
            if estimate.reason is not None:
                verdict = next(short for word, short in VERDICTS if word in estimate.reason)
            print(
                f"  {spp:4d} {seed:4d} {relmse_against(inputs.image, truth, own):7.4f} {true:9.5f} "
                f"{relmse_against(plain.image, truth, own) / true:6.2f} "
                f"{relmse_against(whole.image, truth, own) / true:5.2f} | "
                f"{variance_part / true:5.2f} {cross_validation / true:6.2f} "
                f"{sure(inputs, truth, seed) / relmse_against(whole.image, truth, own):7.2f} | "
                f"{estimate.value / true:8.2f} {estimate.standard_error:5.2f} "
                f"{estimate.alternative / estimate.value:6.2f}  "
                f"{verdict:22} {result.seconds:5.2f}"
            )
            verdicts.append((estimate.value / true, estimate.relmse))
    return verdicts


#: The options ``options_table`` compares: (features, quality); the first is the default.
CHOICES = (
    ("prefilter", "balanced"),
    ("prefilter", "high"),
    ("prefilter", "fast"),
    ("noisy", "balanced"),
    ("none", "balanced"),
)


def options_table(spps: list[int], seed: int) -> None:
    """What the features, their prefiltering and OIDN's quality buy: each choice's relMSE
    over the default's, and its seconds (denoised image and estimate), per scene and spp."""
    print("  relMSE / the default's (seconds), features/quality:")
    print("  " + " " * 24 + "".join(f"{features}/{quality:>9}".rjust(20) for features, quality in CHOICES))
    ratios: dict[tuple[str, str], list[float]] = {choice: [] for choice in CHOICES}
    for scene_name, (res, options) in SCENES.items():
        scene = ptlab.load_scene(scene_name)
        truth, own = reference(scene, res, say=False)
        for spp in spps:
            inputs = study_inputs(scene, res, spp, seed, options)
            cells = []
            errors = {}
            for features, quality in CHOICES:
                result = denoise(inputs, features=features, quality=quality)
                errors[features, quality] = relmse_against(result.image, truth, own)
                ratio = errors[features, quality] / errors[CHOICES[0]]
                ratios[features, quality].append(ratio)
                cells.append(f"{ratio:6.2f} ({result.seconds:5.2f} s)")
            print(f"  {scene_name:18} {spp:4d} spp" + "".join(cell.rjust(20) for cell in cells))
    print("  median" + " " * 23 + "".join(f"{statistics.median(ratios[c]):6.2f}".rjust(20) for c in CHOICES))
    print(
        "  range "
        + " " * 23
        + "".join(f"{min(ratios[c]):.2f}-{max(ratios[c]):.2f}".rjust(20) for c in CHOICES)
    )


def timing(repeat: int) -> None:
    """Seconds per megapixel of ``denoise`` (prefilter, two halves, estimate) and of a
    preview (one run) on 1 and 2 threads, alternating, on a 512x512 image (the Cornell box
    at 16 spp, tiled 2 x 2)."""
    res, options = SCENES["cornell-box"]
    small = study_inputs(ptlab.load_scene("cornell-box"), res, 16, 0, options)
    inputs = DenoiseInputs(
        *(np.tile(getattr(small, name), (2, 2, 1)) for name in DenoiseInputs.__dataclass_fields__)
    )
    megapixels = inputs.half_a.shape[0] * inputs.half_a.shape[1] / 1e6
    for threads in (1, 2):  # (first runs make the devices and filters: not timed)
        denoise(inputs, threads=threads)
        denoise(inputs, threads=threads, estimate=False)
    seconds: dict[tuple[int, bool], list[float]] = {}
    for run in range(repeat):
        for threads in (1, 2) if run % 2 == 0 else (2, 1):
            for estimate in (True, False):
                start = time.perf_counter()
                denoise(inputs, threads=threads, estimate=estimate)
                seconds.setdefault((threads, estimate), []).append((time.perf_counter() - start) / megapixels)
    height, width = inputs.half_a.shape[:2]
    print(f"  {width}x{height}, {repeat} runs each, alternating; s/MP median (min-max)")
    for estimate, label in (
        (True, "denoise + estimate (prefilter, 2 runs)"),
        (False, "preview (prefilter, 1 run)"),
    ):
        for threads in (1, 2):
            values = seconds[threads, estimate]
            print(
                f"    {label:40} {threads} thread{'s' if threads > 1 else ' '} "
                f"{statistics.median(values):6.2f} ({min(values):.2f}-{max(values):.2f})"
            )
    ratios = [one / two for one, two in zip(seconds[1, True], seconds[2, True], strict=True)]
    spread = f"{min(ratios):.2f}-{max(ratios):.2f}"
    print(f"    1 thread / 2 threads (denoise + estimate): {statistics.median(ratios):.2f} ({spread})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenes", default=",".join(SCENES))
    parser.add_argument("--spp", default="4,16,64")
    parser.add_argument("--seeds", default="0,1")
    parser.add_argument("--repeat", type=int, default=5, help="timing runs per thread count")
    parser.add_argument("--interim", action="store_true", help="build the inputs from separate renders")
    args = parser.parse_args()
    global INTERIM
    INTERIM = args.interim
    spps = [int(value) for value in args.spp.split(",")]
    seeds = [int(value) for value in args.seeds.split(",")]
    rows = []
    for scene_name in args.scenes.split(","):
        rows += measure(scene_name, spps, seeds)
    trusted = [ratio for ratio, value in rows if value is not None]
    print(
        f"\nestimates trusted: {len(trusted)} of {len(rows)}; their ratio to the truth "
        + (f"{min(trusted):.2f}-{max(trusted):.2f}" if trusted else "(none)")
    )
    print(f"\nwhat the options buy (the denoised image, light seen directly kept out; seed {seeds[0]}):")
    options_table(spps, seeds[0])
    print("\ndenoiser time:")
    timing(args.repeat)


if __name__ == "__main__":
    main()
