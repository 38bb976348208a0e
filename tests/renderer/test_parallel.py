"""Parallel, progressive, resumable rendering: the image never depends on how it was made.

Every test compares bit for bit (``np.array_equal``) against the same render made in one
process without interruption.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import ptlab
from ptlab.image import read_image
from ptlab.materials import Diffuse
from ptlab.rendering import render_result

# Small tiles and several passes: many jobs, finishing out of order.
SMALL = dict(spp=6, res=(48, 40), seed=11, tile_size=16, spp_per_pass=2)


@pytest.fixture(scope="module")
def reference(cornell):
    return render_result(cornell, workers=1, **SMALL)


@pytest.mark.subprocess
@pytest.mark.parametrize("workers", [2, 3])
def test_process_pool_gives_the_same_image(cornell, reference, workers):
    result = render_result(cornell, workers=workers, **SMALL)
    assert result.complete
    assert result.spp == 6
    assert np.array_equal(result.image, reference.image)
    assert result.rays == reference.rays


def test_any_executor_gives_the_same_image(cornell, reference):
    with ThreadPoolExecutor(3) as pool:
        result = render_result(cornell, executor=pool, **SMALL)
    assert np.array_equal(result.image, reference.image)


@pytest.mark.slow
@pytest.mark.subprocess
def test_dask_cluster_gives_the_same_image(cornell, reference):
    distributed = pytest.importorskip("dask.distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        result = render_result(cornell, executor=client.get_executor(), **SMALL)
    assert np.array_equal(result.image, reference.image)


class StopAfter:
    """A ``stop`` callback that asks to stop once ``jobs`` jobs have been added."""

    def __init__(self, jobs: int):
        self.jobs, self.seen = jobs, 0

    def progress(self, film) -> None:
        self.seen += 1

    def __call__(self) -> bool:
        return self.seen >= self.jobs


@pytest.mark.parametrize("workers", [1, pytest.param(2, marks=pytest.mark.subprocess)])
def test_stop_keeps_whole_passes_per_tile_and_resume_finishes_identically(
    cornell, reference, tmp_path, workers, monkeypatch
):
    # (One worker runs a pass of a render this small as one group of jobs, and a stop is heard
    # between groups: groups of one job here, to stop in the middle of a pass.)
    monkeypatch.setattr("ptlab.rendering.jobs.MAX_GROUP_SAMPLES", 1)
    checkpoint = tmp_path / "render.npz"
    stopper = StopAfter(jobs=13)  # 9 tiles x 3 passes: stop in pass 2
    partial = render_result(
        cornell, workers=workers, checkpoint=checkpoint, progress=stopper.progress, stop=stopper, **SMALL
    )
    assert not partial.complete
    assert checkpoint.is_file()
    assert 0 < partial.spp < partial.spp_max <= 6
    assert partial.spp % 2 == 0
    resumed = render_result(cornell, workers=workers, resume=checkpoint, **SMALL)
    assert resumed.complete
    assert resumed.spp == 6
    assert np.array_equal(resumed.image, reference.image)
    assert resumed.samples < reference.samples  # only the missing passes ran


def test_resume_refuses_a_checkpoint_of_another_render(cornell, tmp_path):
    checkpoint = tmp_path / "render.npz"
    stopper = StopAfter(jobs=3)
    render_result(cornell, workers=1, checkpoint=checkpoint, progress=stopper.progress, stop=stopper, **SMALL)
    with pytest.raises(ptlab.errors.PtlabError, match="seed"):
        render_result(cornell, workers=1, resume=checkpoint, **dict(SMALL, seed=12))
    (tmp_path / "junk.npz").write_bytes(b"not a checkpoint")
    with pytest.raises(ptlab.errors.PtlabError, match="not a ptlab checkpoint"):
        render_result(cornell, workers=1, resume=tmp_path / "junk.npz", **SMALL)


def test_resume_may_add_passes_but_not_drop_them(cornell, tmp_path):
    checkpoint = tmp_path / "render.npz"
    stopper = StopAfter(jobs=12)  # 9 tiles x 3 passes: 3 tiles have 2 passes
    render_result(cornell, workers=1, checkpoint=checkpoint, progress=stopper.progress, stop=stopper, **SMALL)
    with pytest.raises(ptlab.errors.PtlabError, match="started with, 6"):
        render_result(cornell, workers=1, resume=checkpoint, **dict(SMALL, spp=2))
    longer = render_result(cornell, workers=1, resume=checkpoint, **dict(SMALL, spp=8))
    assert longer.complete
    assert longer.spp == 8
    straight = render_result(cornell, workers=1, **dict(SMALL, spp=8))
    assert np.array_equal(longer.image, straight.image)


def test_resume_alone_continues_the_same_render_to_the_same_output(cornell, tmp_path, monkeypatch, capsys):
    """`ptlab render --resume FILE`: the checkpoint knows its scene, options and output."""
    from ptlab.cli import main

    out, checkpoint = tmp_path / "box.exr", tmp_path / "render.npz"
    options = dict(SMALL, sampler="independent", rr=0.8, max_depth=5)
    stopper = StopAfter(jobs=4)
    command = dict(scene="cornell-box", out=str(out))
    first = render_result(
        "cornell-box",
        workers=1,
        checkpoint=checkpoint,
        progress=stopper.progress,
        stop=stopper,
        command=command,
        **options,
    )
    assert not first.complete
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    assert main(["render", "--resume", str(checkpoint), "--workers", "1", "--quiet"]) == 0, (
        capsys.readouterr().err
    )
    image, metadata = read_image(out)
    assert metadata["spp"] == 6
    assert metadata["sampler"] == "independent"
    assert list(elsewhere.iterdir()) == []  # (the output went where the render first wrote)
    assert np.array_equal(image, render_result(cornell, workers=1, **options).image)
    # An option that contradicts the checkpoint is refused, in one line.
    assert main(["render", "--resume", str(checkpoint), "--seed", "12"]) == 2
    assert "the checkpoint was made with seed = 11, this render has 12" in capsys.readouterr().err


def test_resume_of_a_checkpoint_that_does_not_record_its_scene_asks_for_it(cornell, tmp_path, capsys):
    from ptlab.cli import main

    checkpoint = tmp_path / "render.npz"
    stopper = StopAfter(jobs=3)
    render_result(cornell, workers=1, checkpoint=checkpoint, progress=stopper.progress, stop=stopper, **SMALL)
    assert main(["render", "--resume", str(checkpoint)]) == 2
    assert capsys.readouterr().err == (
        f"ptlab: error: {checkpoint}: this checkpoint does not record its scene: give the scene too\n"
    )


def test_a_checkpoint_from_before_render_options_still_resumes(cornell, reference, tmp_path):
    # Checkpoints written before RenderOptions kept the roulette and its depth as text
    # ('throughput', 'None'); the identity they record is otherwise the same.
    checkpoint = tmp_path / "render.npz"
    stopper = StopAfter(jobs=13)
    render_result(cornell, workers=1, checkpoint=checkpoint, progress=stopper.progress, stop=stopper, **SMALL)
    with np.load(checkpoint) as data:
        arrays = {name: data[name] for name in data.files}
    identity = json.loads(str(arrays["identity"]))
    assert identity["rr_depth"] is None
    identity.update(rr="throughput", rr_depth="None")
    del arrays["nonfinite"]  # (nor did they count NaN samples)
    np.savez(checkpoint, **dict(arrays, identity=json.dumps(identity)))
    resumed = render_result(cornell, workers=1, resume=checkpoint, **SMALL)
    assert resumed.complete
    assert np.array_equal(resumed.image, reference.image)
    with pytest.raises(ptlab.errors.PtlabError, match="rr_depth = 'None', this render has 1"):
        render_result(cornell, workers=1, resume=checkpoint, rr_depth=1, **SMALL)


def test_the_count_of_nan_samples_goes_on_across_a_resume(cornell, tmp_path, monkeypatch):
    original = Diffuse.eval

    def nan_near_grazing(self, wo, wi, n):
        f = np.array(original(self, wo, wi, n))
        f[(wi * n).sum(axis=1) < 0.2] = np.nan
        return f

    monkeypatch.setattr(Diffuse, "eval", nan_near_grazing)
    straight = render_result(cornell, workers=1, **SMALL)
    checkpoint = tmp_path / "render.npz"
    stopper = StopAfter(jobs=13)
    render_result(cornell, workers=1, checkpoint=checkpoint, progress=stopper.progress, stop=stopper, **SMALL)
    resumed = render_result(cornell, workers=1, resume=checkpoint, **SMALL)
    assert resumed.nonfinite == straight.nonfinite > 0


class DieOnceDiffuse(Diffuse):
    """A diffuse material that kills the process shading it, once per marker file.

    Stands in for a worker the system kills (out of memory, say) in the middle of a job.
    """

    def __init__(self, albedo, marker: str):
        super().__init__(albedo)
        self.marker = marker

    def batch_key(self):
        return "die-once"

    @classmethod
    def stack(cls, materials):
        return materials[0]

    def take(self, index):
        return self

    def sample_weight(self, wo, n, u, front=None):
        if not os.path.exists(self.marker):
            Path(self.marker).touch()
            os.kill(os.getpid(), signal.SIGKILL)
        return super().sample_weight(wo, n, u, front)


@pytest.mark.subprocess
def test_a_killed_worker_has_its_jobs_run_again(cornell, tmp_path):
    materials = list(cornell.materials)
    white = cornell.material_names.index("white")
    marker = str(tmp_path / "died")
    scene = ptlab.Scene(cornell.triangles, cornell.material_ids, materials, cornell.camera)
    scene.materials[white] = DieOnceDiffuse(cornell.materials[white].albedo, marker)
    scene = ptlab.Scene(scene.triangles, scene.material_ids, scene.materials, scene.camera)
    Path(marker).touch()
    expected = render_result(scene, workers=1, **SMALL).image
    os.remove(marker)
    with pytest.warns(RuntimeWarning, match="worker process died"):
        result = render_result(scene, workers=2, **SMALL)
    assert os.path.exists(marker)  # a worker really died
    assert np.array_equal(result.image, expected)


#: ``ptlab render ARGS`` whose progress bar (called after every job) sends the process the
#: signal ``SIGNUM`` once the first pass over the image is done: the signal comes at the same
#: point of the render however fast the machine is, from outside the render's own code.
INTERRUPTED_RENDER = """
import os, sys
from ptlab.cli import main
from ptlab.rendering.progress import ProgressBar

