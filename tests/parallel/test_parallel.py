"""brdfnorm.parallel: jobs as source, fixed chunks, identical tables in one process, a local pool and on Dask
(a real scheduler and two worker processes on 127.0.0.1, one killed mid-run), and checkpoints that resume
after SIGTERM/SIGKILL without recomputing finished chunks (shown by evaluation counts); a check's albedo
integrals through the same layer, with the same report bit for bit."""

from __future__ import annotations

import json
import os
import pickle
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import psutil
import pytest
from helpers.paths import REPO

import brdfnorm as bn
from brdfnorm.check import Budget, check
from brdfnorm.errors import ArgumentError, EvaluationError
from brdfnorm.normalization import normalize
from brdfnorm.parallel import CellsJob, ModelSource, Scheduler, albedo_cells, chunk_plan
from brdfnorm.parallel.checkpoint import Checkpoint
from brdfnorm.parallel.results import albedo_result

ROOT = REPO
GGX = ROOT / "examples" / "ggx.brdf"
SRC = Path(bn.__file__).resolve().parents[1]  # the brdfnorm these tests import, for subprocesses
CLI = [sys.executable, "-c", "from brdfnorm.cli import main; main()"]


def _env() -> dict:
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")])}


def _same(a, b) -> None:
    """Bit-for-bit equality of two computed tables."""
    for name in ("value", "error", "evaluations", "converged", "theta", "phi"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.value.tobytes() == b.value.tobytes() and a.error.tobytes() == b.error.tobytes()


def _ggx_job(chunk_cells: int = 6) -> CellsJob:
    model = bn.load(GGX)
    theta = np.radians(np.linspace(0, 85, 9))[None, :]
    return CellsJob.of(model, theta, values={"roughness": np.geomspace(0.05, 1.0, 4)[:, None]}, rtol=1e-8,
                       chunk_cells=chunk_cells)


COOK_TORRANCE = ROOT / "examples" / "cook_torrance.brdf"  # four bool combinations; fails energy at grazing views
CHECK_ARGS = {"checks": ("energy", "normalization"), "at": "view", "points": 8,
              "budget": Budget(seconds=None, evaluations=3_000_000)}


def _verdicts(report) -> tuple[dict, dict]:
    """A check's results and coverage without the clock's readings (what must be identical bit for bit)."""
    def timeless(d: dict) -> dict:
        return {k: timeless(v) if isinstance(v, dict) else v for k, v in d.items()
                if not k.endswith("seconds") and k not in ("elapsed_s", "parallel")}

    return ({name: {**vars(r), "sampled": timeless(r.sampled)} for name, r in report.results.items()},
            timeless(report.coverage))


# -- the job definition -----------------------------------------------------------------------------------

def test_model_source_rebuilds_builtin_and_brdf_models():
    rng = np.random.default_rng(5)
    L = rng.normal(size=(64, 3))
    V = rng.normal(size=(64, 3))
    L[:, 2], V[:, 2] = np.abs(L[:, 2]), np.abs(V[:, 2])
    L /= np.linalg.norm(L, axis=1, keepdims=True)
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    for model in (bn.load("phong", n=37.5), bn.load(GGX, roughness=0.2, f0=0.5)):
        source = ModelSource.of(model)
        clone = pickle.loads(pickle.dumps(source)).load()  # what a worker receives: data, not the model
        assert type(clone) is type(model) and clone.params == model.params
        assert np.array_equal(clone.eval(L, V), model.eval(L, V))
    text = GGX.read_text()
    assert ModelSource.of(bn.load(GGX)).text == text  # the file's text travels, not its path
    assert ModelSource.from_json(json.loads(json.dumps(source.to_json()))) == source


def test_model_source_refuses_what_has_no_source():
    with pytest.raises(ArgumentError, match="array"):
        ModelSource.of(bn.load("phong").with_params(n=np.array([1.0, 2.0])))

    class Local(bn.Model):
        name = "local"

        def evaluate(self, L, V, params):
            return np.ones(L.shape[:-1] + (1,))

    with pytest.raises(ArgumentError, match="cannot travel"):
        ModelSource.of(Local())


def test_a_source_is_rebuilt_by_brdfnorm_load_itself(monkeypatch):
    """Issue 40: the job does not re-implement loading; a name goes to brdfnorm.load, a file's text to load_text."""
    calls = []
    load, load_text = bn.load, bn.load_text
    monkeypatch.setattr(bn, "load", lambda key, **p: calls.append(("load", key, p)) or load(key, **p))
    monkeypatch.setattr(bn, "load_text", lambda text, key, **p: calls.append(("text", key, p)) or
                        load_text(text, key, **p))
    ModelSource.of(load("phong", n=37.5)).load()
    ModelSource.of(load(GGX, roughness=0.2)).load()
    assert [c[:2] for c in calls] == [("load", "phong"), ("text", str(GGX))]
    assert calls[0][2]["n"] == 37.5 and calls[1][2]["roughness"] == 0.2


def test_one_worker_computes_with_the_loaded_model_and_never_parses_it_again(monkeypatch):
    """Issue 40: with one worker the job's own model computes every chunk: the .brdf file is not parsed or
    compiled again; a job rebuilt from its data (as a checkpoint or a worker holds it) compiles once, not
    twice, and both give the table bit for bit."""
    import brdfnorm.brdffile as brdffile

    job = _ggx_job(chunk_cells=12)
    assert job.model is not None and job.model.params["roughness"] == job.source.params["roughness"]
    compiled = []
    compile_brdf = brdffile.compile_brdf
    monkeypatch.setattr(brdffile, "compile_brdf", lambda *a, **k: compiled.append(1) or compile_brdf(*a, **k))
    direct = albedo_cells(job, workers=1)
    assert compiled == []
    from dataclasses import replace

    rebuilt = replace(job, model=None)
    assert rebuilt.digest == job.digest  # the model is never part of the job's definition
    _same(albedo_cells(rebuilt, workers=1), direct)
    assert compiled == [1]


def test_digest_is_stable_across_processes_and_changes_with_the_job():
    job = _ggx_job()
    assert job.digest == _ggx_job().digest
    script = ("import numpy as np, brdfnorm as bn\nfrom brdfnorm.parallel import CellsJob\n"
              f"m = bn.load({str(GGX)!r})\n"
              "job = CellsJob.of(m, np.radians(np.linspace(0, 85, 9))[None, :], "
              "values={'roughness': np.geomspace(0.05, 1.0, 4)[:, None]}, rtol=1e-8, chunk_cells=6)\n"
              "print(job.digest)")
    other = subprocess.run([sys.executable, "-c", script], env={**_env(), "PYTHONHASHSEED": "12345"},
                           capture_output=True, text=True, check=True)
    assert other.stdout.strip() == job.digest
    model = bn.load(GGX)
    theta = np.radians(np.linspace(0, 85, 9))[None, :]
    roughness = np.geomspace(0.05, 1.0, 4)[:, None]
    changed = [
        CellsJob.of(model, theta, values={"roughness": roughness}, rtol=1e-9, chunk_cells=6),
        CellsJob.of(model, theta, values={"roughness": np.nextafter(roughness, 0)}, rtol=1e-8, chunk_cells=6),
        CellsJob.of(model.with_params(f0=0.05), theta, values={"roughness": roughness}, rtol=1e-8, chunk_cells=6),
        CellsJob.of(model, theta, values={"roughness": roughness}, rtol=1e-8, chunk_cells=5),
        CellsJob.of(model, theta, values={"roughness": roughness}, rtol=1e-8, over="view", chunk_cells=6),
    ]
    assert len({job.digest, *(c.digest for c in changed)}) == 1 + len(changed)


def test_chunks_are_fixed_by_the_job_and_group_neighbouring_cells():
    model = bn.load("blinn-phong-gaussian")
    n = np.geomspace(1, 1e4, 40)[:, None]
    job = CellsJob.of(model, np.radians(np.linspace(0, 89, 30))[None, :], values={"n": n}, rtol=1e-9)
    plan = chunk_plan(job, model)
    again = chunk_plan(CellsJob.of(model, np.radians(np.linspace(0, 89, 30))[None, :], values={"n": n},
                                   rtol=1e-9), model)
    assert np.array_equal(plan.bounds, again.bounds) and np.array_equal(plan.order, again.order)
    assert 1 < plan.count < job.size  # a probe sized them: neither one chunk nor one cell each
    sizes = np.diff(plan.bounds)
    assert sizes.min() < sizes.max()  # cut at equal estimated cost: the cheap low-n cells come in bigger chunks
    assert sizes[-1] < sizes[0]
    assert sorted(plan.order) == list(range(job.size))
    # canonical order: by the swept parameter first, so each chunk spans a narrow range of n (similar cost)
    n_of_cell = job.values["n"]
    assert np.all(np.diff(n_of_cell[plan.order]) >= 0)


# -- identical tables wherever they are computed ---------------------------------------------------------------

@pytest.mark.slow
def test_one_process_and_a_local_pool_agree_bit_for_bit_with_albedo():
    job = _ggx_job()
    serial = albedo_cells(job, workers=1)
    progress = []
    pooled = albedo_cells(job, workers=2, on_progress=lambda done, total: progress.append((done, total)))
    assert progress[0] == (0, 36) and progress[-1] == (36, 36) and len(progress) == 7  # once per chunk
    assert all(a[0] < b[0] for a, b in zip(progress, progress[1:], strict=False))
    assert serial.executor == "in-process" and pooled.executor == "local processes" and pooled.workers == 2
    assert serial.chunks == pooled.chunks == 6
    _same(serial, pooled)


def test_a_cells_albedo_does_not_depend_on_its_batch():
    """Chunks are fixed so that this need not hold; it does today, so a table also equals one albedo() call
    (README). If an engine change breaks it, tables stay identical across executors but not to that call."""
    job = _ggx_job()
    serial = albedo_result(job, albedo_cells(job, workers=1))  # as brdfnorm.albedo returns it
    direct = bn.albedo(bn.load(GGX).with_params(roughness=np.geomspace(0.05, 1.0, 4)[:, None]),
                       np.radians(np.linspace(0, 85, 9))[None, :], rtol=1e-8)
    for name in ("value", "error", "evaluations", "converged", "theta", "phi", "method", "over"):
        assert np.array_equal(getattr(serial, name), getattr(direct, name)), name
    assert serial.params.keys() == direct.params.keys()
    for name, value in direct.params.items():
        assert np.array_equal(serial.params[name], value), name


@pytest.mark.slow
def test_normalize_sweep_at_max_on_a_pool_matches_normalize(run_cli):
    code, out, err = run_cli("normalize", "blinn-phong-gaussian", "--sweep", "n=1:1000:6:log", "--at",
                             "max", "--rtol", "1e-8", "--workers", "2", "--chunk-cells", "2", "--json")
    assert code == 0, err
    assert "6 cells in 3 chunks" in err and "2 workers" in err
    rows = json.loads(out)["results"]
    n = np.geomspace(1, 1000, 6)
    reference = normalize(bn.load("blinn-phong-gaussian"), at="max", sweep={"n": n}, rtol=1e-8)
    assert [r["albedo"] for r in rows] == reference.albedo[:, 0, 0].tolist()
    assert [r["theta_deg"] for r in rows] == np.degrees(reference.theta[:, 0]).tolist()


def test_an_error_in_a_worker_arrives_whole(tmp_path):
    path = tmp_path / "infinite.brdf"
    path.write_text("analytic\n::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)\n"
                    "{ return vec3(1.0 / (L.z - L.z)); }\n::end shader\n")
    job = CellsJob.of(bn.load(path), np.radians([0.0, 10, 20, 30]), chunk_cells=2)
    with pytest.raises(EvaluationError, match="not finite") as caught:
        albedo_cells(job, workers=2)
    assert "infinite" in caught.value.where  # the where survives the trip back from the worker


# -- Dask: a real scheduler and two worker processes -----------------------------------------------------------

@pytest.fixture(scope="module")
def dask_cluster(tmp_path_factory):
    """``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1, as the README starts them."""
    pytest.importorskip("distributed")
    dask = shutil.which("dask", path=os.path.dirname(sys.executable)) or shutil.which("dask")
    if dask is None:
        pytest.skip("the `dask` command (package distributed) is not installed")
    scheduler_file = tmp_path_factory.mktemp("dask") / "scheduler.json"
    env = _env()
    quiet = dict(env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    processes = [subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                   "--scheduler-file", str(scheduler_file)], **quiet)]
    try:
        deadline = time.monotonic() + 60
        while not scheduler_file.exists() or not scheduler_file.read_text().strip():
            assert time.monotonic() < deadline, "the Dask scheduler did not start"
            time.sleep(0.1)
        address = json.loads(scheduler_file.read_text())["address"]
        for _ in range(2):
            processes.append(subprocess.Popen([dask, "worker", address, "--nthreads", "1", "--no-nanny",
                                               "--host", "127.0.0.1", "--no-dashboard"], **quiet))
        from distributed import Client

        with Client(address, timeout=30) as client:
            client.wait_for_workers(2, timeout=60)
        yield address, processes
    finally:
        for process in reversed(processes):
            process.terminate()
        for process in processes:
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()


