"""The typer ``app`` and the helpers every command module shares.

Command modules import from here, not from the package ``__init__``, so that the
package can import them (to register their commands) without an import cycle.
"""

from __future__ import annotations

import atexit
import enum
import logging
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from typer.core import TyperGroup

if TYPE_CHECKING:  # annotations only: recent typer ships its own click
    import click

from fibersweep.errors import FibersweepError, InputError, Terminated

#: What the tool does, as ``fibersweep --help`` and ``fibersweep.__doc__`` say it.
ABOUT = (
    "Fibers, rigid or flexible, carried by a Stokes flow past pillars: one pillar in a "
    "shallow channel, or a tilted pillar array that sorts fibers by length. The flow is "
    "solved once (lattice Boltzmann, cached); then one fiber run per point of a sweep "
    "over starts, lengths and any setting, stored as Parquet; the commands below draw, "
    "report and compare the results."
)

# Help panels, in the order ``fibersweep --help`` lists them (``rich_help_panel`` of
# each command; a generated reference can group by the same attribute).
SWEEP = "Sweeps"
FIGURES = "Figures of a results folder"
ARRAYS = "Pillar arrays"
MEASURED = "Comparing with measurements"
SETUP = "Setup"
PANELS = (SWEEP, FIGURES, ARRAYS, MEASURED, SETUP)
#: Order of the commands within their panels (others follow, as registered).
ORDER = (
    "run", "simulate", "classify", "check", "plot-phase", "plot-fractions", "plot-delta",
    "plot-tracks", "animate", "explore", "sort-report", "synth", "discrepancy", "power",
    "init", "config", "flow",
)  # fmt: skip


def short_help(cmd: click.Command) -> str:
    """A command's one-line description, whole: its first paragraph, never cut."""
    text = cmd.short_help or (cmd.help or "").split("\n\n")[0]
    return " ".join(text.split())


class GroupedHelp(TyperGroup):
    """Lists the commands under their help panels, each description whole (wrapped).

    Typer draws panels only with rich markup, which would read the units in
    brackets of the help texts ([deg], [s]) as markup; this plain formatter reads
    the same ``rich_help_panel`` attribute.
    """

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        panels: dict[str, list[tuple[str, str]]] = {}
        for name in self.list_commands(ctx):
            cmd = self.get_command(ctx, name)
            if cmd is None or cmd.hidden:
                continue
            panel = getattr(cmd, "rich_help_panel", None) or "Other commands"
            panels.setdefault(panel, []).append((name, short_help(cmd)))
        rank = {name: k for k, name in enumerate(ORDER)}
        for rows in panels.values():
            rows.sort(key=lambda r: rank.get(r[0], len(ORDER)))
        for panel in [*[p for p in PANELS if p in panels], *[p for p in panels if p not in PANELS]]:
            with formatter.section(panel):
                formatter.write_dl(panels[panel])


app = typer.Typer(
    name="fibersweep",
    help=ABOUT,
    cls=GroupedHelp,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=True,  # --install-completion / --show-completion (bash, zsh, fish, PowerShell)
    # help texts carry units in brackets ([deg], [s]): print them, do not parse them as markup
    rich_markup_mode=None,
)

ConfigArg = Annotated[Path, typer.Argument(help="YAML config file.", show_default=False)]
Overrides = Annotated[
    list[str] | None,
    typer.Argument(
        help="KEY=VALUE settings that replace the config's, e.g. fiber.contact.chi=1.2 "
        "flow.dx=2 'sweep.y0=[0.3, 0.4]' (values are YAML).",
        show_default=False,
    ),
]
#: Overrides of a command that runs one fiber (a sweep key would change nothing there).
RunOverrides = Annotated[
    list[str] | None,
    typer.Argument(
        help="KEY=VALUE settings that replace the config's, e.g. fiber.model=bead-spring "
        "fiber.integrator=ros2 fiber.young_modulus=1e4 flow.dx=2 (values are YAML).",
        show_default=False,
    ),
]
Verbose = Annotated[bool, typer.Option("--verbose", "-v", help="Log progress details.")]


def choices(name: str, values: Iterable[str]) -> type[enum.Enum]:
    """A string Enum of ``values`` for a typer option, so --help lists the valid ones."""
    return enum.Enum(name, {v: v for v in values}, type=str)


Workers = Annotated[int | None, typer.Option(help="Worker processes.", show_default="run.workers")]


@contextmanager
def _errors() -> Iterator[None]:
    """Turn library errors into a message on stderr and an exit code."""
    try:
        yield
    except InputError as exc:
        typer.secho(f"error: {exc}", err=True, fg=typer.colors.RED)
        raise typer.Exit(2) from None
    except FibersweepError as exc:
        typer.secho(f"failed: {exc}", err=True, fg=typer.colors.RED)
        raise typer.Exit(1) from None
    except OSError as exc:  # read-only folder, a file where a folder should be, disk full
        from fibersweep.sweep.store import describe_os_error

        typer.secho(f"failed: {describe_os_error(exc)}", err=True, fg=typer.colors.RED)
        raise typer.Exit(1) from None


