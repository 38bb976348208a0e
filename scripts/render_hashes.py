"""Fingerprint ptlab's images: a SHA-256 of each of a set of small renders (not run in CI).

    python scripts/render_hashes.py --save before.json      # before a change
    python scripts/render_hashes.py --compare before.json   # after it: which images changed

A change that should not change images (moving code, renaming, a refactor) must leave every
hash as it was. The renders cover each integrator, strategy, heuristic, sampler, sampling,
roulette setting and backend, and every built-in scene, at a small size so that the whole set
takes about a minute. With ``--compare``, an image that changed is reported with its mean before and
after, and the exit code is 1.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys

import numpy as np

import ptlab

#: (name, scene, options): each render of the set, in one process (``workers=1``).
RENDERS = [
    ("cornell embree", "cornell-box", {}),
    ("cornell numpy", "cornell-box", {"backend": "numpy"}),
    ("cornell homework", "cornell-box", {"sampling": "uniform", "rr": 0.8}),
    ("cornell independent", "cornell-box", {"sampler": "independent"}),
    ("cornell stratified", "cornell-box", {"sampler": "stratified"}),
    ("cornell bsdf", "cornell-box", {"strategy": "bsdf"}),
    ("cornell mis balance", "cornell-box", {"strategy": "mis", "heuristic": "balance"}),
    ("cornell rr depth 1", "cornell-box", {"rr_depth": 1, "max_depth": 6}),
    ("cornell whitted", "cornell-box", {"integrator": "whitted"}),
    ("cornell albedo", "cornell-box", {"integrator": "albedo"}),
    ("cornell normals", "cornell-box", {"integrator": "normals"}),
    ("cornell depth", "cornell-box", {"integrator": "depth"}),
    ("veach-mis mis", "veach-mis", {"strategy": "mis"}),
    ("glossy mis", "cornell-box-glossy", {"strategy": "mis"}),
    ("microfacet nee", "cornell-box-microfacet", {}),
    ("small light mis", "cornell-box-small-light", {"strategy": "mis"}),
    ("hw5 whitted", "games101-hw5", {"integrator": "whitted"}),
    ("hw5 mis", "games101-hw5", {"strategy": "mis"}),
    ("hw6 whitted", "games101-hw6", {"integrator": "whitted"}),
    ("hw6 nee numpy", "games101-hw6", {"backend": "numpy"}),
    # (to a noise target: the first pass at the set's spp, then passes of its own)
    ("cornell target", "cornell-box", {"target_error": 0.05}),
    ("veach-mis target", "veach-mis", {"strategy": "mis", "target_error": 0.2}),
]


def fingerprints(res: int, spp: int) -> dict[str, dict]:
    """{render name: {"sha256", "mean"}} for every render of ``RENDERS``."""
    result = {}
    for name, scene, options in RENDERS:
        image = ptlab.render(scene, spp=spp, res=res, seed=7, workers=1, **options)
        image = np.ascontiguousarray(image, dtype=np.float32)
        result[name] = {
            "sha256": hashlib.sha256(image.tobytes()).hexdigest(),
            "mean": float(image.astype(np.float64).mean()),
        }
        print(f"{name:22s} {result[name]['sha256'][:16]}  mean {result[name]['mean']:.6f}", flush=True)
    return result


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--res", type=int, default=48, help="square resolution (default 48)")
    parser.add_argument("--spp", type=int, default=8, help="samples per pixel (default 8)")
    what = parser.add_mutually_exclusive_group(required=True)
    what.add_argument("--save", metavar="FILE.json", help="write the fingerprints here")
    what.add_argument("--compare", metavar="FILE.json", help="compare with a saved set")
    args = parser.parse_args()
    if args.compare:
        with open(args.compare) as file:
            saved = json.load(file)
        args.res, args.spp = saved["res"], saved["spp"]
    current = fingerprints(args.res, args.spp)
    if args.save:
        with open(args.save, "w") as file:
            json.dump({"res": args.res, "spp": args.spp, "renders": current}, file, indent=1)
        print(f"saved {len(current)} fingerprints to {args.save}")
        return 0
    changed = [
        name
        for name, entry in saved["renders"].items()
        if current.get(name, {}).get("sha256") != entry["sha256"]
    ]
    for name in changed:
        before = saved["renders"][name]["mean"]
        after = current[name]["mean"] if name in current else float("nan")
        print(f"CHANGED {name}: mean {before:.6f} -> {after:.6f}")
    print(f"{len(saved['renders']) - len(changed)} of {len(saved['renders'])} images identical")
    return 1 if changed else 0


if __name__ == "__main__":
    sys.exit(main())