@pytest.mark.slow
def test_check_through_dask_equals_the_in_process_check(dask_cluster, run_cli):
    from distributed import Client

    address, _ = dask_cluster
    with Client(address, timeout=30) as client:  # two unless a test before this one killed one
        workers = len(client.scheduler_info()["workers"])
    serial = check(COOK_TORRANCE, **CHECK_ARGS)
    on_dask = check(COOK_TORRANCE, **CHECK_ARGS, workers=None, scheduler=address, chunk_cells=8)
    assert on_dask.coverage["parallel"]["executors"] == [f"dask {address}"]
    assert on_dask.coverage["parallel"]["workers"] == workers
    assert _verdicts(on_dask) == _verdicts(serial)
    # the command line: the same JSON but for the clock's readings and where the integrals ran
    argv = ["check", str(COOK_TORRANCE), "--only", "energy,normalization", "--normalized", "--at", "view",
            "--points", "8", "--budget", "3e6evals", "--json"]
    code, local, err = run_cli(*argv, "--workers", "1")
    assert code == 1, err  # the energy check fails
    code, remote, err = run_cli(*argv, "--scheduler", address, "--chunk-cells", "8")
    assert code == 1 and f"on {workers} workers (dask {address})" in err, err

    def timeless(text: str) -> dict:
        report = json.loads(text)["reports"][0]
        for name in ("elapsed_s", "parallel"):
            report["coverage"].pop(name, None)
        for part in (report["coverage"]["energy"], report["checks"]["energy"]["sampled"]):
            for name in ("coarse_seconds", "refinement_seconds"):
                part.pop(name)
        return report

    assert timeless(remote) == timeless(local)