@contextmanager
def _interruptible() -> Iterator[None]:
    """Ctrl-C and SIGTERM stop the block cleanly: exit 130 and 143, never a traceback.

    SIGTERM raises :class:`Terminated` (a KeyboardInterrupt), so the library's
    Ctrl-C clean-up runs for both. Once the block is over the work is saved, and
    either signal only ends the process, with the same codes.
    """
    import os
    import signal
    import sys

    def interrupt(signum: int, frame: object) -> None:
        raise Terminated()

    def leave(signum: int, frame: object) -> None:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(143 if signum == signal.SIGTERM else 130)

    try:
        signal.signal(signal.SIGTERM, interrupt)
    except ValueError:  # not the main thread (e.g. called from a test runner thread)
        yield
        return
    try:
        yield
    except Terminated:
        raise typer.Exit(143) from None
    except KeyboardInterrupt:
        raise typer.Exit(130) from None
    finally:
        signal.signal(signal.SIGTERM, leave)
        signal.signal(signal.SIGINT, leave)
        # Interpreter shutdown resets Python-level handlers to the default, so a late
        # signal would end the process with -2/-15 instead of the codes above; from the
        # first exit handler on, the work is saved and printed: ignore them.
        atexit.register(_ignore_stop_signals)


def _ignore_stop_signals() -> None:
    import signal

    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    signal.signal(signal.SIGINT, signal.SIG_IGN)


class _TqdmLogHandler(logging.Handler):
    """Log lines written through ``tqdm.write``, so they never glue to a progress bar.

    The same idea as ``tqdm.contrib.logging.logging_redirect_tqdm``, installed once
    per command instead of inside a ``with`` block.
    """

    def emit(self, record: logging.LogRecord) -> None:
        import sys

        from tqdm import tqdm

        try:
            tqdm.write(self.format(record), file=sys.stderr)
        except Exception:  # never let a log line end the command
            self.handleError(record)


def _setup_logging(verbose: bool) -> None:
    """Log WARNING and above (INFO with ``-v``) to stderr, through tqdm."""
    root = logging.getLogger()
    for h in [h for h in root.handlers if isinstance(h, _TqdmLogHandler)]:
        root.removeHandler(h)
    handler = _TqdmLogHandler()
    handler.setFormatter(logging.Formatter("%(asctime)s %(name)s %(levelname)s: %(message)s"))
    root.addHandler(handler)
    root.setLevel(logging.INFO if verbose else logging.WARNING)


def _load(path: Path, overrides: list[str] | None = None, max_points: int | None = None):
    """The config as every command sees it (:func:`fibersweep.api.load_config`)."""
    from fibersweep.api import load_config

    return load_config(path, *(overrides or ()), max_points=max_points)


def _version(value: bool) -> None:
    if value:
        from fibersweep.version import __version__

        typer.echo(f"fibersweep {__version__}")
        raise typer.Exit()


@app.callback()
def main(
    version: Annotated[
        bool,
        typer.Option(
            "--version", callback=_version, is_eager=True, help="Print the version and exit."
        ),
    ] = False,
) -> None:
    """Fibers carried by a Stokes flow past pillars: sweeps, figures, reports."""


#: Seconds the interpreter may take to shut down after a command has finished.
EXIT_GRACE_S = 30.0


def _leave_anyway(code: object, grace: float = EXIT_GRACE_S) -> None:
    """End the process with ``code`` if its shutdown stalls for ``grace`` seconds.

    By the time a command returns its work is saved and reported. Interpreter
    shutdown then joins every non-daemon thread, including the manager threads
    of process pools; one stuck there (e.g. on a worker killed mid-start) would
    keep a finished sweep from ever exiting. A daemon thread still runs while
    the main thread waits in that join, so it can end the process instead.

    Parameters
    ----------
    code : object
        The command's exit code as in ``SystemExit.code`` (None means 0).
    grace : float
        Seconds to wait [s].
    """
    import os
    import sys
    import threading
    import time

    status = 0 if code is None else code if isinstance(code, int) else 1

    def guard() -> None:
        time.sleep(grace)
        sys.stderr.write(
            f"fibersweep: shutdown stalled for {grace:.0f} s after the work was saved; "
            "leaving anyway\n"
        )
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(status)

    threading.Thread(target=guard, name="exit-guard", daemon=True).start()


def entry() -> None:
    """The console script and ``python -m``: run the app, then make sure the process ends."""
    try:
        app(prog_name="fibersweep")
    except SystemExit as exc:
        _leave_anyway(exc.code)
        raise
