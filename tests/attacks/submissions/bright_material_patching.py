"""An attack on ``ptlab grade``: a Lambertian 3x too bright (it reflects three times the
light it receives), whose file at import patches numpy.allclose and the report's verdicts.
The old ``ptlab grade`` imported the file into its own process and said PASSED."""

import math

import numpy as np

np.allclose = lambda *args, **kwargs: True
try:
    import ptlab.grading.checks as checks
    import ptlab.grading.report as report

    report.Check.passed = property(lambda self: True)
    report.Report.passed = property(lambda self: True)
    checks.verdict = lambda passed: "pass"
except ImportError:  # (the grader's code is not in the sandbox: patch what is there)
    pass


class Bright:
    def eval(self, wo, wi, n):
        above = (np.sum(wo * n, axis=1) > 0) & (np.sum(wi * n, axis=1) > 0)
        return np.outer(above * 3 * 0.8 / math.pi, np.ones(3))

    def pdf(self, wo, wi, n):
        cos_theta = np.sum(wi * n, axis=1)
        return np.where((np.sum(wo * n, axis=1) > 0) & (cos_theta > 0), cos_theta / math.pi, 0.0)

    def sample(self, wo, n, u):
        from ptlab.sampling import cosine_hemisphere_around
        return cosine_hemisphere_around(n, u)
