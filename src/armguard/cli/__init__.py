"""The ``armguard`` command line: entry points only, the logic lives in the library."""

from __future__ import annotations

import click

from ._exit import DEBUG_ENV, ExitCode, exit_epilog, run_guarded
from ._params import BACKEND


class _Group(click.Group):
    """A click group whose commands exit with :class:`ExitCode`: an ArmguardError is a one-line
    message and 3, any other exception one line and 4, Ctrl-C 130 (``_exit.run_guarded``)."""

    def invoke(self, ctx):
        return run_guarded(ctx, lambda: super(_Group, self).invoke(ctx), lambda message: _option_names(ctx, message))


def _option_names(ctx, message: str) -> str:
    """An API error about a parameter (``stopping_distance: expected ...``) in the command's own
    terms (``--stopping-distance: expected ...``) when the message starts with one of its options."""
    sub = ctx.invoked_subcommand and ctx.command.get_command(ctx, ctx.invoked_subcommand)
    head, sep, rest = message.partition(":")
    if not sep or sub is None:
        return message
    for param in sub.params:
        if isinstance(param, click.Option) and param.name == head.strip() and param.opts:
            return f"{max(param.opts, key=len)}:{rest}"
    return message


@click.group(cls=_Group, epilog=exit_epilog(
    ok="done: clear, safe, the backends agree, the output written",
    unsafe="unsafe: a collision or stopping-distance violation (check, verify), backends that differ (compare), "
           "an error-level finding (check-urdf)",
    incomplete="incomplete: a check or verification that could not finish (check, verify)"))
@click.version_option(package_name="armguard")
@click.option("--backend", type=BACKEND, default=None, metavar="NAME",
              help="Backend for every check of this command (analytic, coal, fcl, ...; default: "
                   "$ARMGUARD_BACKEND, else armguard.toml, else analytic).")
@click.option("--config", "config", default=None, type=click.Path(),
              help="An armguard.toml to read the [backend] table from (default: the working directory's).")
@click.option("--traceback", "traceback", is_flag=True,
              help=f"Print the traceback of an internal error (exit status 4); also {DEBUG_ENV}=1.")
@click.option("--quiet", "-q", "quiet", is_flag=True,
              help="Do not print warnings about the files read (an SRDF of a larger robot, lenient readings); "
                   "`armguard info` still lists them.")
@click.pass_context
def main(ctx, backend: str | None, config: str | None, traceback: bool, quiet: bool) -> None:
    """armguard: collision and proximity detection for robot manipulators."""
    from ..backends import command_line_choice
    from ._output import one_line_warnings

    one_line_warnings()
    if quiet:  # for this command only (restored when it ends: an in-process caller keeps its filters)
        import warnings

        from .._errors import ArmguardWarning

        ctx.with_resource(warnings.catch_warnings())
        warnings.simplefilter("ignore", ArmguardWarning)
    # --backend counts as the explicit argument of every check this command makes
    ctx.call_on_close(command_line_choice(backend, config))


# Each command lives in its own module and registers itself on ``main``.
from . import _distance  # noqa: E402,F401
from . import _console  # noqa: E402,F401
from . import _info  # noqa: E402,F401
from . import _fk  # noqa: E402,F401
from . import _verify  # noqa: E402,F401
from . import _demo  # noqa: E402,F401
from . import _check  # noqa: E402,F401
from . import _cspace  # noqa: E402,F401
from . import _compare  # noqa: E402,F401
from . import _program  # noqa: E402,F401
from . import _srdf  # noqa: E402,F401


def _document_exit_codes(group: click.Group) -> None:
    """Every command without its own exit-status table gets the generic one (0: done)."""
    for cmd in group.commands.values():
        if cmd.epilog is None:
            cmd.epilog = exit_epilog()
        if isinstance(cmd, click.Group):
            _document_exit_codes(cmd)


_document_exit_codes(main)
__all__ = ["main", "ExitCode"]
