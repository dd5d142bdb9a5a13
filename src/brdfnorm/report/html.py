"""HTML of ``brdfnorm report``: one self-contained page (inline CSS, no scripts), its tables and figures.

Every piece of text is escaped here; table cells that show a number also carry the full-precision value in a
``data-value`` attribute (``repr`` of the float), so the page can be checked by machine to the last digit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from html import escape

from .figures import Image

CSS = """
body { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; margin: 0 auto; max-width: 1240px;
       padding: 1.5em 2em 4em; color: #1d1d1f; line-height: 1.45; }
h1 { font-size: 1.7em; margin-bottom: 0.2em; }
h2 { margin-top: 2.2em; border-bottom: 1px solid #ddd; padding-bottom: 0.2em; }
code { background: #f3f3f3; padding: 0 0.25em; border-radius: 3px; }
nav ol { columns: 2; }
figure { margin: 1em 0; }
figure img { max-width: 100%; height: auto; }
figcaption { color: #555; font-size: 0.92em; }
table { border-collapse: collapse; margin: 0.8em 0; font-size: 0.84em; }
th, td { border: 1px solid #d6d6d6; padding: 0.2em 0.4em; }
th { background: #f5f5f7; font-weight: 600; overflow-wrap: anywhere; }
td.num { text-align: right; font-variant-numeric: tabular-nums; font-family: ui-monospace, monospace; }
td.bad { color: #b00020; font-weight: 600; }
td.good { color: #1b7a2f; }
.scroll { overflow-x: auto; max-width: 100%; }
.scroll tr > :first-child { position: sticky; left: 0; background: #f5f5f7; }
.findings li { margin: 0.25em 0; }
.note { color: #555; font-size: 0.92em; }
small.detail { color: #555; }
"""


@dataclass(frozen=True)
class Cell:
    """A table cell: shown text, optional full-precision value, optional CSS class, optional span, and an optional
    explaining line drawn small under the text."""

    text: str
    value: float | None = None
    css: str = ""
    colspan: int = 1
    rowspan: int = 1
    detail: str = ""


def number(value: float, digits: int = 12, css: str = "num") -> Cell:
    value = float(value)
    text = f"{value:.{digits}g}" if math.isfinite(value) else ("∞" if value > 0 else "—" if math.isnan(value)
                                                                 else "−∞")
    return Cell(text.replace("-", "−"), value, css)


def relative(value: float, tolerance: float | None = None) -> Cell:
    """A relative difference in scientific notation, flagged when larger than ``tolerance``."""
    value = float(value)
    if not math.isfinite(value):
        return Cell("—", None, "num")
    css = "num" if tolerance is None else ("num good" if abs(value) <= tolerance else "num bad")
    return Cell(f"{value:+.2e}".replace("-", "−"), value, css)


def percent(value: float, digits: int = 2, signed: bool = True) -> Cell:
    value = float(value)
    if not math.isfinite(value):
        return Cell("—", None, "num")
    return Cell(f"{100 * value:{'+' if signed else ''}.{digits}f} %".replace("-", "−"), value, "num")


def text(value: str, css: str = "") -> Cell:
    return Cell(value, None, css)


def table(header: list[list[Cell | str]], rows: list[list[Cell | str]], table_id: str = "",
          caption: str = "") -> str:
    """A table with one or more header rows (cells with colspan/rowspan) and body rows."""
    out = [f'<div class="scroll"><table{f" id={_quote(table_id)}" if table_id else ""}>']
    if caption:
        out.append(f"<caption>{escape(caption)}</caption>")
    out.append("<thead>")
    for row in header:
        out.append("<tr>" + "".join(_cell(c, "th") for c in row) + "</tr>")
    out.append("</thead><tbody>")
    for row in rows:
        out.append("<tr>" + "".join(_cell(c, "td") for c in row) + "</tr>")
    out.append("</tbody></table></div>")
    return "\n".join(out)


def _cell(cell: Cell | str, tag: str) -> str:
    if isinstance(cell, str):
        cell = Cell(cell)
    attributes = ""
    if cell.css:
        attributes += f" class={_quote(cell.css)}"
    if cell.colspan > 1:
        attributes += f' colspan="{cell.colspan}"'
    if cell.rowspan > 1:
        attributes += f' rowspan="{cell.rowspan}"'
    if cell.value is not None:
        attributes += f' data-value="{cell.value!r}"'
    detail = f'<br><small class="detail">{escape(cell.detail)}</small>' if cell.detail else ""
    return f"<{tag}{attributes}>{escape(cell.text)}{detail}</{tag}>"


def _quote(value: str) -> str:
    return '"' + escape(value, quote=True) + '"'


def figure(image: Image, caption: str) -> str:
    return (f'<figure><img src={_quote(image.name)} width="{image.width}" height="{image.height}" '
            f"alt={_quote(image.alt)}><figcaption>{caption}</figcaption></figure>")


@dataclass(frozen=True)
class Section:
    anchor: str
    title: str
    body: str  # HTML


def page(title: str, intro: str, sections: list[Section], footer: str) -> str:
    nav = "".join(f'<li><a href="#{escape(s.anchor)}">{escape(s.title)}</a></li>' for s in sections)
    body = "\n".join(f'<section id="{escape(s.anchor)}">\n<h2>{escape(s.title)}</h2>\n{s.body}\n</section>'
                     for s in sections)
    return (f'<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
            f'<meta name="viewport" content="width=device-width, initial-scale=1">\n'
            f'<meta name="generator" content="brdfnorm report">\n<title>{escape(title)}</title>\n'
            f"<style>{CSS}</style>\n</head>\n<body>\n<h1>{escape(title)}</h1>\n{intro}\n"
            f"<nav><ol>{nav}</ol></nav>\n{body}\n<footer class=\"note\">{footer}</footer>\n</body>\n</html>\n")