@pytest.mark.slow
def test_dask_table_equals_the_in_process_one_even_when_a_worker_dies(dask_cluster, monkeypatch, run_cli):
    from distributed import Client

    address, _ = dask_cluster
    argv = ["normalize", str(GGX), "--sweep", "roughness=0.1,0.5", "--at", "view", "--theta", "0:80:5", "--json",
            "--chunk-cells", "3"]
    code, local, err = run_cli(*argv, "--workers", "1")
    assert code == 0, err
    code, remote, err = run_cli(*argv, "--scheduler", address)
    assert code == 0 and f"on 2 workers (dask {address})" in err, err
    assert remote == local
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", address)  # the variable Dask's own tools read
    code, remote, err = run_cli(*argv)
    assert code == 0 and f"(dask {address})" in err and remote == local, err
    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS")

    job = _ggx_job(chunk_cells=3)  # 12 chunks
    serial = albedo_cells(job, workers=1)
    on_dask = albedo_cells(job, scheduler=address)
    assert on_dask.executor == f"dask {address}" and on_dask.workers == 2 and on_dask.chunks == 12
    _same(serial, on_dask)

    killed = {}
    with Client(address, timeout=30) as client:
        pids = client.run(os.getpid)

        def kill_a_busy_worker(done, total):
            if killed or done == 0:
                return
            processing = client.processing()
            worker = max(processing, key=lambda w: len(processing[w]))
            killed.update(worker=worker, keys=list(processing[worker]))
            os.kill(pids[worker], signal.SIGKILL)

        survived = albedo_cells(job, scheduler=address, on_progress=kill_a_busy_worker)
    assert killed["keys"], "the worker killed was running a chunk"
    assert not psutil.pid_exists(pids[killed["worker"]]) or \
        psutil.Process(pids[killed["worker"]]).status() == psutil.STATUS_ZOMBIE
    _same(serial, survived)
    assert survived.chunks_computed == 12


