"""The inspector's printout: a block of lines per vertex, the steps of the homework's
``castRay`` in its order (the hit, the emission seen, the light sample, Russian roulette,
the BSDF sample, the throughput after)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ptlab.errors import PtlabError

if TYPE_CHECKING:
    from ptlab.inspector.records import Sample, Vertex


def number(x: float) -> str:
    """A number in 4 significant digits."""
    return f"{x:.4g}"


def vec(v: list[float] | None) -> str:
    """(x, y, z) in 4 significant digits each, or "-"."""
    return "-" if v is None else "(" + ", ".join(number(x) for x in v) + ")"


def table(found: Any, sample: int | None = None) -> str:
    """Every sample's vertices (or only sample ``sample``'s), then the pixel's value."""
    options = found.options
    x, y = found.pixel
    lines = [
        f"pixel ({x}, {y}) of {found.scene}, {options.get('width')}x{options.get('height')}, "
        f"{len(found.samples)} spp, seed {options.get('seed')}, {options.get('integrator')}"
        + (f" ({options.get('strategy')})" if options.get("integrator") == "path" else "")
    ]
    if sample is not None:
        if not 0 <= sample < len(found.samples):
            raise PtlabError(f"--sample {sample}: the pixel has samples 0 to {len(found.samples) - 1}")
        shown = [found.samples[sample]]
    else:
        shown = found.samples
    for s in shown:
        lines += sample_lines(s)
    lines.append(
        f"pixel value {vec(found.value)}: the mean of the {len(found.samples)} samples' contributions"
    )
    return "\n".join(lines)


def sample_lines(sample: Sample) -> list[str]:
    """The lines of one sample."""
    lines = ["", f"sample {sample.index}"]
    if not sample.vertices:
        lines.append("  the camera ray hit nothing")
    if sample.sky is not None:
        lines.append(f"  camera ray escaped: sky adds {vec(sample.sky)}")
    for vertex in sample.vertices:
        lines += vertex_lines(vertex)
    lines.append(f"  contribution {vec(sample.contribution)}")
    return lines


def vertex_lines(v: Vertex) -> list[str]:
    """The lines of one vertex, indented under its depth."""
    pad = " " * 11
    side = "front" if v.front else "back"
    lines = [
        f"  depth {v.depth:<3} hit {vec(v.position)} on triangle {v.triangle} ({v.material}), "
        f"{side} face, n {vec(v.normal)}, wo {vec(v.wo)}"
    ]
    if v.emission is not None:
        lines.append(f"{pad}emission: adds {vec(v.emission)}")
    if v.light is not None:
        light = v.light
        if light.point is None:
            lines.append(f"{pad}light:    adds {vec(light.contribution)}")
        else:
            mis = "" if light.mis_weight is None else f", MIS weight {number(light.mis_weight)}"
            seen = {
                True: "visible",
                False: "blocked",
                None: "no shadow ray (the light is behind the surface or faces away)",
            }[light.visible]
            lines.append(
                f"{pad}light:    {light.light} at {vec(light.point)}, pdf {number(light.pdf or 0)}, "
                f"{seen}{mis}: adds {vec(light.contribution)}"
            )
    if v.roulette is not None:
        outcome = "survives" if v.roulette.survived else "ends"
        lines.append(f"{pad}roulette: survival {number(v.roulette.survival or 0)}, {outcome}")
    if v.bsdf is not None:
        b = v.bsdf
        values = (
            "" if b.f is None else f", f {vec(b.f)}, pdf {number(b.pdf or 0)}, cos {number(b.cos_theta or 0)}"
        )
        weight = "" if b.weight is None else f", weight {vec(b.weight)}"
        lines.append(f"{pad}bsdf:     wi {vec(b.wi)}{values}{weight}")
    lines += [f"{pad}next ray: wi {vec(ray.wi)}, weight {vec(ray.weight)}" for ray in v.split]
    if v.sky is not None:
        lines.append(f"{pad}escaped:  sky adds {vec(v.sky)}")
    if v.throughput is not None:
        lines.append(f"{pad}throughput after: {vec(v.throughput)}")
    return lines
