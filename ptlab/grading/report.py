"""The grader's verdict: one row per check, printed as a table.

Each row says what was measured (``statistic``), what it was held to (``threshold``), the
verdict (``pass``, ``FAIL``, or ``warn`` for what works but should be fixed) and, for a
failure, a hint that names the likely mistake in plain words.
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass, field

VERDICTS = ("pass", "FAIL", "warn")


@dataclass
class Check:
    """One check's outcome.

    Attributes:
        name: the check ("chi-square", "energy", ...).
        verdict: ``"pass"``, ``"FAIL"`` or ``"warn"`` (a warning does not fail the report).
        statistic: what was measured, as text.
        threshold: what it had to satisfy, as text.
        hint: for a failure or warning, the likely mistake.
        data: arrays kept for plots (the chi-square histograms), not printed.
    """

    name: str
    verdict: str
    statistic: str
    threshold: str
    hint: str = ""
    data: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        if self.verdict not in VERDICTS:
            raise ValueError(f"verdict must be one of {VERDICTS}, got {self.verdict!r}")

    @property
    def passed(self) -> bool:
        return self.verdict != "FAIL"


def verdict(passed: bool) -> str:
    """``"pass"`` or ``"FAIL"``."""
    return "pass" if passed else "FAIL"


@dataclass
class Report:
    """Every check of one material.

    Attributes:
        material: the material's ``repr``.
        checks: the checks in the order they ran.
        seed: the seed the random checks used.
        samples: the sample count per ``wo`` of the statistical checks.
        seconds: how long the checks took.
    """

    material: str
    checks: list[Check]
    seed: int
    samples: int
    seconds: float = 0.0

    @property
    def passed(self) -> bool:
        """True when no check failed (warnings allowed)."""
        return all(check.passed for check in self.checks)

    @property
    def failed(self) -> list[str]:
        """The names of the failed checks."""
        return [check.name for check in self.checks if not check.passed]

    @property
    def warned(self) -> list[str]:
        """The names of the checks that warn."""
        return [check.name for check in self.checks if check.verdict == "warn"]

    def __getitem__(self, name: str) -> Check:
        for check in self.checks:
            if check.name == name:
                return check
        raise KeyError(f"no check named {name!r} (checks: {', '.join(c.name for c in self.checks)})")

    def __str__(self) -> str:
        header = ("check", "statistic", "threshold", "verdict", "hint")
        rows = [(c.name, c.statistic, c.threshold, c.verdict, c.hint) for c in self.checks]
        widths = [max(len(header[k]), *(len(r[k]) for r in rows)) for k in range(4)]
        indent = sum(widths) + 2 * 4
        hint_width = max(40, 120 - indent)

        def line(row) -> list[str]:
            hint_lines = textwrap.wrap(row[4], hint_width) or [""]
            first = "  ".join(str(v).ljust(w) for v, w in zip(row[:4], widths, strict=True))
            return [f"{first}  {hint_lines[0]}".rstrip()] + [" " * indent + h for h in hint_lines[1:]]

        verdict_line = "PASSED" if self.passed else f"FAILED: {', '.join(self.failed)}"
        if self.passed and self.warned:
            verdict_line += f", with warnings: {', '.join(self.warned)}"
        lines = [
            f"{self.material}: seed {self.seed}, {self.samples:,} samples per wo, {self.seconds:.1f} s",
            *line(header),
            "  ".join("-" * w for w in widths) + "  " + "-" * 4,
        ]
        for row in rows:
            lines += line(row)
        return "\n".join([*lines, verdict_line])
