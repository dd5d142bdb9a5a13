"""Help text that reads well at 80 columns: applied once to the click command tree typer builds.

Typer shows each parameter's Python type beside it (``<bool>``, ``<float>``, ``<light|view>``) and wraps a
required argument in braces on the usage line (``{MODEL}``); neither means anything to a user. This pass gives
every option a metavar a person reads (a flag none, a choice its values, a number ``N`` or ``NUMBER``), drops
the type column of arguments, writes arguments plainly on the usage line, and reflows each command's help so that
the lines of a docstring paragraph are one paragraph (typer keeps the docstring's line breaks). Commands are
listed in the order a new user meets them (`ORDER`).

Typer lays an option out in five columns (name, short name, negations, metavar, help); at 80 columns the help
column was 23 characters wide and long words in it were cut with "…". :func:`options_panel` replaces typer's
panel printer with two columns: the option as it is typed (``-p, --param NAME=VALUE``) and its help; an option
longer than :data:`NAME_WIDTH` gets its own line with the help below it, and long words fold rather than cut.
"""

from __future__ import annotations

import re
from pathlib import Path

from typer.core import TyperArgument, TyperGroup, TyperOption

#: The commands in the order a user meets them: discover, compute, tabulate and fit, audit, explore, study.
ORDER = ("models", "info", "albedo", "normalize", "lut", "fit", "check", "audit", "explore", "verify", "report")


#: The widest option column (characters); a longer option is on a line of its own, its help below it.
NAME_WIDTH = 24


def _typed(param) -> str:
    """The option as a user types it: short and long names, then the metavar (an argument: its name)."""
    if isinstance(param, TyperArgument):
        return param.display_name_raw or param.name.upper()
    names = sorted(param.opts, key=lambda o: (o.startswith("--"), o)) + list(param.secondary_opts)
    metavar = param.metavar or ""
    return ", ".join(names) + (f" {metavar}" if metavar else "")


def options_panel(*, name: str, params, ctx, markup_mode, console) -> None:
    """Typer's options panel in two columns (the module docstring says why); same signature as the function it
    replaces, ``typer.rich_utils._print_options_panel``."""
    import typer.rich_utils as rich_utils
    from rich import box
    from rich.console import Group
    from rich.padding import Padding
    from rich.panel import Panel
    from rich.table import Table
    from rich.text import Text

    if not params:
        return
    typed = {id(p): _typed(p) for p in params}
    width = max((len(t) + 3 for t in typed.values() if len(t) + 3 <= NAME_WIDTH), default=NAME_WIDTH)  # marker, gap
    rows = []
    for param in params:
        marker = Text("* ", style=rich_utils.STYLE_REQUIRED_SHORT) if param.required else Text("  ")
        shown = rich_utils.highlighter(marker + Text(typed[id(param)]))
        helped = rich_utils._get_parameter_help(param=param, ctx=ctx, markup_mode=markup_mode)
        for item in getattr(helped, "renderables", ()):
            if isinstance(item, Text):
                item.overflow = "fold"  # a word wider than the column folds onto the next line, never cut
        if shown.cell_len >= width:
            rows.append(Group(shown, Padding(helped, (0, 0, 0, width + 1))))
            continue
        row = Table.grid(padding=(0, 1), expand=True)
        row.add_column(width=width, no_wrap=True)
        row.add_column(overflow="fold", ratio=1)
        row.add_row(shown, helped)
        rows.append(row)
    console.print(Panel(Group(*rows), border_style=rich_utils.STYLE_OPTIONS_PANEL_BORDER, title=name,
                        title_align=rich_utils.ALIGN_OPTIONS_PANEL, box=box.ROUNDED))


def _install() -> None:
    """Put :func:`options_panel` in typer's place: at the first help printed, not at import (typer's rich helpers
    import markdown and syntax highlighting, ~0.15 s of every command's start)."""
    import typer.rich_utils as rich_utils

    rich_utils._print_options_panel = options_panel


