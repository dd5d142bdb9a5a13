"""The command line's start imports only what every command needs (issue 39, item 5: `lut examples/ggx.brdf` 32×32
≤ 2 s through the CLI): the anisotropic and certified table routes, scipy.optimize (fits) and typer's rich help
printer (markdown, syntax highlighting) are imported where a command uses them. Measured on the 2-core machine:
``import brdfnorm.cli`` 0.83 → 0.51 CPU s (docs/performance.md)."""

from __future__ import annotations

from helpers.imports import imported

LAZY = ("brdfnorm.lut.anisotropy", "brdfnorm.engine.routes.anisotropic", "brdfnorm.lut.certified", "scipy.optimize",
        "typer.rich_utils")


def _imported(code: str) -> dict[str, bool]:
    return imported(code, LAZY)


def test_the_command_line_starts_without_the_optional_routes():
    assert _imported("import brdfnorm.cli") == dict.fromkeys(LAZY, False)


def test_the_probe_sees_them_once_a_command_needs_them():
    # (the test above cannot pass by a probe that never sees a module)
    # and the help printed puts the project's options panel in typer's place (cli.help, installed at first help)
    code = ("import brdfnorm.cli\nimport brdfnorm.lut.anisotropy, brdfnorm.lut.certified\n"
            "from brdfnorm.fit import families\nfamilies._optimize()\n"
            "from brdfnorm.cli import help, main\ntry:\n    main(['lut', '--help'])\n"
            "except SystemExit as done:\n    assert not done.code\n"
            "import typer.rich_utils\nassert typer.rich_utils._print_options_panel is help.options_panel")
    assert _imported(code) == dict.fromkeys(LAZY, True)
