"""``ptlab exercise inspect`` (``ptlab.course.inspection``): a student's functions against
the library's at one pixel, and the command a failing render check suggests. Deterministic:
both sides trace the same samples, so a right answer agrees and a wrong one differs at a
vertex known in advance."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from test_exercises import WRONG, _wrong_answer_text

from ptlab.cli import main
from ptlab.course.inspect_command import suggestion
from ptlab.course.inspect_microfacet import drawn, reference_pdfs, terms, terms_lines
from ptlab.course.inspection import Difference, first_difference, message
from ptlab.course.messages import language
from ptlab.inspector import PixelInspection
from ptlab.inspector.records import BsdfSample, Sample, Vertex
from ptlab.materials import Microfacet
from ptlab.sampling import to_world
from ptlab.scattering import reflect
from ptlab.vectors import normalize


def student_file(tmp_path, name: str, chapter_file: str):
    """The typical wrong (or right) answer ``name`` as a student's file named as the chapter's."""
    path = tmp_path / chapter_file
    path.write_text(_wrong_answer_text(name), encoding="utf-8")
    return path


@pytest.mark.subprocess
def test_wrong_mis_weights_differ_at_the_first_light_sample(tmp_path, capsys):
    path = student_file(tmp_path, "10_wrong_argument_order", "10_mis.py")
    out = tmp_path / "first.json"
    code = main(["exercise", "inspect", "10", str(path), "--pixel", "16,16", "--json", str(out)])
    assert code == 1
    printed = capsys.readouterr().out
    assert "sample 0, depth 0: your light.mis_weight" in printed
    found = json.loads(out.read_text())["first_difference"]
    assert (found["sample"], found["depth"], found["quantity"]) == (0, 0, "light.mis_weight")
    # The other strategy's weight: the power heuristic of (other, pdf), not (pdf, other).
    assert found["expected"] == pytest.approx(1.0)
    assert found["yours"] < 1e-6
    # The call behind it, with its arguments: a light sample of density 3862, which the
    # BSDF would draw with density 0.19.
    call = found["call"]
    assert (call["drawn_by"], call["heuristic"]) == ("light", "power")
    assert (call["pdf"], call["other"]) == (pytest.approx(3862, rel=1e-3), pytest.approx(0.1948, rel=1e-3))
    assert (call["yours"], call["expected"]) == (found["yours"], found["expected"])
    assert 'mis_weight(pdf 3862, other 0.1948, "power"), pdf the light sample\'s density' in printed


@pytest.mark.subprocess
def test_a_pdf_without_walters_jacobian_is_found_where_the_path_first_meets_a_metal(tmp_path, capsys):
    path = student_file(tmp_path, "09_wrong_pdf_of_h", "09_microfacet.py")
    assert main(["exercise", "inspect", "9", str(path), "--pixel", "16,16", "--lang", "zh"]) == 1
    printed = capsys.readouterr().out
    assert printed.startswith("样本 6，深度 1：你的 bsdf.pdf 是 "), printed


@pytest.mark.subprocess
def test_a_right_answer_agrees_and_a_black_light_differs_at_the_lamp(tmp_path, capsys):
    right = tmp_path / "07_path_tracing.py"
    shutil.copyfile(WRONG / "07_right_own_code.py", right)
    out = tmp_path / "agree.json"
    assert main(["exercise", "inspect", "7", str(right), "--pixel", "16,4", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["first_difference"] is None
    assert "agree at pixel (16, 4)" in capsys.readouterr().out
    (tmp_path / "wrong").mkdir()
    wrong = student_file(tmp_path / "wrong", "07_wrong_black_light", "07_path_tracing.py")
    assert main(["exercise", "inspect", "7", str(wrong), "--pixel", "16,4"]) == 1
    # The pieces agree; the loop's sample misses the lamp's Le (47.8 in red) it sees.
    assert capsys.readouterr().out.startswith("sample 0: your contribution (2.5")


@pytest.mark.subprocess
def test_eta_the_wrong_way_up_changes_the_first_fresnel_weight(tmp_path, capsys):
    path = tmp_path / "03_whitted.py"
    shutil.copyfile(WRONG / "03_wrong_eta_inverted.py", path)
    # Pixel (30, 35) of the render check's view sees the glass block; with eta the wrong way
    # up, the Fresnel weight of the first reflected ray is the first number to differ.
    assert main(["exercise", "inspect", "3", str(path), "--pixel", "30,35"]) == 1
    assert capsys.readouterr().out.startswith("sample 0, depth 0: your reflected ray weight (")


#: Chapter 9's right answers, and typical wrong ones made of them: (base, old lines, new).
RIGHT_09 = ("09_right_walter.py", "09_right_heitz.py")
WRONG_09 = {
    # Smith's Lambda without its / 2: G1 and G2 both wrong, D and F right.
    "lambda_without_half": (
        "09_right_walter.py",
        "    return (np.sqrt(1 + alpha * alpha * (1 - cos2) / cos2) - 1) / 2\n",
        "    return np.sqrt(1 + alpha * alpha * (1 - cos2) / cos2) - 1\n",
    ),
    # A sampler with the wrong lobe: tan(theta_h) = alpha u0, its pdf still Walter's.
    "lobe_tan_alpha_u": (
        "09_right_walter.py",
        "        tan2_theta = self.alpha**2 * u[:, 0] / (1 - u[:, 0])\n",
        "        tan2_theta = (self.alpha * u[:, 0]) ** 2\n",
    ),
    # h reflected the wrong way: h mirrored about wo, not wo about h.
    "reflected_about_wo": (
        "09_right_walter.py",
        "        return reflect(wo, to_world(local, n))\n",
        "        return reflect(to_world(local, n), wo)\n",
    ),
    # Visible normals' pdf with wo and wi swapped: G1(wi) D / (4 cos_theta_i).
    "visible_pdf_of_wi": (
        "09_right_heitz.py",
        "            density = G1(cos_o, self.alpha) * D(dot(h, n), self.alpha) / (4 * cos_o)\n",
        "            cos_i = np.maximum(cos_i, 1e-7)\n"
        "            density = G1(cos_i, self.alpha) * D(dot(h, n), self.alpha) / (4 * cos_i)\n",
    ),
}


def file_09(tmp_path, name: str):
    """The wrong answer ``name`` of ``WRONG_09`` (or a right one) as a student's file."""
    if name in RIGHT_09:
        text = (WRONG / name).read_text(encoding="utf-8")
    else:
        base, old, new = WRONG_09[name]
        text = (WRONG / base).read_text(encoding="utf-8")
        assert text.count(old) == 1, f"{name}: the patch of {base} no longer applies"
        text = text.replace(old, new)
    folder = tmp_path / name
    folder.mkdir()
    (folder / "09_microfacet.py").write_text(text, encoding="utf-8")
    return folder / "09_microfacet.py"


