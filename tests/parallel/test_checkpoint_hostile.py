"""Tampered checkpoints (issue 35): a chunk whose digest matches the job is still checked as data and computed
again when it fails, a checkpoint directory holding foreign files is refused, and two processes starting the same
job on a new directory at once both succeed."""

from __future__ import annotations

import io
import multiprocessing
import warnings
from pathlib import Path

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.errors import ArgumentError
from brdfnorm.parallel import CellsJob, albedo_cells
from brdfnorm.parallel.checkpoint import Checkpoint


def _job() -> CellsJob:
    return CellsJob.of(bn.load("ggx", alpha=0.5), np.linspace(0.1, 1.2, 8), 0.0, rtol=1e-8, chunk_cells=4)


def _tamper(path: Path, change) -> None:
    with np.load(path, allow_pickle=False) as data:
        arrays = {name: data[name] for name in data.files}
    change(arrays)
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    path.write_bytes(buffer.getvalue())


def _set(name, index, value):
    def change(arrays):
        array = arrays[name].copy()
        array[index] = value
        arrays[name] = array
    return change


TAMPERS = {
    "nan-converged": (_set("value", (1, 0), np.nan), "non-finite value"),
    "negative-error": (_set("error", (0, 0), -1e-3), "negative error estimate"),
    "theta-7-rad": (_set("theta", 2, 7.0), "θ or φ"),
    "negative-count": (_set("evaluations", 3, -5), "negative evaluation count"),
    "complex-values": (lambda a: a.update(value=a["value"] + 1j), "complex"),
    "wrong-shape": (lambda a: a.update(error=a["error"][:2]), "shape"),
    "bool-as-float": (lambda a: a.update(converged=a["converged"].astype(float)), "converged holds"),
    "text-values": (lambda a: a.update(value=a["value"].astype(str)), "text"),
    "other-cells": (_set("cells", 0, 5), "cells are not"),
}


@pytest.mark.parametrize("kind", list(TAMPERS))
def test_a_tampered_chunk_is_computed_again_never_used(tmp_path, kind):
    job = _job()
    first = albedo_cells(job, workers=1, checkpoint=tmp_path / "c")
    change, reason = TAMPERS[kind]
    _tamper(tmp_path / "c" / "chunk-000000.npz", change)
    with pytest.warns(UserWarning, match="chunk-000000.npz") as caught:
        again = albedo_cells(job, workers=1, checkpoint=tmp_path / "c")
    messages = [str(w.message) for w in caught if "chunk-000000" in str(w.message)]
    assert len(messages) == 1 and reason in messages[0] and "again" in messages[0], messages
    assert again.chunks_computed == 1
    np.testing.assert_array_equal(again.value, first.value)
    np.testing.assert_array_equal(again.error, first.error)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the recomputed chunk replaced the tampered one
        assert albedo_cells(job, workers=1, checkpoint=tmp_path / "c").chunks_computed == 0


def test_a_checkpoint_holding_foreign_files_is_refused(tmp_path):
    job = _job()
    albedo_cells(job, workers=1, checkpoint=tmp_path / "c")
    (tmp_path / "c" / "notes.txt").write_text("mine")
    with pytest.raises(ArgumentError, match="not this checkpoint's.*notes.txt"):
        albedo_cells(job, workers=1, checkpoint=tmp_path / "c")
    assert (tmp_path / "c" / "notes.txt").read_text() == "mine"


def test_lut_refuses_a_checkpoint_directory_holding_foreign_files(tmp_path, run_cli):
    root = tmp_path / "tables"
    root.mkdir()
    (root / "notes.txt").write_text("mine")
    out = tmp_path / "t.npz"
    code, stdout, err = run_cli("lut", "ggx", "--axis", "mu=0.5:1:3", "--checkpoint", str(root), "-o",
                                str(out))
    assert code == 2 and err.startswith("error: --checkpoint: ") and "notes.txt" in err and err.count("\n") == 1
    assert stdout == "" and not out.exists() and sorted(p.name for p in root.iterdir()) == ["notes.txt"]


def _start(directory: str, barrier, results) -> None:
    barrier.wait()  # both processes open the new directory at the same moment
    try:
        cells = albedo_cells(_job(), workers=1, checkpoint=directory)
        results.put(("ok", cells.value.tobytes()))
    except Exception as error:  # noqa: BLE001 — reported to the test
        results.put(("error", f"{type(error).__name__}: {error}"))


def test_two_processes_starting_one_job_on_a_new_directory_both_succeed(tmp_path):
    context = multiprocessing.get_context("fork")
    for attempt in range(8):
        directory = tmp_path / f"c{attempt}"
        barrier, results = context.Barrier(2), context.Queue()
        processes = [context.Process(target=_start, args=(str(directory), barrier, results)) for _ in range(2)]
        for process in processes:
            process.start()
        outcomes = [results.get(timeout=120) for _ in processes]
        for process in processes:
            process.join(30)
        assert [o[0] for o in outcomes] == ["ok", "ok"], outcomes
        assert outcomes[0][1] == outcomes[1][1]
        assert sorted(p.name for p in directory.iterdir() if not p.name.startswith("chunk-")) == \
            ["cells.npz", "job.json"]
        assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")], "a staging directory was left"
        Checkpoint.open(directory, _job(), lambda: pytest.fail("the plan is stored"))
