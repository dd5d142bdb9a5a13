"""An audit for people: the terminal text, and ``--report DIR``'s figures (|error| maps on a log colour scale
with the wrong cells marked, error against resolution) and its list of wrong cells (``wrong_cells.csv``), drawn
with matplotlib (Agg) from :class:`.api.AuditResult`. The directory is written as ``brdfnorm report``'s is
(:func:`brdfnorm.output.directories.staged`): created if absent, replaced whole only if it holds an earlier
report, never half-written."""

from __future__ import annotations

import io
import os

import numpy as np

from .. import __version__
from ..output.directories import staged


def _png(figure) -> bytes:
    buffer = io.BytesIO()
    figure.savefig(buffer, dpi=100, format="png")
    return buffer.getvalue()


def _g(x: float) -> str:
    return f"{x:.3g}" if np.isfinite(x) else str(x)


def _n(n: int) -> str:
    return f"{n:,}".replace(",", "\u2009")


def _channel_line(c: dict) -> str:
    if c["fits"]:
        verdict = "every cell within it" if c["clean"] else f"{_n(c['bad'])} wrong"
    else:
        verdict = "too noisy to decide" if c.get("too_noisy") else "meaning not named (fits too few cells)"
    at = ", ".join(f"{k}={_g(v)}" for k, v in c.get("worst_at", {}).items())
    if c.get("layout"):
        verdict = f"stored {c['layout']} (read so, it fits); {_n(c['bad'])} cells misplaced"
    return (f"  channel {c['channel']}: {c['meaning']} fits {_n(c['within'])} of {_n(c['cells'])} cells "
            f"(tolerance {_g(c['tolerance'])}, noise σ {_g(c['noise_sigma'])}): {verdict}; "
            f"median error {_g(c['median'])}, RMS {_g(c['rms'])}, max {_g(c['max'])} at cell "
            f"{tuple(c['worst_cell'])}{f' ({at})' if at else ''}"
            + (f" [on a subgrid of {c['cells']} cells]" if c.get("sampled") else ""))


def _hypothesis_line(h: dict) -> str:
    within = sum(c["within"] for c in h["channels"] if c["meaning"])
    cells = sum(c["cells"] for c in h["channels"] if c["meaning"])
    return f"fits {_n(within)} of {_n(cells)} cells, median error {_g(h['median'])}"


#: Wrong cells printed per channel in the terminal text (all of them are in --json and the report).
TEXT_CELLS = 400


def _wrong_lines(channel: str, info: dict) -> list[str]:
    count, regions = info["count"], info["regions"]
    lines = [f"channel {channel} ({info['meaning']}{', stored ' + info['layout'] if info.get('layout') else ''}): "
             f"{_n(count)} wrong cell{'s' if count != 1 else ''} in "
             f"{len(regions)} region{'s' if len(regions) != 1 else ''} (tolerance {_g(info['tolerance'])}):"]
    by_region: dict[int, list] = {}
    for cell in info["cells"]:
        by_region.setdefault(cell["region"], []).append(cell)
    shown = 0
    for region in regions:
        span = ", ".join(f"{a}" if a == b else f"{a}..{b}" for a, b in zip(region["from"], region["to"], strict=True))
        lines.append(f"  region {region['region']}: {region['cells']} cell{'s' if region['cells'] != 1 else ''} at "
                     f"[{span}], max error {_g(region['max_error'])}")
        for cell in by_region.get(region["region"], []):
            if shown >= TEXT_CELLS:
                break
            shown += 1
            at = " ".join(f"{k}={v:.6g}" for k, v in cell["at"].items())
            lines.append(f"    {tuple(cell['index'])} {at}: stored {cell['stored']:.8g}, exact {cell['exact']:.8g}, "
                         f"error {cell['error']:+.3g}")
    if shown < count:
        more = info.get("listed", count) - shown
        lines.append(f"  … {_n(more)} more in --json" + (f" ({_n(count - info['listed'])} beyond its list)"
                                                           if info.get("listed", count) < count else ""))
    return lines


def _resolution_cell(r: dict) -> str:
    if "max" in r:
        return f"{r['size']}: {_g(r['max'])}"
    return f"{r['size']}: skipped ({r.get('skipped', 'over the budget')})"