@pytest.mark.subprocess
@pytest.mark.parametrize("name", RIGHT_09)
def test_right_microfacets_agree_with_what_their_samplers_draw(tmp_path, capsys, name):
    # Pixel (8, 20) sees the copper sphere at every sample's first vertex: the student's
    # eval and pdf there, then the directions its sample draws at the first one. Heitz's
    # visible normals have a pdf of their own (not Walter's), which is right too.
    out = tmp_path / "agree.json"
    path = file_09(tmp_path, name)
    assert main(["exercise", "inspect", "9", str(path), "--pixel", "8,20", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["first_difference"] is None
    assert "agree at pixel (8, 20)" in capsys.readouterr().out


@pytest.mark.subprocess
def test_a_wrong_g1_is_named_among_the_terms_of_the_brdf(tmp_path, capsys):
    path = file_09(tmp_path, "lambda_without_half")
    out = tmp_path / "terms.json"
    assert main(["exercise", "inspect", "9", str(path), "--pixel", "8,20", "--json", str(out)]) == 1
    printed = capsys.readouterr().out
    assert printed.startswith("sample 0, depth 0: your bsdf.f (")
    assert "G1(wo) differs first: yours 0.969" in printed
    assert "the same as the library's: D(h), F(wo . h)" in printed
    terms = json.loads(out.read_text())["first_difference"]["terms"]
    assert terms["differs"] == "G1(wo)"
    marked = [line.split()[0] for line in printed.splitlines() if line.endswith("<-")]
    assert marked == ["G1(wo)", "G1(wi)", "G2(wo,"]


@pytest.mark.subprocess
@pytest.mark.parametrize(
    ("name", "verdict"),
    [
        (
            "lobe_tan_alpha_u",
            "your pdf is the density of Walter's sampling, so it is your sample that differs",
        ),
        ("reflected_about_wo", "so it is your sample that differs"),
        (
            "visible_pdf_of_wi",
            "your sample draws like the library's visible normals, so it is your pdf that differs",
        ),
    ],
)
def test_a_sampler_that_draws_what_its_pdf_does_not_say_is_found(tmp_path, capsys, name, verdict):
    path = file_09(tmp_path, name)
    out = tmp_path / "drawn.json"
    assert main(["exercise", "inspect", "9", str(path), "--pixel", "8,20", "--json", str(out)]) == 1
    printed = capsys.readouterr().out
    assert printed.startswith("sample 0, depth 0: "), printed
    assert "your sample draws directions that your pdf does not describe" in printed
    assert verdict in printed
    found = json.loads(out.read_text())["first_difference"]
    assert found["drawn"]["p"] < 1e-30
    # Its eval and pdf are Walter's at the library's directions: only what it draws
    # differs. A pdf of wi's G1 differs there already, and what it draws says which is wrong.
    assert found["quantity"] == ("bsdf.pdf" if name == "visible_pdf_of_wi" else "sample")


def test_what_a_sampler_draws_is_told_apart_from_its_pdf_at_any_angle():
    # The library's visible normals agree with their pdf from head-on to grazing wo, where
    # the quadrature of the pdf over the bins is hardest; a lobe of tan(theta_h) = alpha u0
    # with Walter's pdf does not, and Walter's density is named as the pdf's.
    n = np.array([0.3, -0.4, np.sqrt(0.75)], np.float32)
    tangent = np.cross(n, [1.0, 0.0, 0.0]).astype(np.float32)
    tangent /= np.linalg.norm(tangent)
    for alpha, cos_theta_o in ((0.04, 0.9), (0.25, 0.5), (0.6, 0.003)):
        wo = (cos_theta_o * n + np.sqrt(1 - cos_theta_o**2) * tangent).astype(np.float32)
        found = drawn(Microfacet((1, 1, 1), alpha=alpha), wo, n, alpha, "ggx", np.random.default_rng(1))
        assert found.agrees, (alpha, cos_theta_o, found)
        assert found.pdf_of == "visible", (alpha, cos_theta_o, found)

    class WrongLobe(Microfacet):
        def sample(self, wo, n, u, front=None):
            tan_theta = self.alpha * u[:, 0]
            phi = 2 * np.pi * u[:, 1]
            local = np.stack([tan_theta * np.cos(phi), tan_theta * np.sin(phi), np.ones_like(phi)], axis=1)
            return reflect(wo, to_world(normalize(local), n))

        def pdf(self, wo, wi, n):
            return reference_pdfs(self.alpha, "ggx", wo, wi, n)["walter"]

    found = drawn(WrongLobe((1, 1, 1), alpha=0.25), wo, n, 0.25, "ggx", np.random.default_rng(1))
    assert not found.agrees
    assert (found.pdf_of, found.like) == ("walter", None)


def _inspection(*vertices: Vertex, contribution=(1.0, 1.0, 1.0)) -> PixelInspection:
    return PixelInspection(
        "scene", (0, 0), list(contribution), [Sample(0, list(contribution), list(vertices))]
    )


def _vertex(depth: int, pdf: float | None, wi=(0.0, 0.0, 1.0)) -> Vertex:
    return Vertex(
        depth,
        [0.0, 0.0, 0.0],
        3,
        "white",
        [0.0, 0.0, 1.0],
        True,
        [0.0, 0.0, 1.0],
        bsdf=BsdfSample(list(wi), pdf=pdf),
    )


class _OddTerms:
    """A student's module whose terms are no numbers (D), far too many (G1), or raise (G2)."""

    @staticmethod
    def D(cos_h, alpha):  # noqa: N802 (the exercise's name)
        return ["not", "a", "number"]

    @staticmethod
    def G1(cos, alpha):  # noqa: N802
        return np.zeros(200_000)

    @staticmethod
    def G2(cos_o, cos_i, alpha):  # noqa: N802
        raise ValueError("not written")

    @staticmethod
    def fresnel_schlick(cos, f0):  # (right: Schlick's approximation)
        f0 = np.asarray(f0)
        return f0 + (1 - f0) * (1 - cos[:, None]) ** 5


def test_terms_that_are_no_numbers_or_too_many_are_shown_as_such_and_the_others_still_compared():
    wo, wi, n = (
        normalize(np.array([0.3, 0.1, 0.9])),
        normalize(np.array([-0.2, 0.3, 0.8])),
        np.array([0, 0, 1.0]),
    )
    found = terms(
        _OddTerms, (1.0, 0.782, 0.344), 0.3, (wo, wi, n), (wo[None], wi[None], n[None], np.ones((1, 3)))
    )
    lines = "\n".join(terms_lines(found))
    assert [t.yours for t in found.terms[:4]] == [None, "shape (200000,)", "shape (200000,)", None]
    assert found.differs == "D(h)"
    assert len(lines) < 2000  # (the 200 000 values are not printed)
    assert found.terms[4].agrees()  # (the right F is still compared, and agrees)


def test_first_difference_compares_only_what_both_recorded():
    library = _inspection(_vertex(0, 0.318), _vertex(1, 0.2))
    assert first_difference(_inspection(_vertex(0, 0.318 * (1 + 1e-5)), _vertex(1, 0.2)), library) is None
    # A field one side did not record (a student's piece seen from outside) is not compared.
    assert first_difference(_inspection(_vertex(0, None), _vertex(1, 0.2)), library) is None
    found = first_difference(_inspection(_vertex(0, 0.318), _vertex(1, 0.1)), library)
    assert found == Difference(0, 1, "bsdf.pdf", 0.1, 0.2)
    assert message(found, (0, 0), 1) == "sample 0, depth 1: your bsdf.pdf 0.1, the library's 0.2"
    shorter = first_difference(_inspection(_vertex(0, 0.318)), library)
    assert shorter == Difference(0, 1, "vertices", 1, 2)


def test_the_suggested_pixel_is_where_the_images_differ_most():
    rng = np.random.default_rng(3)
    library = rng.random((4, 10, 12, 3))  # (passes, H, W, 3)
    student = library.copy()
    student[:, 7, 2] += 0.5  # x 2, y 7
    student[:, 1, 1, 0] = np.nan  # NaN beats everything: it is the worst pixel
    assert "--pixel 1,1 --seed 5 " in suggestion(7, student, library, 5)
    student[:, 1, 1, 0] = library[:, 1, 1, 0]
    with language("zh"):
        line = suggestion(9, student[0], library[0], 12)
    assert "ptlab exercise inspect 9 你的文件 --pixel 2,7 --seed 12" in line
