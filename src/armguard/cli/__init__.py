"""The ``armguard`` command line: entry points only, the logic lives in the library."""

from __future__ import annotations

import sys

import click

from .._errors import ArmguardError


class _Group(click.Group):
    """A click group that turns ArmguardError into a one-line message and exit code 2."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except ArmguardError as exc:
            click.secho(f"error: {_option_names(ctx, str(exc))}", fg="red", err=True)
            sys.exit(2)


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


@click.group(cls=_Group)
@click.version_option(package_name="armguard")
@click.option("--backend", default=None, metavar="NAME",
              help="Backend for every check of this command (analytic, coal, fcl, ...; default: "
                   "$ARMGUARD_BACKEND, else armguard.toml, else analytic).")
@click.option("--config", "config", default=None, type=click.Path(dir_okay=False),
              help="An armguard.toml to read the [backend] table from (default: the working directory's).")
@click.pass_context
def main(ctx, backend: str | None, config: str | None) -> None:
    """armguard: collision and proximity detection for robot manipulators."""
    from ..backends import available, command_line_choice

    if backend is not None and backend not in available():
        raise click.BadParameter(f"unknown backend {backend!r}; installed backends are {list(available())}",
                                 param_hint="--backend")
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
