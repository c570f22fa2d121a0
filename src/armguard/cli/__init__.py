"""The ``armguard`` command line: entry points only, the logic lives in the library."""

from __future__ import annotations

import click

from ._exit import DEBUG_ENV, ExitCode, exit_epilog, run_guarded
from ._params import BACKEND, PATH


class _Group(click.Group):
    """A click group whose commands exit with :class:`ExitCode`: an ArmguardError is a one-line
    message and 3, any other exception one line and 4, Ctrl-C 130 (``_exit.run_guarded``)."""

    def resolve_command(self, ctx, args):
        name, cmd, rest = super().resolve_command(ctx, args)
        script = ctx.obj if isinstance(ctx.obj, _Script) else None
        if script is not None and cmd is not None:  # tools/compare.py: its usage line is the script's, not "armguard compare"
            script.command = name
            return script.name, cmd, rest
        return name, cmd, rest

    def invoke(self, ctx):
        try:
            return run_guarded(ctx, lambda: super(_Group, self).invoke(ctx), lambda message: _option_names(ctx, message))
        except click.NoSuchOption as exc:
            raise _misplaced(self, exc) from None


def _misplaced(group: click.Group, exc: click.NoSuchOption) -> click.NoSuchOption:
    """``exc`` (a command's unknown option) said again when the option is the group's own (``armguard check z1 -q``):
    "armguard's own options (...) go before the command", with the command line that works; click's usage error
    (exit status 2) still."""
    ctx = exc.ctx
    options = [p for p in group.params if isinstance(p, click.Option) and p.opts]
    param = next((p for p in options if exc.option_name in (*p.opts, *p.secondary_opts)), None)
    if param is None or ctx is None or isinstance(ctx.find_root().obj, _Script):  # a script has no place for them
        return exc

    def usage(p: click.Option, name: str | None = None) -> str:
        return (name or "/".join(sorted(p.opts, key=len))) + ("" if p.is_flag else f" {p.make_metavar(ctx)}")

    root = ctx.find_root().info_name or "armguard"
    sub = ctx.command_path.split(" ", 1)[1] if " " in ctx.command_path else "COMMAND"
    fixed = f"{root} --version" if exc.option_name == "--version" else \
        f"{root} {usage(param, exc.option_name)} {sub} ..."
    return click.NoSuchOption(
        exc.option_name, f"No such option {exc.option_name!r} for '{ctx.command_path}'. {root}'s own options "
        f"({', '.join(usage(p) for p in options)}) go before the command: {fixed}", ctx=ctx)


class _Script:
    """``ctx.obj`` of :func:`run_as_script`: the script's name, and the command it runs."""

    def __init__(self, name: str) -> None:
        self.name, self.command = name, None


def run_as_script(command: str, args=None, name: str | None = None):
    """``armguard COMMAND ARGS...`` as a script of its own (``tools/compare.py MODEL ...``): the same options and
    exit statuses, with the script's name (``name``, default ``sys.argv[0]``'s file name) in its usage line and
    messages (``Usage: compare.py [OPTIONS] MODEL``); ``args`` default to ``sys.argv[1:]``.  Exits."""
    import os
    import sys

    args = sys.argv[1:] if args is None else list(args)
    name = name or os.path.basename(sys.argv[0]) or command
    # the group's own name is left empty, so that the command's path is the script's name alone
    return main.main(args=[command, *args], prog_name="", obj=_Script(name))


def _option_names(ctx, message: str) -> str:
    """An API error about a parameter (``stopping_distance: expected ...``) in the command's own
    terms (``--stopping-distance: expected ...``) when the message starts with one of its options."""
    name = ctx.obj.command if isinstance(ctx.obj, _Script) else ctx.invoked_subcommand
    sub = name and ctx.command.get_command(ctx, name)
    head, sep, rest = message.partition(":")
    if not sep or sub is None:
        return message
    for param in sub.params:
        if isinstance(param, click.Option) and param.name == head.strip() and param.opts:
            return f"{max(param.opts, key=len)}:{rest}"
    return message


@click.group(cls=_Group, epilog=exit_epilog(
    ok="done: clear, safe, the backends agree, the output written",
    unsafe="unsafe: a collision or stopping-distance violation (check, verify), an edge in collision (edges), "
           "backends that differ (compare), "
           "an error-level finding (check-urdf), with --strict a disabled pair that can collide, Adjacent and Default "
           "ones exempt (check-srdf), a map "
           "that allows a colliding configuration (cspace info --samples), a motion refused or a FIND failed "
           "(program run, program calibrate)",
    incomplete="incomplete: a check or verification that could not finish (check, verify, edges; compare: a "
               "backend refused some configurations)"))
@click.version_option(package_name="armguard")
@click.option("--backend", type=BACKEND, default=None, metavar="NAME",
              help="Backend for every check of this command (analytic, coal, fcl, ...; default: "
                   "$ARMGUARD_BACKEND, else armguard.toml, else analytic).")
@click.option("--config", "config", default=None, type=PATH,
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
from . import _edges  # noqa: E402,F401
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
__all__ = ["main", "ExitCode", "run_as_script"]
