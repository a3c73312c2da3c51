"""femcheck command line. One module per subcommand in this package, each defining
``register(app: typer.Typer)``; they are found automatically, so adding a command is adding a file.
The library logs; only the CLI prints.
"""
from __future__ import annotations

import logging
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



#: output options of this invocation (root options -q / -v), read by :func:`console` and :func:`progress`
OUTPUT = {"quiet": False, "verbose": 0}


def _version(value: bool) -> None:
    if value:
        from importlib.metadata import PackageNotFoundError, version
        try:
            v = version("femcheck")
        except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
            v = "unknown (not installed)"
        typer.echo(f"femcheck {v}")
        raise typer.Exit(0)


@app.callback()
def _root(
    quiet: bool = typer.Option(False, "--quiet", "-q", help="only results and errors: no progress, no warnings"),
    verbose: int = typer.Option(0, "--verbose", "-v", count=True, help="log what the library does (-v info, -vv debug)"),
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True, help="print the version and exit"),
    linear_solver: str = typer.Option(
        None, "--linear-solver", metavar="NAME",
        help="sparse direct solver: auto | pardiso | cholmod | mumps | superlu (default: "
             "$FEMCHECK_LINEAR_SOLVER, else auto = PARDISO with MKL, else CHOLMOD/UMFPACK)"),
) -> None:
    """femcheck: analytical stiffness models vs finite elements and measured data."""
    OUTPUT.update(quiet=quiet, verbose=verbose)
    if linear_solver is not None:
        from femcheck.fe.linear_solver import set_preferred
        set_preferred(linear_solver)
    level = logging.ERROR if quiet else (logging.DEBUG if verbose >= 2 else logging.INFO if verbose == 1 else logging.WARNING)
    logging.getLogger().setLevel(level)
    logging.getLogger("femcheck").setLevel(level)
    # scikit-fem logs every assembly at INFO: shown from -vv on; its warnings stay visible
    logging.getLogger("skfem").setLevel(logging.DEBUG if verbose >= 2 else logging.ERROR if quiet else logging.WARNING)


def progress(stage: str, total, console=None, weights=None, stderr: bool = False):
    """A :class:`femcheck.cli._progress.StageProgress` for a long stage (quiet under -q); ``weights``: the
    expected relative cost of each step, for the ETA; ``stderr``: progress on standard error (when standard
    output carries JSON)."""
    from femcheck.cli._progress import StageProgress
    if console is None:
        from rich.console import Console
        console = Console(stderr=True) if stderr else globals()["console"]()
    return StageProgress(stage, total, console, quiet=OUTPUT["quiet"], weights=weights)


_registered = False


def console(stderr: bool = False):
    """A rich console (on stdout, or ``stderr``) that does not squeeze tables when output is not a terminal."""
    from rich.console import Console
    import sys as _sys
    tty = (_sys.stderr if stderr else _sys.stdout).isatty()
    # in logs and pipes, long lines stay whole (grep-able); tables still fit 140 columns
    return Console(width=None if tty else 140, soft_wrap=not tty, stderr=stderr)


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


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def main(argv: list[str] | None = None) -> int:
    """Entry point: ``femcheck ...``. Exit codes: 0 all good, 1 a failed check, 2 bad input (a femcheck error
    prints one line, no traceback), 130 Ctrl-C (docs/errors.md)."""
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s %(levelname)s %(name)s: %(message)s",
                        datefmt="%H:%M:%S")
    _register_all()
    try:
        # standalone_mode=False makes click *return* the code of typer.Exit(n) instead of exiting:
        # it must be passed on, or `verify --check` reports drift and still exits 0
        rc = app(args=argv, prog_name="femcheck", standalone_mode=False)
    except FemcheckError as exc:
        typer.secho(f"error: {_one_line(exc)}", err=True, fg="red")
        return int(getattr(exc, "exit_code", 2))
    except SystemExit as exc:  # typer/click exit codes
        return int(exc.code or 0)
    except KeyboardInterrupt:
        typer.secho("interrupted", err=True, fg="red")
        return 130
    except OSError as exc:
        # a file the user named cannot be read or written (permissions, a directory in the way, disk full)
        where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
        typer.secho(f"error: {where}{exc.strerror or exc}", err=True, fg="red")
        return 2
    except Exception as exc:
        if type(exc).__name__ == "Abort":  # click turns Ctrl-C at a prompt into Abort
            typer.secho("interrupted", err=True, fg="red")
            return 130
        # usage errors of (typer's own copy of) click: one line naming the option, no usage box
        if hasattr(exc, "format_message") and hasattr(exc, "exit_code"):
            typer.secho(f"error: {_one_line(exc.format_message())}", err=True, fg="red")
            return int(exc.exit_code)
        raise
    return int(rc) if isinstance(rc, int) else 0


if __name__ == "__main__":
    sys.exit(main())