def text(result: dict) -> str:
    """The terminal report of ``AuditResult.to_json()``."""
    shape = "×".join(map(str, result["shape"]))
    lines = [f"{result['file']}: {shape} {result['storage']} ({result['format']}"
             + (f", array {result['array']}" if result["array"] else "") + f"), channels "
             f"{', '.join(result['channels'])}; model {result['model']}; {result['hypotheses_tested']} conventions "
             f"tested, storage step {_g(result['storage_step'])}"]
    for note in result["notes"]:
        lines.append(f"note: {note}")
    best = result["best"]
    if result["tolerance_given"] is not None:
        lines.append(f"tolerance {_g(result['tolerance_given'])} (--tolerance)")
    else:
        lines.append(f"tolerance per channel: storage step × max|exact| + the reference's error + k × the "
                     f"table's noise σ ({result['storage']} storage)")
    if result["verdict"] == "fits":
        lines.append(f"convention: {best['text']}")
        lines.append(result["headline"])
    else:
        lines.append(result["headline"] + ":")
        lines.append(f"  {best['text']}")
    lines += [_channel_line(c) for c in best["channels"]]
    for k, other in enumerate(result["runners_up"][:2]):
        label = "runner-up" if k == 0 else "next"
        lines.append(f"{label}{' (as good: the table does not decide)' if k == 0 and result['ambiguous'] else ''}"
                     f": {other['text']}: {_hypothesis_line(other)}")
    approx = result.get("approximation")
    if approx:
        lines.append(f"the table is {approx['name']} tabulated ({approx['source']}): it equals {_n(approx['within'])} "
                     f"of {_n(approx['cells'])} cells; in {approx['convention']} its error against the exact values:")
        for c in approx["channels"]:
            at = ", ".join(f"{k}={_g(v)}" for k, v in c["worst_at"].items())
            lines.append(f"  channel {c['channel']} approximates {c['approximates']}: max error {_g(c['max'])} at "
                         f"cell {tuple(c['worst_cell'])} ({at}), median {_g(c['median'])}, RMS {_g(c['rms'])}")
    for channel, info in result["wrong_cells"].items():
        lines += _wrong_lines(channel, info)
    for channel, e in result["interpolation"].items():
        worst = ", ".join(f"{k}={_g(v)}" for k, v in e["worst"].items())
        lines.append(f"GPU interpolation error, channel {channel} ({e['points']} points of the {e['density']}× grid "
                     f"of {e['of_grid']} cells): max {_g(e['max'])} at {worst}; RMS {_g(e['rms'])}")
    for channel, rows in result["resolution"].items():
        lines.append(f"exact tables, channel {channel}, max interpolation error by size: "
                     f"{'; '.join(_resolution_cell(r) for r in rows)}")
    for kind, info in result["bad_cells"].items():
        if info["count"]:
            shown = ", ".join(f"{tuple(c)}={_g(v)}" for c, v in zip(info["cells"], info["values"], strict=True))
            lines.append(f"{info['count']} {kind.replace('_', ' ')} cells: {shown}"
                         + (" …" if info["count"] > len(info["cells"]) else ""))
    if result["unnamed_channels"]:
        lines.append(f"channel{'s' if len(result['unnamed_channels']) > 1 else ''} "
                     f"{', '.join(result['unnamed_channels'])}: no meaning fits most cells")
    lines.append(("PASS: every cell of every channel is within its tolerance" if result["passes"] else
                  "FAIL: not every cell of every channel is within its tolerance") + f" ({result['seconds']:.2f} s)")
    return "\n".join(lines)