# -- checkpoints ----------------------------------------------------------------------------------------------

GGX_TABLE = ["albedo", str(GGX), "--theta", "0:85:120", "--rtol", "1e-10", "--chunk-cells", "12"]


def _cli_job() -> CellsJob:
    """The job GGX_TABLE's command line defines, built through the library."""
    return CellsJob.of(bn.load(GGX), np.radians(np.linspace(0, 85, 120)), 0.0, rtol=1e-10, chunk_cells=12)


def _interrupt(directory: Path, sig: int, workers: int, chunks: int = 2) -> tuple[subprocess.CompletedProcess, dict]:
    """Start the GGX table on the command line, send ``sig`` once ``chunks`` chunks are saved."""
    process = subprocess.Popen([*CLI, *GGX_TABLE, "--workers", str(workers), "--checkpoint", str(directory),
                                "--json"], env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    children = {}
    while len(list(directory.glob("chunk-*.npz"))) < chunks:
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "no chunk was saved"
        children.update({c.pid: c for c in psutil.Process(process.pid).children(recursive=True)})
        time.sleep(0.02)
    saved = {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in directory.glob("chunk-*.npz")}
    process.send_signal(sig)
    out, err = process.communicate(timeout=60)
    # the pool's workers (and multiprocessing's helpers) stop with the job, not after their chunks
    _, alive = psutil.wait_procs(list(children.values()), timeout=5)
    assert not alive, [(c.pid, c.cmdline()) for c in alive]
    return subprocess.CompletedProcess(process.args, process.returncode, out, err), saved


@pytest.mark.slow
@pytest.mark.parametrize("sig, workers", [(signal.SIGTERM, 2), (signal.SIGKILL, 1)])
def test_an_interrupted_job_resumes_without_recomputing_finished_chunks(tmp_path, sig, workers, run_cli):
    directory = tmp_path / "checkpoint"
    stopped, saved = _interrupt(directory, sig, workers)
    assert stopped.returncode == (143 if sig == signal.SIGTERM else -signal.SIGKILL)
    assert stopped.stdout == ""  # nothing half-written
    if sig == signal.SIGTERM:
        assert stopped.stderr.strip() == "error: interrupted by SIGTERM"
    job = _cli_job()
    store = Checkpoint.open(directory, job, lambda: pytest.fail("the checkpoint stores its chunk plan"))
    finished = store.finished()  # whole files only (the atomic rename), all of this job
    assert len(finished) >= 2 and set(saved) <= {store.chunk_path(k).name for k in finished}
    evaluations_saved = sum(int(r.evaluations.sum()) for r in finished.values())

    resumed = albedo_cells(job, workers=1, checkpoint=directory)
    uninterrupted = albedo_cells(job, workers=1)
    _same(uninterrupted, resumed)
    assert resumed.chunks == 10 and resumed.chunks_computed == 10 - len(finished)
    # evaluation counts: this run spent exactly what the missing chunks cost, nothing on the saved ones
    assert resumed.evaluations_computed == int(uninterrupted.evaluations.sum()) - evaluations_saved
    assert evaluations_saved > 0
    for name, (inode, mtime) in saved.items():  # the saved chunks were not rewritten
        assert ((directory / name).stat().st_ino, (directory / name).stat().st_mtime_ns) == (inode, mtime)

    # the command line, rerun on the complete checkpoint, computes nothing and prints the same table
    code, out, err = run_cli(*GGX_TABLE, "--checkpoint", str(directory), "--json")
    assert code == 0, err
    assert "120 cells in 10 chunks (10 from the checkpoint)" in err
    albedo = [row["albedo"] for row in json.loads(out)["results"]]
    assert albedo == [list(v) for v in uninterrupted.value.tolist()]


def test_a_checkpoint_of_another_job_is_refused(tmp_path, run_cli):
    directory = tmp_path / "checkpoint"
    code, _, err = run_cli("albedo", "phong", "-p", "n=10", "--theta", "0:60:20", "--chunk-cells", "10",
                           "--workers", "1", "--checkpoint", str(directory))
    assert code == 0, err
    before = {p.name: p.read_bytes() for p in directory.iterdir()}
    assert set(before) == {"job.json", "cells.npz", "chunk-000000.npz", "chunk-000001.npz"}
    for other in (["-p", "n=11"], ["-p", "n=10", "--rtol", "1e-9"]):
        code, out, err = run_cli("albedo", "phong", *other, "--theta", "0:60:20", "--chunk-cells", "10",
                                 "--checkpoint", str(directory))
        assert code == 2 and out == ""
        assert err.count("\n") == 1 and err.startswith("error: --checkpoint: ") and "different job" in err, err
    assert {p.name: p.read_bytes() for p in directory.iterdir()} == before  # nothing clobbered

    stranger = tmp_path / "not-a-checkpoint"
    stranger.mkdir()
    (stranger / "notes.txt").write_text("mine")
    code, _, err = run_cli("albedo", "phong", "--theta", "0:60:20", "--checkpoint", str(stranger))
    assert code == 2 and "holds no brdfnorm checkpoint" in err and (stranger / "notes.txt").read_text() == "mine"

    # a damaged chunk is never used: computed again (issue 35), with one warning naming it, and replaced
    (directory / "chunk-000001.npz").write_bytes(b"PK\x03\x04 damaged")
    code, _, err = run_cli("albedo", "phong", "-p", "n=10", "--theta", "0:60:20", "--chunk-cells", "10",
                           "--checkpoint", str(directory))
    warned = [line for line in err.splitlines() if "chunk-000001.npz" in line]
    assert code == 0 and len(warned) == 1 and warned[0].startswith("warning:") and "again" in warned[0], err
    assert (directory / "chunk-000001.npz").read_bytes()[:4] == b"PK\x03\x04" and \
        (directory / "chunk-000001.npz").stat().st_size > 100


def test_every_parallel_command_has_the_same_options_in_the_same_place(monkeypatch, run_cli):
    monkeypatch.setenv("COLUMNS", "200")
    for command in ("albedo", "normalize", "fit", "lut", "check"):
        code, out, _ = run_cli(command, "--help")
        assert code == 0
        # the parallel options are a help panel of their own (cli.common.PARALLEL_PANEL), in the same order
        lines = out.splitlines()
        start = next(i for i, line in enumerate(lines) if line.startswith("╭─ Parallel and resumable runs"))
        end = next(i for i in range(start, len(lines)) if lines[i].startswith("╰"))
        options = [line.split()[1] for line in lines[start + 1:end] if line.split()[1:2] and
                   line.split()[1].startswith("--")]
        expected = ["--workers", "--scheduler", "--connect-timeout", "--checkpoint"] + \
            ([] if command == "lut" else ["--chunk-cells"])
        assert options == expected, (command, options)
        assert "DASK_SCHEDULER_ADDRESS" in out


def test_bad_parallel_arguments_are_one_line_errors(run_cli):
    cases = [
        (["albedo", "lambert", "--theta", "0,10", "--workers", "0"], "--workers"),
        (["albedo", "lambert", "--theta", "0,10", "--workers", "2", "--scheduler", "tcp://127.0.0.1:9"],
         "--workers"),
        (["albedo", "lambert", "--theta", "0,10", "--chunk-cells", "0"], "--chunk-cells"),
        (["normalize", "lambert", "--workers", "2"], "--sweep"),
    ]
    for argv, where in cases:
        code, out, err = run_cli(*argv)
        assert code == 2 and out == "", argv
        assert err.count("\n") == 1 and where in err, err


def test_certified_bounds_travel_through_a_pool_and_a_checkpoint(tmp_path):
    pytest.importorskip("flint")
    model = bn.load("phong", n=10.0)
    theta = np.radians([0.0, 20.0, 40.0, 60.0])
    direct = bn.albedo(model, theta, method="certified", digits=20)
    job = CellsJob.of(model, theta, method="certified", digits=20, chunk_cells=2)
    first = albedo_cells(job, workers=2, checkpoint=tmp_path / "c")
    again = albedo_cells(job, workers=2, checkpoint=tmp_path / "c")  # read back from the files
    assert again.chunks_computed == 0
    for result in (first, again):
        assert result.lower.tolist() == direct.lower.tolist() and result.upper.tolist() == direct.upper.tolist()
        assert np.array_equal(result.value, direct.value)
    with pytest.raises(ArgumentError, match="certified"):
        albedo_cells(CellsJob.of(model, theta, digits=20), workers=1)


def test_a_scheduler_without_workers_is_refused_not_waited_on():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=0, processes=False, protocol="tcp", host="127.0.0.1",
                                  dashboard_address=":0") as empty:
        with pytest.raises(ArgumentError, match="no workers"):
            albedo_cells(_ggx_job(), scheduler=Scheduler(empty.scheduler_address, connect_timeout=1))
        with pytest.raises(ArgumentError, match="no workers"):  # a check too, before any work
            check("lambert", workers=None, scheduler=empty.scheduler_address)
    with pytest.raises(ArgumentError, match="cannot reach the Dask scheduler"):
        albedo_cells(_ggx_job(), scheduler="tcp://127.0.0.1:1")