signum, update = int(sys.argv[1]), ProgressBar.__call__

def update_then_signal(bar, film):
    update(bar, film)
    if film.passes_done.min() >= 1 and not getattr(bar, "signalled", False):
        bar.signalled = True
        os.kill(os.getpid(), signum)

ProgressBar.__call__ = update_then_signal
sys.exit(main(["render", *sys.argv[2:]]))
"""


def run_cli(args: list[str], cwd: Path, signum: int | None = None) -> subprocess.Popen:
    """`ptlab render ARGS` in a new process (so that signals reach only it); with ``signum``,
    one that sends itself that signal after its first pass (``INTERRUPTED_RENDER``)."""
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    command = (
        ["-m", "ptlab.cli", "render"] if signum is None else ["-c", INTERRUPTED_RENDER, str(int(signum))]
    )
    return subprocess.Popen(
        [sys.executable, *command, *args],
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


@pytest.mark.subprocess
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_interrupted_cli_writes_what_it_has_then_resumes_to_the_same_image(tmp_path, signum):
    # One tile, 8 passes of 16 samples, at most 4 jobs in flight with 2 workers: the signal
    # after the first pass leaves at most 4 passes done, so the render is always cut short.
    options = ["cornell-box", "--res", "64", "--spp", "128", "--seed", "5", "--workers", "2"]
    process = run_cli([*options, "--out", "partial.exr", "--checkpoint", "state.npz"], tmp_path, signum)
    _, err = process.communicate(timeout=600)
    assert process.returncode == 128 + signum, err  # (the shell's code for that signal)
    assert "interrupted" in err
    assert "Traceback" not in err
    partial, metadata = read_image(tmp_path / "partial.exr")
    assert metadata["complete"] == 0
    assert 16 <= metadata["spp"] <= 64
    assert np.isfinite(partial).all()
    assert partial.mean() > 0.1

    resumed = run_cli([*options, "--out", "final.exr", "--resume", "state.npz"], tmp_path)
    _out, err = resumed.communicate(timeout=600)
    assert resumed.returncode == 0, err
    final, metadata = read_image(tmp_path / "final.exr")
    assert metadata["spp"] == 128
    assert metadata["complete"] == 1
    expected = ptlab.render("cornell-box", spp=128, res=64, seed=5, workers=1)
    assert np.array_equal(final, expected)


def test_preview_rewrites_the_output_after_a_pass(cornell, tmp_path):
    from ptlab.cli import _Preview

    out = tmp_path / "preview.exr"
    previews = []

    def on_pass(film):
        _Preview(out, 0.0)(film)
        previews.append(read_image(out)[1]["spp"])

    render_result(cornell, workers=1, on_pass=on_pass, **SMALL)
    assert previews == [2, 4, 6]


# -- a plain script, as the README shows it ------------------------------------------------

SCRIPT = """
import numpy as np
import ptlab
{before}
scene = ptlab.load_scene("cornell-box")
image = ptlab.render(scene, spp=6, res=(48, 40), seed=11, tile_size=16, spp_per_pass=2, workers=2)
np.save({out!r}, image)
print("rendered")
"""


def run_script(tmp_path: Path, before: str = "") -> subprocess.CompletedProcess:
    script = tmp_path / "render_box.py"
    script.write_text(SCRIPT.format(before=before, out=str(tmp_path / "image.npy")))
    return subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=120, cwd=tmp_path
    )


@pytest.mark.subprocess
def test_a_script_without_a_main_guard_renders_with_workers(tmp_path, reference):
    """Workers started by the fork server would run such a script again, and render again in
    each; ptlab forks them from the script's process instead, which runs it once."""
    result = run_script(tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.count("rendered") == 1
    assert "Traceback" not in result.stderr
    assert np.array_equal(np.load(tmp_path / "image.npy"), reference.image)


@pytest.mark.subprocess
def test_a_script_without_a_main_guard_that_cannot_fork_is_told_what_to_add(tmp_path):
    # Embree's threads already run in this process (a render in it), so forking is unsafe.
    result = run_script(
        tmp_path, before="ptlab.render('cornell-box', spp=1, res=8, workers=1, backend='embree')"
    )
    assert result.returncode != 0
    last = result.stderr.strip().splitlines()[-1]
    assert last.endswith(
        'render_box.py: put the script\'s own work under `if __name__ == "__main__":` to render '
        "with several workers (or pass workers=1)"
    ), result.stderr
    assert "worker processes died" not in result.stderr
    assert not (tmp_path / "image.npy").exists()


@pytest.mark.subprocess
def test_a_guarded_script_still_uses_the_fork_server(tmp_path):
    script = tmp_path / "guarded.py"
    script.write_text(
        "import ptlab.rendering.executors as e\n"
        "if __name__ == '__main__':\n"
        "    print(e.pool_context().get_start_method())\n"
        "print(e.pool_context().get_start_method())\n"
    )
    result = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=60)
    assert result.stdout.split() == ["forkserver", "fork"], result.stderr