def figures(result, directory: str) -> list[str]:
    """Signed error maps (one per audited channel) and the error-against-resolution plot, as PNG files."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    files: dict[str, bytes] = {}
    describe = result.best.convention.describe()["axes"]
    for fit in result.best.channels:
        if fit.residual is None:
            continue
        residual, bad = fit.residual, fit.bad if fit.bad is not None else np.zeros(fit.residual.shape, bool)
        finite = np.isfinite(residual)
        magnitude = np.abs(np.where(finite, residual, 0.0))
        top = float(np.max(magnitude)) if magnitude.size else 0.0
        floor = max(float(np.min(magnitude[magnitude > 0])) if np.any(magnitude > 0) else 1e-17, 1e-17)
        figure, axes = plt.subplots(figsize=(6.4, 5.2))
        title = (f"channel {fit.channel} ({fit.meaning}): {int(np.sum(~bad))} of {bad.size} cells within "
                 f"{fit.tolerance:.2g}\nmax |error| {top:.3g}; × wrong cells, ○ not finite")
        offset = 0
        if residual.ndim == 3:  # the slice through the worst cell along the first axis
            k = fit.worst[0] if fit.worst else 0
            residual, bad, finite, magnitude, offset = residual[k], bad[k], finite[k], magnitude[k], 1
            title += f"; slice {describe[0]} index {k}"
        if residual.ndim == 1:
            x = np.arange(residual.size)
            axes.semilogy(x, np.maximum(magnitude, floor), "o-", ms=3)
            axes.semilogy(x[bad & finite], np.maximum(magnitude, floor)[bad & finite], "kx", ms=8)
            axes.axhline(fit.tolerance, color="grey", lw=0.8, ls="--", label="tolerance")
            axes.set_xlabel(f"array index ({describe[0]})")
            axes.set_ylabel(f"|table − exact {fit.meaning}|")
        else:
            shown = np.ma.masked_where(~finite | (magnitude <= 0), magnitude)
            image = axes.imshow(shown, cmap="viridis", norm=LogNorm(vmin=floor, vmax=max(top, floor * 10)),
                                origin="upper", interpolation="nearest", aspect="auto")
            figure.colorbar(image, ax=axes, label=f"|table − exact {fit.meaning}| (log scale)")
            rows, cols = np.nonzero(bad & finite)
            axes.scatter(cols, rows, marker="x", c="red", s=28, linewidths=1.2)
            rows, cols = np.nonzero(~finite)
            axes.scatter(cols, rows, marker="o", facecolors="none", edgecolors="magenta", s=40)
            axes.set_xlabel(f"array axis {offset + 1} ({describe[offset + 1]})")
            axes.set_ylabel(f"array axis {offset} ({describe[offset]})")
        axes.set_title(title, fontsize=9)
        figure.tight_layout()
        files[f"error_map_{fit.channel}.png"] = _png(figure)
        plt.close(figure)
    if result.resolution:
        figure, axes = plt.subplots(figsize=(6.4, 4.4))
        skipped = []
        meanings = {f.channel: f.meaning for f in result.best.channels}
        for channel, rows in result.resolution.items():
            sizes = [r["size"] for r in rows if "max" in r]
            name = f"channel {channel} ({meanings.get(channel)})"
            axes.loglog(sizes, [r["max"] for r in rows if "max" in r], "o-", label=f"{name}: max")
            axes.loglog(sizes, [r["rms"] for r in rows if "max" in r], "s--", label=f"{name}: RMS")
            skipped += [(r["size"], r["skipped"]) for r in rows if "max" not in r]
        for level in (1e-3, 1e-4):
            axes.axhline(level, color="grey", lw=0.5)
        axes.set_xlabel("samples per axis of an exact table in this convention")
        axes.set_ylabel("interpolation error at dense points")
        if skipped:
            axes.set_title("skipped sizes: " + "; ".join(f"{n} ({why})" for n, why in sorted(set(skipped))),
                           fontsize=8)
        axes.legend(fontsize=8)
        figure.tight_layout()
        files["error_vs_resolution.png"] = _png(figure)
        plt.close(figure)
    if result.wrong_cells:
        files["wrong_cells.csv"] = wrong_cells_csv(result.wrong_cells).encode("utf-8")
    return _write(directory, files)


def wrong_cells_csv(wrong: dict) -> str:
    """Every wrong cell, one line each: channel, meaning, region, the table's indices, the axis values as stored,
    stored, exact and error (the report's list; the same as ``--json``'s ``wrong_cells``)."""
    lines = []
    for channel, info in wrong.items():
        for cell in info["cells"]:
            if not lines:
                lines.append(",".join(["channel", "meaning", "region", *[f"index{a}" for a in range(len(
                    cell["index"]))], *cell["at"], "stored", "exact", "error"]))
            lines.append(",".join([channel, str(info["meaning"]), str(cell["region"]), *map(str, cell["index"]),
                                   *(repr(v) for v in cell["at"].values()), repr(cell["stored"]),
                                   repr(cell["exact"]), repr(cell["error"])]))
    return "\n".join(lines) + "\n"


def _write(directory: str, files: dict[str, bytes]) -> list[str]:
    """The figures written into ``directory`` at once; their paths."""
    with staged(directory, f"brdfnorm {__version__} audit\n", "--report") as stage:
        for name, data in files.items():
            stage.write(name, data)
    return [os.path.join(directory, name) for name in files]


def formula_figures(arrays: dict, directory: str) -> list[str]:
    """The signed error of a formula over its domain: a map over (μ, α) or a curve over α, one PNG a quantity."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    files: dict[str, bytes] = {}
    for quantity, (diff, mu, alpha) in arrays.items():
        figure, axes = plt.subplots(figsize=(6, 5))
        finite = diff[np.isfinite(diff)]
        limit = float(np.max(np.abs(finite))) if finite.size else 1.0
        if mu is None:
            axes.plot(alpha, diff)
            axes.set_xlabel("alpha")
            axes.set_ylabel(f"formula − exact {quantity}")
        else:
            image = axes.pcolormesh(alpha[0], mu[:, 0], diff, cmap="RdBu_r", vmin=-limit, vmax=limit,
                                    shading="nearest")
            figure.colorbar(image, ax=axes, label=f"formula − exact {quantity}")
            axes.set_xlabel("alpha")
            axes.set_ylabel("mu = cos θ")
        axes.set_title(f"{quantity}: max |error| {limit:.3g}")
        files[f"formula_error_{quantity}.png"] = _png(figure)
        plt.close(figure)
    return _write(directory, files)
