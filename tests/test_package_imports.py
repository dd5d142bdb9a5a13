"""``import brdfnorm`` imports what its names need, when they are first used (PEP 562's module ``__getattr__`` in
:mod:`brdfnorm`, :mod:`brdfnorm.materials` and :mod:`brdfnorm.inputs`), and the public API is the same as when it
imported them at once: every name of ``__all__`` reachable, listed by ``dir()``, importable with ``from brdfnorm
import``; every subpackage reachable as an attribute. Run in new processes (``sys.modules`` of this one holds
whatever the other tests imported)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from helpers.imports import imported
from helpers.paths import SRC

#: What ``import brdfnorm`` must not import: each costs the start of a command that does not use it (the engine,
#: the models and scipy.special ~0.2 s, the materials ~0.1 s, Numba ~0.3 s; numpy before the command line has
#: set its BLAS threads: docs/performance.md, eighth round).
HEAVY = ("brdfnorm.engine", "brdfnorm.models", "brdfnorm.materials", "brdfnorm.materials.model",
         "brdfnorm.inputs.npz", "brdfnorm.normalization", "numpy", "scipy", "scipy.special", "numba")


def _run(code: str) -> dict:
    return imported(code, HEAVY)


def test_import_brdfnorm_imports_none_of_the_heavyimported():
    assert _run("import brdfnorm") == dict.fromkeys(HEAVY, False)


def test_a_material_file_check_does_not_import_the_material_model():
    # load() of a .brdf path asks materials.files whether it is a material file: the OpenPBR model stays out
    imported = _run("import brdfnorm.materials.files")
    assert not imported["brdfnorm.materials.model"] and not imported["numba"]


def test_the_probe_sees_them_once_used():
    # (the tests above cannot pass by a probe that never sees a module)
    imported = _run("import brdfnorm, numba, scipy.special\nbrdfnorm.albedo\nbrdfnorm.normalize\n"
                    "brdfnorm.materials.OpenPBR\nfrom brdfnorm.inputs import npz_arrays")
    assert imported == dict.fromkeys(HEAVY, True)


def test_the_public_names_are_the_same():
    import brdfnorm
    from brdfnorm.engine.methods import AlbedoResult, albedo
    from brdfnorm.models import REGISTRY, Model
    from brdfnorm.normalization import NormalizationResult, normalize

    expected = {"AlbedoResult": AlbedoResult, "albedo": albedo, "REGISTRY": REGISTRY, "Model": Model,
                "NormalizationResult": NormalizationResult, "normalize": normalize}
    for name, value in expected.items():
        assert getattr(brdfnorm, name) is value
    assert set(brdfnorm.__all__) <= set(dir(brdfnorm))
    assert {"load", "load_text", "__version__", "albedo", "REGISTRY"} <= set(dir(brdfnorm))
    namespace: dict = {}
    exec("from brdfnorm import *", namespace)  # noqa: S102 — the star import resolves every lazy name
    assert set(brdfnorm.__all__) <= set(namespace)


def test_subpackages_are_attributes_and_unknown_names_are_not():
    import brdfnorm

    assert brdfnorm.materials.OpenPBR is brdfnorm.REGISTRY["openpbr"]
    assert brdfnorm.lut.compute is not None and brdfnorm.inputs.npz_arrays is not None
    for missing in ("no_such_name", "_private"):
        with pytest.raises(AttributeError, match=missing):
            getattr(brdfnorm, missing)
    with pytest.raises(AttributeError):
        brdfnorm.materials.no_such_name  # noqa: B018
    with pytest.raises(AttributeError):
        brdfnorm.inputs.no_such_name  # noqa: B018


def test_load_still_finds_each_kind_of_model(tmp_path):
    # in a new process: the lazy load() reaches the registry, material files and .brdf files itself
    material = tmp_path / "m.toml"
    material.write_text('model = "openpbr"\n', encoding="utf-8")
    code = (f"import brdfnorm\nm = brdfnorm.load('ggx', alpha=0.3)\nassert m.name == 'ggx'\n"
            f"assert type(brdfnorm.load({str(material)!r})).__name__ == 'OpenPBR'\n"
            f"assert brdfnorm.load({str(SRC.parent / 'examples' / 'ggx.brdf')!r}).name == 'ggx'\n")
    env = {**os.environ, "PYTHONPATH": str(SRC) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True, text=True)


POOL = ("brdfnorm.parallel.executors", "brdfnorm.parallel.job", "brdfnorm.parallel.checkpoint", "multiprocessing")


def test_a_table_on_threads_does_not_import_the_process_pool():
    # brdfnorm.parallel's names are imported at first use: lut.table (threads, the glass tables' pool in a function)
    assert imported("import brdfnorm.lut.table, brdfnorm.parallel.threads", POOL) == dict.fromkeys(POOL, False)
    assert imported("from brdfnorm.parallel import albedo_cells", POOL) == dict.fromkeys(POOL, True)


def test_the_parallel_package_exports_the_same_names():
    from brdfnorm import parallel
    from brdfnorm.parallel import cells, cores, executors, job

    assert set(parallel.__all__) <= set(dir(parallel))
    for name in parallel.__all__:
        owner = next(m for m in (cells, cores, executors, job) if hasattr(m, name))
        assert getattr(parallel, name) is getattr(owner, name)
    assert executors.local_cores is cores.local_cores  # (still importable from where it was)
    with pytest.raises(AttributeError, match="no_such_name"):
        parallel.no_such_name  # noqa: B018