# -- a check's albedo integrals through the parallel layer ---------------------------------------------------

@pytest.mark.slow
def test_check_on_two_local_workers_equals_the_in_process_check():
    serial = check(COOK_TORRANCE, **CHECK_ARGS)
    assert "parallel" not in serial.coverage and serial.status == "fail"  # a verdict with a worst case to compare
    pooled = check(COOK_TORRANCE, **CHECK_ARGS, workers=2, chunk_cells=8)
    spread = pooled.coverage["parallel"]
    # batches larger than one chunk went to the pool, the others ran here; same values either way
    assert spread["executors"] == ["in-process", "local processes"] and spread["workers"] == 2
    assert spread["chunks"] > spread["jobs"] and spread["evaluations_computed"] == pooled.coverage["evaluations"]
    assert _verdicts(pooled) == _verdicts(serial)
    assert pooled.results["energy"].value == serial.results["energy"].value  # the numbers, not just the verdicts


def _chunk_files(directory: Path) -> list[Path]:
    return sorted(directory.glob("*/chunk-*.npz"))


@pytest.mark.slow
def test_a_checkpointed_check_resumes_without_recomputing_finished_chunks(tmp_path, run_cli):
    directory = tmp_path / "check-ck"
    args = {**CHECK_ARGS, "workers": 1, "chunk_cells": 8, "checkpoint": directory}
    first = check(COOK_TORRANCE, **args)
    files = _chunk_files(directory)
    assert (directory / "check.json").is_file() and len(files) == first.coverage["parallel"]["chunks"]
    total = first.coverage["evaluations"]
    assert first.coverage["parallel"]["evaluations_computed"] == total
    assert _verdicts(first) == _verdicts(check(COOK_TORRANCE, **CHECK_ARGS))

    # a run killed part way leaves whole chunk files (written atomically): drop every third one
    lost = files[::3]
    lost_evaluations = 0
    for path in lost:
        with np.load(path) as data:
            lost_evaluations += int(data["evaluations"].sum())
        path.unlink()
    assert lost_evaluations > 0
    resumed = check(COOK_TORRANCE, **args)
    assert _verdicts(resumed) == _verdicts(first)  # the budget counted restored cells: the same search
    spread = resumed.coverage["parallel"]
    assert spread["evaluations_computed"] == lost_evaluations  # by evaluation counts: only what was lost
    assert spread["chunks_from_checkpoint"] == len(files) - len(lost)
    assert resumed.coverage["evaluations"] == total

    # the command line on the complete checkpoint computes no integral and prints the same verdicts
    argv = ["check", str(COOK_TORRANCE), "--only", "energy,normalization", "--normalized", "--at", "view",
            "--points", "8", "--budget", "3e6evals", "--chunk-cells", "8", "--workers", "1", "--checkpoint",
            str(directory), "--json"]
    code, out, err = run_cli(*argv)
    assert code == 1, err
    report = json.loads(out)["reports"][0]
    assert report["coverage"]["parallel"]["evaluations_computed"] == 0
    assert f"({len(files)} from the checkpoint)" in err
    assert report["checks"]["energy"]["value"] == first.results["energy"].value


