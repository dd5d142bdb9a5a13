"""``brdfnorm explore``: a local web page with live sliders, plots and exact numbers (:mod:`brdfnorm.explore`)."""

from __future__ import annotations

import threading
import webbrowser

import typer

from .application import app
from .common import DEBUG_OPTION, guarded


@app.command(short_help="Explore lobes in the browser: sliders, the lobe in 2-D and 3-D, E(θ_o), exact factors, "
                        "the energy verdict, and the factor fitted as shader code.")
def explore(
    models: list[str] = typer.Argument(None, metavar="MODEL_OR_FILE",
                                       help="Built-in names or .brdf files to open first; files are watched and "
                                            "reloaded when saved. The built-ins and examples/ are always offered."),
    port: int = typer.Option(0, "--port", min=0, max=65535, help="Port to listen on (default: a free one)."),
    host: str = typer.Option("127.0.0.1", "--host",
                             help="Address to listen on. Anything but a loopback address exposes the explorer "
                                  "to the network (a warning is printed)."),
    no_browser: bool = typer.Option(False, "--no-browser", help="Print the URL only; do not open a browser."),
    debug: bool = DEBUG_OPTION,
) -> None:
    """Explore lobes in the browser: parameter sliders, the lobe in 2-D and 3-D, E(θ_o) with its error band,
    normalization factors (normal / max / view), the energy verdict of `brdfnorm check` at the page's values
    (the same as `brdfnorm check MODEL --only energy -p NAME=VALUE ... --budget 2e7evals`, which the page
    prints), and a fit of the factor as GLSL/HLSL code.

    Serves only the models named here, the built-ins and examples/; Ctrl-C stops it.
    """
    with guarded(debug):
        from ..extras import require

        for module in ("anyio", "starlette", "uvicorn", "watchfiles"):  # the server's stack: one install hint
            require(module, "explore", where="explore")
        from ..explore import Catalog, bind, serve, url_of
        from ..explore.server import is_loopback

        catalog = Catalog.build(list(models or []))
        sock = bind(host, port)
        url = url_of(sock)
        if not is_loopback(host):
            typer.echo(f"warning: listening on {host}: anyone who can reach this machine can use the explorer "
                       "(it serves only its models and runs nothing from requests)", err=True)
        typer.echo(f"brdfnorm explore: {url}  (Ctrl-C stops)", err=True)
        if not no_browser:  # the socket already listens; a thread, because a console browser would block
            threading.Thread(target=webbrowser.open, args=(url,), daemon=True).start()
        serve(catalog, sock)
        typer.echo("brdfnorm explore: stopped", err=True)