def test_a_ctrl_c_inside_the_pools_bookkeeping_waits_until_it_is_done():
    # A KeyboardInterrupt raised inside concurrent.futures can leave a future's lock taken,
    # and the pool's thread then waits for it forever (the rare hang of a second Ctrl-C).
    from ptlab.rendering.scheduler import signals_held

    def two_ctrl_cs_then(finished: list[bool]) -> None:
        with signals_held():
            signal.raise_signal(signal.SIGINT)
            signal.raise_signal(signal.SIGINT)
            finished.append(True)

    before = signal.getsignal(signal.SIGINT)
    finished: list[bool] = []
    with pytest.raises(KeyboardInterrupt):
        two_ctrl_cs_then(finished)
    assert finished == [True]
    assert signal.getsignal(signal.SIGINT) is before


@pytest.mark.parametrize("whole_process", [True, False])
def test_a_stopped_ptlab_render_ignores_later_signals_only_as_its_own_process(whole_process):
    # Once stopped, `ptlab render` has only its exit left, which a late Ctrl-C would cut short
    # (a traceback from an exit hook, or death by SIGINT); a caller's process gets its handlers back.
    from ptlab.cli import _StopOnSignal

    before = {signum: signal.getsignal(signum) for signum in (signal.SIGINT, signal.SIGTERM)}
    try:
        with _StopOnSignal(whole_process) as signals:
            signal.raise_signal(signal.SIGTERM)
        assert signals.exit_code == 143
        for signum, handler in before.items():
            assert signal.getsignal(signum) is (signal.SIG_IGN if whole_process else handler)
    finally:
        for signum, handler in before.items():
            signal.signal(signum, handler)
