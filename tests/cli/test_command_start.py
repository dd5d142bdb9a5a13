"""The command line's start and end (:func:`brdfnorm.cli.main`): a run imports the module of the command it names
only (:data:`brdfnorm.cli.COMMANDS`), and the process ends after flushing its streams and running its ``atexit``
functions, without the interpreter's teardown, unless a thread or child process still runs (docs/performance.md,
eighth round). Each case runs ``main()`` as the process's command line, in a new process."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from helpers.paths import EXAMPLES, SRC

#: Command modules that ``lut`` does not use: none may be imported by ``brdfnorm lut``.
OTHERS = ("brdfnorm.cli.fit", "brdfnorm.cli.audit", "brdfnorm.cli.check", "brdfnorm.cli.report",
          "brdfnorm.cli.explore", "brdfnorm.cli.verify", "brdfnorm.cli.materials", "brdfnorm.fit",
          "brdfnorm.check", "brdfnorm.report")


def _process(code: str, *argv: str, stdin: str | None = None) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(SRC) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    return subprocess.run([sys.executable, "-c", code, *argv], env=env, capture_output=True, text=True, input=stdin,
                          timeout=300)


def _modules_after(*argv: str) -> dict[str, bool]:
    """Which of OTHERS the command line ``argv`` imported (read by an atexit function: main() ends the process)."""
    code = ("import atexit, json, sys\n"
            f"atexit.register(lambda: print(json.dumps({{m: m in sys.modules for m in {list(OTHERS)!r}}})))\n"
            "from brdfnorm.cli import main\nsys.argv[0] = 'brdfnorm'\nmain()\n")
    done = _process(code, *argv)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_a_command_imports_its_own_module_only():
    assert _modules_after("lut", "--help") == dict.fromkeys(OTHERS, False)


def test_the_root_help_imports_every_command():
    # (the test above cannot pass by a probe that never sees the modules)
    imported = _modules_after("--help")
    assert all(imported[m] for m in OTHERS if m.startswith("brdfnorm.cli."))


def test_a_table_not_on_a_terminal_does_not_import_rich():
    # rich (~0.1 s) draws the progress bar on a terminal and prints tables; `lut` to a file needs neither
    code = ("import atexit, sys\natexit.register(lambda: print('rich' in sys.modules))\n"
            "from brdfnorm.cli import main\nsys.argv[0] = 'brdfnorm'\nmain()\n")
    args = ["lut", str(EXAMPLES / "ggx.brdf"), "--axis", "mu=0.5", "--axis", "roughness=0.5", "-p", "f0=1",
            "--rtol", "1e-6", "--no-average", "-o", "-", "--format", "csv"]
    plain = _process(code, *args)
    assert plain.returncode == 0 and plain.stdout.splitlines()[-1] == "False", plain.stderr
    # the probe sees it where rich is told stderr is a terminal (its FORCE_COLOR): the bar is drawn
    env = {**os.environ, "FORCE_COLOR": "1", "PYTHONPATH": str(SRC) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    forced = subprocess.run([sys.executable, "-c", code, *args], env=env, capture_output=True, text=True,
                            timeout=300)
    assert forced.returncode == 0 and forced.stdout.splitlines()[-1] == "True" and "\x1b[" in forced.stderr


def test_commands_names_every_command_by_its_module():
    from brdfnorm.cli import COMMANDS, app

    registered = {(c.name or c.callback.__name__).replace("_", "-"): c.callback.__module__
                  for c in app.registered_commands}
    assert registered == {name: f"brdfnorm.cli.{module}" for name, module in COMMANDS.items()}


def test_chosen_reads_the_command_word():
    from brdfnorm.cli import chosen

    assert chosen(["lut", "--help"]) == ["lut"]
    assert chosen(["--version"]) is None and chosen([]) is None
    assert chosen(["lutt", "ggx"]) is None  # unknown: every command, for the "did you mean"
    assert chosen(["--", "lut"]) is None


def test_a_table_through_the_process_equals_the_in_process_one(tmp_path, run_cli):
    # the whole table reaches a pipe (flushed before the process ends), and equals what main(argv) writes
    args = ["lut", str(EXAMPLES / "ggx.brdf"), "--axis", "mu=0.2,0.7", "--axis", "roughness=0.3,0.6", "-p",
            "f0=1", "--rtol", "1e-8", "-o", "-", "--format", "csv"]
    done = _process("import sys\nfrom brdfnorm.cli import main\nsys.argv[0] = 'brdfnorm'\nmain()\n", *args)
    assert done.returncode == 0, done.stderr
    code, out, _ = run_cli(*args)
    assert code == 0 and done.stdout == out and out.count("\n") > 4


def test_exit_codes_and_atexit_functions_are_kept():
    code = ("import atexit, sys\natexit.register(lambda: print('atexit ran', file=sys.stderr))\n"
            "from brdfnorm.cli import main\nsys.argv[0] = 'brdfnorm'\nmain()\n")
    bad = _process(code, "albedo", "no-such-model", "0")
    assert bad.returncode == 2 and bad.stderr.startswith("error:") and "atexit ran" in bad.stderr
    good = _process(code, "models")
    assert good.returncode == 0 and "ggx" in good.stdout and "atexit ran" in good.stderr


def test_a_running_thread_is_waited_for():
    # a thread that is no daemon (a library's, a plug-in's) finishes before the process ends, as at a normal exit:
    # here one that ends a second after the command's module is imported, long after the command's output
    code = ("import sys, threading, time\n"
            "def later():\n    while 'brdfnorm.cli.core' not in sys.modules:\n        time.sleep(0.01)\n"
            "    time.sleep(1.0)\n    print('thread done', flush=True)\n"
            "threading.Thread(target=later).start()\n"
            "from brdfnorm.cli import main\nsys.argv[0] = 'brdfnorm'\nmain()\n")
    done = _process(code, "models")
    assert done.returncode == 0 and "built-in models" in done.stdout and "thread done" in done.stdout


def test_a_profiled_run_writes_its_profile(tmp_path):
    # cProfile writes its file after main() returns: under a profiler the process ends the interpreter's way
    env = {**os.environ, "PYTHONPATH": str(SRC) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    profile = tmp_path / "run.prof"
    done = subprocess.run([sys.executable, "-m", "cProfile", "-o", str(profile), "-m", "brdfnorm", "models"], env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and "ggx" in done.stdout and profile.stat().st_size > 0


def test_one_blas_thread_unless_the_user_sets_them():
    # the process's BLAS threads spin on the cores its table threads compute on: one, where the user sets none
    from brdfnorm.cli import BLAS_THREADS

    code = ("import atexit, os, sys\n"
            "atexit.register(lambda: print(os.environ.get('OPENBLAS_NUM_THREADS'), os.environ.get('MKL_NUM_THREADS'),"
            " 'numpy' in sys.modules))\nfrom brdfnorm.cli import main\nsys.argv[0] = 'brdfnorm'\nmain()\n")
    base = {k: v for k, v in os.environ.items() if k not in BLAS_THREADS}
    base["PYTHONPATH"] = str(SRC) + os.pathsep + os.environ.get("PYTHONPATH", "")
    for given, expected in (({}, "1 1 True"), ({"OMP_NUM_THREADS": "2"}, "None None True"),
                            ({"OPENBLAS_NUM_THREADS": "3"}, "3 None True")):
        done = subprocess.run([sys.executable, "-c", code, "albedo", "ggx", "--theta", "30"], env={**base, **given},
                              capture_output=True, text=True, timeout=300)
        assert done.returncode == 0 and done.stdout.splitlines()[-1] == expected, (given, done.stdout, done.stderr)


def test_main_with_arguments_leaves_the_process_and_the_collector_alone():
    import gc

    from brdfnorm.cli import main

    try:
        main(["--version"])
    except SystemExit as done:
        assert done.code in (0, None)
    assert gc.isenabled()
