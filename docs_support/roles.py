"""The API pages in one style: the docstrings' Sphinx roles and doctest examples, rendered for MkDocs.

The docstrings of ``src/`` cross-reference in Sphinx's way (``:mod:`brdfnorm.lut```, ``:func:`albedo```,
``:class:`~brdfnorm.errors.ParameterError```) and show examples as doctest lines (``>>> load("ggx")``). Markdown
knows neither: the roles showed raw and a ``>>>`` line became a triple-nested quote. Rather than rewrite ~700
roles across the source, two pieces render them:

* :class:`SphinxRoles`, a griffe extension (``mkdocs.yml``: ``plugins.mkdocstrings...options.extensions``),
  rewrites every docstring as it is loaded: a role becomes an optional autorefs reference — a link where the
  target is on an API page, its name in code font where it is not, never a dead link — named as Sphinx would
  (``~a.b.c`` shows ``c``); a relative name (``:data:`AUTO_ORDER```) is resolved in its class, then its module;
  a run of doctest lines becomes a fenced ``python`` block.
* :func:`on_post_page`, a MkDocs hook (``mkdocs.yml``: ``hooks``), warns for any role still raw in a built page
  (a docstring in a spelling the rewrite does not know, or a Markdown page); ``mkdocs build --strict`` (``make
  docs``) then fails.
"""

from __future__ import annotations

import html
import logging
import re

from griffe import Extension, Object

ROLE = re.compile(r":(?:py:)?(mod|data|func|class|meth|attr|exc|obj|const|ref|term):`([^`]+)`")
#: What a raw role looks like once Markdown has rendered it (the backticks became <code>).
RAW_IN_HTML = re.compile(r":(?:py:)?(mod|data|func|class|meth|attr|exc|obj|const|ref|term):(?:`|<code>)")
DOCTEST = re.compile(r"^(\s*)>>> ")

log = logging.getLogger("mkdocs.plugins.brdfnorm_roles")


def _target(text: str, owner: Object | None) -> tuple[str, str]:
    """(identifier, title) of a role's text: ``~a.b.c`` → (a.b.c, c); ``title <a.b>`` → (a.b, title); a bare
    name is looked up in ``owner``'s class and module."""
    explicit = re.fullmatch(r"(.+?)\s*<([^>]+)>", text)
    if explicit:
        return explicit.group(2).strip(), explicit.group(1).strip()
    short = text.startswith("~")
    path = text.lstrip("~.!").removesuffix("()")
    title = path.rsplit(".", 1)[-1] if short else path
    scope = owner
    while scope is not None and "." not in path:
        try:
            if path in scope.members:
                return f"{scope.path}.{path}", title
        except AttributeError:  # an alias whose target is outside the package
            break
        scope = scope.parent
    return path, title


def rewrite(text: str, owner: Object | None = None) -> str:
    """``text`` with its Sphinx roles as optional autorefs and its doctest runs as fenced code blocks."""

    def role(match: re.Match) -> str:
        identifier, title = _target(match.group(2), owner)
        return (f'<autoref identifier="{html.escape(identifier, quote=True)}" optional>'
                f"<code>{html.escape(title)}</code></autoref>")

    lines, out, index = text.splitlines(), [], 0
    while index < len(lines):
        found = DOCTEST.match(lines[index])
        if not found:
            out.append(ROLE.sub(role, lines[index]))
            index += 1
            continue
        indent = found.group(1)
        block = []
        while index < len(lines) and lines[index].strip() and lines[index].startswith(indent):
            block.append(lines[index][len(indent):])
            index += 1
        if out and out[-1].strip():
            out.append("")
        out += [f"{indent}```python", *(f"{indent}{line}" for line in block), f"{indent}```", ""]
    return "\n".join(out)


class SphinxRoles(Extension):
    """Rewrite every docstring of the loaded package (see the module docstring)."""

    def on_package(self, *, pkg: Object, **kwargs: object) -> None:
        seen: set[int] = set()
        stack = [pkg]
        while stack:
            obj = stack.pop()
            if id(obj) in seen or obj.is_alias:
                continue
            seen.add(id(obj))
            if obj.docstring is not None:
                obj.docstring.value = rewrite(obj.docstring.value, obj if obj.is_class or obj.is_module
                                              else obj.parent)
            stack += [member for member in obj.members.values() if not member.is_alias]


def on_post_page(output: str, page, config) -> str:
    """MkDocs hook: a warning (an error under ``--strict``) for each raw Sphinx role left in a built page."""
    text = re.sub(r"<pre.*?</pre>", "", output, flags=re.S)  # code blocks may show roles on purpose
    for match in RAW_IN_HTML.finditer(text):
        start = max(0, match.start() - 60)
        context = html.unescape(re.sub(r"<[^>]+>", "", text[start:match.end() + 60])).replace("\n", " ")
        log.warning("%s: a raw Sphinx role %r is shown on the page: ...%s...", page.file.src_path,
                    match.group(0), context)
    return output
