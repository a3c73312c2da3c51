"""femcheck command line. One module per subcommand in this package, each defining
``register(app: typer.Typer)``; they are found automatically, so adding a command is adding a file.
The library logs; only the CLI prints.
"""
from __future__ import annotations

import importlib
import logging
import pkgutil
import sys

import typer

from femcheck.errors import FemcheckError

app = typer.Typer(
    name="femcheck",
    help="Check compact analytical stiffness models of manipulators against finite elements and measured data.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)



@app.callback()
def _root() -> None:
    """femcheck: analytical stiffness models vs finite elements and measured data."""


_registered = False


def console():
    """A rich console that does not squeeze tables when output is not a terminal."""
    from rich.console import Console
    import sys as _sys
    tty = _sys.stdout.isatty()
    # in logs and pipes, long lines stay whole (grep-able); tables still fit 140 columns
    return Console(width=None if tty else 140, soft_wrap=not tty)


def _register_all() -> None:
    global _registered
    if _registered:
        return
    from femcheck.registry import plugins
    for mod in plugins("femcheck.cli", ("register",)):
        mod.register(app)
    _registered = True


def get_app() -> typer.Typer:
    """The fully registered typer app (tests call it in-process with typer.testing.CliRunner)."""
    _register_all()
    return app


def main(argv: list[str] | None = None) -> int:
    """Entry point: ``femcheck ...``. Known femcheck errors print one clear line and exit 2."""
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    _register_all()
    try:
        app(args=argv, prog_name="femcheck", standalone_mode=False)
    except FemcheckError as exc:
        typer.secho(f"error: {exc}", err=True, fg="red")
        return 2
    except SystemExit as exc:  # typer/click exit codes
        return int(exc.code or 0)
    except KeyboardInterrupt:
        typer.secho("interrupted", err=True, fg="red")
        return 130
    except Exception as exc:
        # usage errors of (typer's own copy of) click: they know how to show themselves
        if hasattr(exc, "show") and hasattr(exc, "exit_code"):
            exc.show()
            return int(exc.exit_code)
        if type(exc).__name__ == "Abort":
            return 130
        raise
    return 0


if __name__ == "__main__":
    sys.exit(main())