def test_check_checkpoint_refusals_are_one_line_errors(tmp_path, run_cli):
    directory = tmp_path / "ck"
    base = ["check", "lambert", "--points", "2", "--budget", "2e5evals", "--chunk-cells", "8", "--workers", "1"]
    code, _, err = run_cli(*base, "--checkpoint", str(directory))
    assert code == 0, err
    before = {p: p.read_bytes() for p in directory.rglob("*") if p.is_file()}
    cases = [
        # under a budget of seconds a rerun asks for other integrals: refused, nothing written
        (["check", "lambert", "--budget", "5", "--checkpoint", str(tmp_path / "other")], "budget of evaluations"),
        (["check", "lambert", "phong", "--budget", "2e5evals", "--checkpoint", str(tmp_path / "other")], "one MODEL"),
        ([*base, "--tolerance", "1e-5", "--checkpoint", str(directory)], "different check"),
        ([*base, "--checkpoint", str(tmp_path)], "holds no brdfnorm check checkpoint"),  # not empty, not ours
        (["check", "lambert", "--workers", "2", "--scheduler", "tcp://127.0.0.1:9"], "--workers"),
        (["check", "lambert", "--chunk-cells", "0"], "--chunk-cells"),
    ]
    for argv, words in cases:
        code, out, err = run_cli(*argv)
        assert code == 2 and out == "" and err.count("\n") == 1 and words in err, (argv, err)
    assert not (tmp_path / "other").exists()
    assert {p: p.read_bytes() for p in directory.rglob("*") if p.is_file()} == before  # nothing clobbered
    with pytest.raises(ArgumentError, match="cannot travel"):  # a model without a source stays in this process
        check(LocalLobe(), workers=2, budget=Budget(seconds=None, evaluations=10_000))