class OrderedGroup(TyperGroup):
    """The root group: commands listed in :data:`ORDER` (any other after them, in registration order)."""

    def list_commands(self, ctx) -> list[str]:
        names = super().list_commands(ctx)
        return sorted(names, key=lambda name: ORDER.index(name) if name in ORDER else len(ORDER))


def _metavar(option: TyperOption) -> str:
    if option.is_flag or option.count:
        return ""
    kind = option.type_descriptor
    if kind.is_choice:
        choices = "|".join(str(getattr(choice, "value", choice)) for choice in kind.choices or ())
        # A long list of choices would take the help text's width: the option's name, then (the help lists them).
        return choices if len(choices) <= 16 else option.name.upper().replace("_", "-")
    annotation = kind.annotation
    if annotation is int:
        return "N"
    if annotation is float:
        return "NUMBER"
    if isinstance(annotation, type) and issubclass(annotation, Path):
        return "PATH"
    return "TEXT"


def _reflow(text: str | None) -> str | None:
    """Join the lines of each paragraph (a blank line separates paragraphs; an indented or bulleted line starts
    a new line, as in a list)."""
    if not text:
        return text
    paragraphs = re.split(r"\n\s*\n", text.strip())
    out = []
    for paragraph in paragraphs:
        lines = [line.strip() for line in paragraph.splitlines()]
        joined = lines[0]
        for line in lines[1:]:
            joined += ("\n" if line.startswith(("-", "*", "•")) else " ") + line
        out.append(joined)
    return "\n\n".join(out)


def _plain_usage(argument: TyperArgument):
    def usage() -> str:
        name = argument.metavar or argument.name.upper()
        name = name if argument.required else f"[{name}]"
        return name + ("..." if argument.nargs != 1 else "")
    return usage


def escape(text: str) -> str:
    """``text`` with rich's markup escaped (``rich.markup.escape``): rich imported only for a text that has any to
    escape — a ``[`` or a final backslash (what that function's pattern needs) — and so not at every command's start
    (rich costs ~0.1 s; the help printer imports it when it prints)."""
    if "[" not in text and not text.endswith("\\"):
        return text
    from rich.markup import escape as rich_escape

    return rich_escape(text)


def tidy(command):
    """Apply the readable-help pass to ``command`` and every subcommand (idempotent)."""
    if getattr(command, "_brdfnorm_tidy", False):
        return command
    command._brdfnorm_tidy = True
    # Help texts are plain text: "pip install 'brdfnorm[certified]'" must not lose "[certified]" as rich markup.
    command.help = escape(_reflow(command.help)) if command.help else command.help
    if command.short_help is None and command.help:
        command.short_help = command.help.split("\n\n")[0]  # the whole first paragraph: never cut
    help_option = command.get_help_option

    def get_help_option(ctx, _original=help_option):
        option = _original(ctx)
        if option is not None:
            option.metavar = ""  # a flag: no "<bool>"
        return option

    command.get_help_option = get_help_option
    format_help = command.format_help

    def formatted_help(ctx, formatter, _original=format_help):
        _install()
        return _original(ctx, formatter)

    command.format_help = formatted_help
    for param in command.params:
        if isinstance(param, TyperOption) and param.metavar is None:
            param.metavar = _metavar(param)
            kind = param.type_descriptor
            if kind.is_choice and param.metavar and "|" not in param.metavar:
                choices = [str(getattr(choice, "value", choice)) for choice in kind.choices or ()]
                param.help = f"{param.help or ''} One of: {', '.join(choices)}.".strip()
        elif isinstance(param, TyperArgument):
            param.display_type_rich = lambda ctx: None  # the argument's help says what it is
            param._usage_display_name = _plain_usage(param)
        if param.help:
            param.help = escape(param.help)
    for sub in getattr(command, "commands", {}).values():
        tidy(sub)
    return command
