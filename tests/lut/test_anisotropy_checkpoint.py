"""Anisotropic tables, issue #45 item 3: ``checkpoint=DIR`` (``lut --anisotropy … --checkpoint DIR``) — a table
interrupted after some chunks resumes from the chunks on disk and ends bit-identical to an uninterrupted run; a
damaged chunk is computed again; a directory holding another table or foreign files is refused in one line."""

from __future__ import annotations

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.errors import ArgumentError
from brdfnorm.lut import anisotropy

AXES = {"mu": [0.3, 0.7, 1.0], "alpha": [0.2, 0.5], "aspect": [0.4, 1.0]}


@pytest.fixture
def small_chunks(monkeypatch):
    monkeypatch.setattr(anisotropy, "CHUNK_CELLS", 4)  # 12 cells: 3 chunks of E, 1 of E_avg


@pytest.fixture(scope="module")
def uninterrupted():
    return anisotropy.compute(bn.load("ggx"), AXES, anisotropy="aspect", rtol=1e-5)


def interrupt_after(monkeypatch, calls: int) -> list[int]:
    """Make the chunk function raise KeyboardInterrupt (what Ctrl-C or SIGTERM raises) on call ``calls + 1``."""
    real, seen = anisotropy._cells_task, []

    def task(*args):
        if len(seen) == calls:
            raise KeyboardInterrupt
        seen.append(1)
        return real(*args)

    monkeypatch.setattr(anisotropy, "_cells_task", task)
    return seen


def test_interrupted_table_resumes_bit_identical(small_chunks, uninterrupted, monkeypatch, tmp_path):
    seen = interrupt_after(monkeypatch, 2)
    with pytest.raises(KeyboardInterrupt):
        anisotropy.compute(bn.load("ggx"), AXES, anisotropy="aspect", rtol=1e-5, checkpoint=tmp_path)
    assert sorted(p.name for p in (tmp_path / "E").iterdir()) == ["chunk-000000.npz", "chunk-000001.npz",
                                                                  "job.json"]
    monkeypatch.undo()
    monkeypatch.setattr(anisotropy, "CHUNK_CELLS", 4)
    seen = interrupt_after(monkeypatch, 99)
    resumed = anisotropy.compute(bn.load("ggx"), AXES, anisotropy="aspect", rtol=1e-5, checkpoint=tmp_path)
    assert len(seen) == 1  # only the third chunk was computed
    assert list(resumed) == list(uninterrupted)
    for name in uninterrupted:
        assert np.array_equal(resumed[name], uninterrupted[name]), name
    # once more: everything from disk, nothing computed
    seen.clear()
    again = anisotropy.compute(bn.load("ggx"), AXES, anisotropy="aspect", rtol=1e-5, checkpoint=tmp_path)
    assert not seen and np.array_equal(again["E_avg"], uninterrupted["E_avg"])


def test_damaged_chunk_is_computed_again(small_chunks, uninterrupted, tmp_path):
    anisotropy.compute(bn.load("ggx"), AXES, anisotropy="aspect", rtol=1e-5, checkpoint=tmp_path, average=False)
    chunk = tmp_path / "E" / "chunk-000001.npz"
    chunk.write_bytes(chunk.read_bytes()[:100])
    with pytest.warns(UserWarning, match="chunk-000001.npz: unreadable"):
        table = anisotropy.compute(bn.load("ggx"), AXES, anisotropy="aspect", rtol=1e-5, checkpoint=tmp_path,
                                   average=False)
    assert np.array_equal(table["E"], uninterrupted["E"])


def test_refusals(small_chunks, tmp_path):
    anisotropy.compute(bn.load("ggx"), {"mu": [1.0], "alpha": [0.3], "aspect": [0.5]}, anisotropy="aspect",
                       rtol=1e-5, checkpoint=tmp_path, average=False)
    with pytest.raises(ArgumentError, match="different table"):  # another rtol: another table
        anisotropy.compute(bn.load("ggx"), {"mu": [1.0], "alpha": [0.3], "aspect": [0.5]}, anisotropy="aspect",
                           rtol=1e-6, checkpoint=tmp_path, average=False)
    (tmp_path / "E" / "notes.txt").write_text("mine")
    with pytest.raises(ArgumentError, match="not this checkpoint's"):
        anisotropy.compute(bn.load("ggx"), {"mu": [1.0], "alpha": [0.3], "aspect": [0.5]}, anisotropy="aspect",
                           rtol=1e-5, checkpoint=tmp_path, average=False)
    other = tmp_path / "other"
    (other / "E").mkdir(parents=True)
    (other / "E" / "data.csv").write_text("1,2")
    with pytest.raises(ArgumentError, match="holds no brdfnorm checkpoint"):
        anisotropy.compute(bn.load("ggx"), {"mu": [1.0], "alpha": [0.3], "aspect": [0.5]}, anisotropy="aspect",
                           rtol=1e-5, checkpoint=other, average=False)



def test_cli_checkpoint(run_cli, tmp_path):
    args = ["lut", "ggx", "--anisotropy", "burley", "--axis", "mu=0.5,1", "--axis", "alpha=0.3", "--axis",
            "anisotropy=0.5", "--rtol", "1e-5", "--no-average", "--checkpoint", str(tmp_path / "ck")]
    for name in ("a.npz", "b.npz"):
        code, _, err = run_cli(*args, "-o", str(tmp_path / name))
        assert code == 0, err
    assert (tmp_path / "ck" / "E" / "job.json").is_file()
    assert np.array_equal(lut.load(tmp_path / "a.npz")["E"], lut.load(tmp_path / "b.npz")["E"])
    code, _, err = run_cli(*[a if a != "alpha=0.3" else "alpha=0.4" for a in args], "-o", str(tmp_path / "c.npz"))
    assert code == 2 and err.startswith("error:") and "different table" in err and "Traceback" not in err
    assert not (tmp_path / "c.npz").exists()


@pytest.mark.slow
def test_resume_on_two_workers_is_bit_identical(small_chunks, uninterrupted, tmp_path):
    anisotropy.compute(bn.load("ggx"), AXES, anisotropy="aspect", rtol=1e-5, checkpoint=tmp_path, average=False)
    for index in (0, 2):  # two chunks to compute: they go to the two processes
        (tmp_path / "E" / f"chunk-00000{index}.npz").unlink()
    table = anisotropy.compute(bn.load("ggx"), AXES, anisotropy="aspect", rtol=1e-5, checkpoint=tmp_path,
                               workers=2)
    for name in uninterrupted:
        assert np.array_equal(table[name], uninterrupted[name]), name
