"""``ptlab bench --against``: a stand-in for the homework's compiled ``RayTracing`` (a small
Python script laid out like the homework: ``build/RayTracing`` beside ``models/``) is timed
against a real, tiny ``ptlab render``."""

from __future__ import annotations

import json
import stat
import sys
from pathlib import Path

import pytest

from ptlab.cli import main

#: A 6-row, 8-column binary PPM: not square, so a swapped width and height shows.
PPM = b"P6\n8 6\n255\n" + bytes(range(8 * 6 * 3))


def stand_in(project: Path, body: str) -> Path:
    """``project/build/RayTracing``: a script that logs how it was run to ``project/calls``,
    then runs ``body``; and ``project/models/``, where the homework keeps its meshes."""
    (project / "models").mkdir(parents=True)
    program = project / "build" / "RayTracing"
    program.parent.mkdir()
    program.write_text(
        f"#!{sys.executable}\n"
        "import json, os, sys, time\n"
        f"with open({str(project / 'calls')!r}, 'a') as log:\n"
        "    log.write(json.dumps(dict(args=sys.argv[1:], cwd=os.getcwd(),\n"
        "        omp=os.environ.get('OMP_NUM_THREADS'), models=os.path.isdir('../models'))) + '\\n')\n"
        f"{body}\n"
    )
    program.chmod(program.stat().st_mode | stat.S_IXUSR)
    return program


def calls(project: Path) -> list[dict]:
    return [json.loads(line) for line in (project / "calls").read_text().splitlines()]


@pytest.mark.subprocess
def test_against_times_both_programs_and_prints_their_ratio(tmp_path, capsys):
    project = tmp_path / "Assignment7"
    program = stand_in(project, f"time.sleep(0.1)\nopen('binary.ppm', 'wb').write({PPM!r})")
    assert main(["bench", "--against", str(program), "--spp", "1", "--repeat", "1", "--workers", "1"]) == 0
    out = capsys.readouterr().out
    # ptlab renders at the C++ image's size, with the homework's estimator.
    assert (
        "ptlab render cornell-box --res 8x6 --spp 1 --sampling uniform --rr 0.8 --workers 1 --quiet"
    ) in out
    rows = {line.split()[0]: line.split() for line in out.splitlines() if line.split()}
    cpp, ptlab, ratio = map(float, rows["1"][1:])
    assert cpp >= 0.1
    assert ptlab > 0
    # (each printed to 2 decimals)
    assert ratio == pytest.approx(cpp / ptlab, abs=0.005 + 0.01 * ratio / min(cpp, ptlab))
    assert [float(x) for x in rows["median"][1:]] == [cpp, ptlab]
    assert f"C++ / ptlab time: {ratio:.2f}x (1 pair; above 1, ptlab is faster)" in out
    # The program got the spp, one OpenMP thread per worker, a scratch folder of its own
    # with the homework's models beside it; the scratch folder is gone afterwards.
    [call] = calls(project)
    assert call["args"] == ["1"]
    assert call["omp"] == "1"
    assert call["models"]
    assert not Path(call["cwd"]).exists()
    assert not (project / "build" / "binary.ppm").exists()


def test_the_summary_gives_the_median_ratio_and_its_range_over_the_pairs():
    from ptlab.measure.against import AgainstResult

    result = AgainstResult((8, 6), cpp_seconds=[2.0, 4.0, 3.0], ptlab_seconds=[1.0, 1.0, 2.0])
    assert result.ratios == [2.0, 4.0, 1.5]
    assert result.summary() == (
        "C++ / ptlab time: 2.00x (median of 3 pairs, range 1.50-4.00; above 1, ptlab is faster)"
    )


@pytest.mark.subprocess
@pytest.mark.parametrize(
    ("body", "options", "message"),
    [
        ("", ["--cpp-args", "--spp {spp} --fast"], "wrote no binary.ppm into the folder it ran in"),
        (f"open('binary.ppm', 'wb').write({PPM[:40]!r})", [], "wrote an unreadable binary.ppm"),
        (
            "sys.exit('cannot open ../models/cornellbox/floor.obj')",
            [],
            "failed with exit code 1: cannot open ../models/cornellbox/floor.obj",
        ),
        ("os.kill(os.getpid(), 9)", [], "was killed by SIGKILL"),
    ],
)
def test_a_program_that_fails_or_writes_no_image_is_a_one_line_error(
    tmp_path, capsys, body, options, message
):
    project = tmp_path / "Assignment7"
    program = stand_in(project, body)
    code = main(["bench", "--against", str(program), "--spp", "4", *options])
    captured = capsys.readouterr()
    assert code == 2, captured.err
    assert captured.err.count("\n") == 1, captured.err
    assert captured.err.startswith(f"ptlab: error: --against {program}")
    assert message in captured.err
    assert "C++ / ptlab" not in captured.out  # no table pretending to be complete
    expected_args = ["--spp", "4", "--fast"] if options else ["4"]
    assert [c["args"] for c in calls(project)] == [expected_args]


@pytest.mark.parametrize(
    ("make", "options", "message"),
    [
        (None, [], "no such file"),
        ("folder", [], "is a folder"),
        ("not executable", [], "is not executable"),
        ("program", ["--res", "64"], "--res does not go with --against"),
        ("program", ["--estimator", "default"], "--estimator does not go with --against"),
        ("program", ["--workers", "1", "--workers", "2"], "a second --workers does not go"),
        ("program", ["--cpp-args", "'{spp}"], "--cpp-args"),
        ("program", ["--spp", "0"], "--spp 0: must be from 1"),
    ],
)
def test_bad_programs_and_options_are_one_line_errors_before_anything_runs(
    tmp_path, capsys, make, options, message
):
    program = tmp_path / "RayTracing"
    if make == "folder":
        program.mkdir()
    elif make is not None:
        program.write_text(f"#!{sys.executable}\nopen({str(tmp_path / 'ran')!r}, 'w')\n")
        if make == "program":
            program.chmod(0o755)
    code = main(["bench", "--against", str(program), *options])
    captured = capsys.readouterr()
    assert code == 2, captured.err
    assert captured.err.count("\n") == 1, captured.err
    assert message in captured.err, captured.err
    assert not (tmp_path / "ran").exists()


def test_the_help_names_the_homework_program(capsys):
    with pytest.raises(SystemExit):
        main(["bench", "--help"])
    out = capsys.readouterr().out
    assert "--against PATH" in out
    assert "RayTracing" in out
    assert "--cpp-args ARGS" in out