class LocalLobe(bn.Model):
    """A lobe defined in a test: no source to send to another process."""

    name = "local"

    def evaluate(self, L, V, params):
        return np.full(L.shape[:-1] + (1,), 1 / np.pi)


@pytest.mark.slow
def test_a_check_stopped_by_sigterm_stops_its_workers_and_resumes(tmp_path):
    directory = tmp_path / "check-ck"
    process = subprocess.Popen([*CLI, "check", str(COOK_TORRANCE), "--points", "8", "--budget", "6e6evals",
                                "--chunk-cells", "8", "--workers", "2", "--checkpoint", str(directory), "--json"],
                               env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    children = {}
    while len(_chunk_files(directory)) < 4:
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "no chunk was saved"
        children.update({c.pid: c for c in psutil.Process(process.pid).children(recursive=True)})
        time.sleep(0.02)
    process.send_signal(signal.SIGTERM)
    out, err = process.communicate(timeout=60)
    assert process.returncode == 143 and out == "" and err.strip() == "error: interrupted by SIGTERM", err
    _, alive = psutil.wait_procs(list(children.values()), timeout=5)
    assert not alive, [(c.pid, c.cmdline()) for c in alive]
    saved = len(_chunk_files(directory))

    budget = Budget(seconds=None, evaluations=6_000_000)
    resumed = check(COOK_TORRANCE, points=8, budget=budget, chunk_cells=8, workers=1, checkpoint=directory)
    assert _verdicts(resumed) == _verdicts(check(COOK_TORRANCE, points=8, budget=budget))
    spread = resumed.coverage["parallel"]
    assert spread["chunks_from_checkpoint"] >= saved >= 4
    assert 0 < spread["evaluations_computed"] < resumed.coverage["evaluations"]
