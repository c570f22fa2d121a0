"""Option types shared by the commands: counts and finite numbers checked where click reads them.

click's ``FloatRange`` lets ``nan`` through (every comparison with it is false), so a number here
is refused unless finite; a refused value is click's usage error (exit status 2) naming the option.
"""

from __future__ import annotations

import math

import click

__all__ = ["AT_LEAST_ONE", "BACKEND", "BACKENDS", "COUNT", "DURATION", "Finite", "LENGTH", "PATH", "PATH_OR_DASH", "POSITIVE",
           "SAMPLES", "SEED", "FilePath", "refuse_unused", "scene_of", "srdf_option"]

AT_LEAST_ONE = click.IntRange(min=1)
"""An integer >= 1 (configurations, workers, evaluations)."""
COUNT = click.IntRange(min=0)
"""An integer >= 0."""
MAX_SAMPLES = 10**7
SAMPLES = click.IntRange(min=1, max=MAX_SAMPLES)
"""Random configurations to draw, 1 to 10^7 (10^10 was a MemoryError, exit 4; 10^20 an overflow)."""
SEED = click.IntRange(min=0)
"""A random seed, >= 0 (NumPy refuses a negative one: it was an internal error, exit 4)."""


class Finite(click.ParamType):
    """A finite float, at least ``low`` (above it when ``open_low``)."""

    name = "float"

    def __init__(self, low: float | None = None, open_low: bool = False, high: float | None = None):
        self.low, self.open_low, self.high = low, open_low, high

    def convert(self, value, param, ctx):
        if isinstance(value, float) and math.isfinite(value):
            x = value
        else:
            try:
                x = float(value)
            except (TypeError, ValueError):
                self.fail(f"{value!r} is not a number", param, ctx)
        if not math.isfinite(x):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        if self.low is not None and (x <= self.low if self.open_low else x < self.low):
            self.fail(f"{value!r} must be {'>' if self.open_low else '>='} {self.low:g}", param, ctx)
        if self.high is not None and x > self.high:
            self.fail(f"{value!r} must be <= {self.high:g}", param, ctx)
        return x


LENGTH = Finite(0.0, high=1e9)
"""A finite length (m) >= 0, at most 1e9 (``Tolerances.max_magnitude``, as a scene file's lengths: 1e300 m was
printed as 300 digits)."""
DURATION = Finite(0.0)
"""A finite time >= 0 (µs of a budget): no upper bound (the library sets none)."""
POSITIVE = Finite(0.0, open_low=True)
"""A finite number > 0 (a rate, a step)."""


def refuse_unused(ctx: click.Context, options, why: str) -> None:
    """A usage error (exit status 2) when one of ``options`` (parameter names) was given on the command line or
    in the environment: an option that does not apply was accepted and silently ignored (``srdf --method
    certified --samples 100``, ``compare --q ... --configs 7``).  ``why``: what the option goes with instead."""
    from click.core import ParameterSource

    for name in options:
        if ctx.get_parameter_source(name) in (ParameterSource.COMMANDLINE, ParameterSource.ENVIRONMENT):
            flag = next(p.opts[0] for p in ctx.command.params if p.name == name)
            raise click.UsageError(f"{flag} {why}", ctx=ctx)


class FilePath(click.Path):
    """A file or folder path: an empty one is refused (``--out ''`` read as "not given" wrote over the file the
    default names), and so is ``-`` unless ``dash`` (standard output or input): it would be a file named ``-``."""

    def __init__(self, dash: bool = False, **kwargs):
        super().__init__(allow_dash=dash, **kwargs)
        self.dash = dash

    def convert(self, value, param, ctx):
        if isinstance(value, str):
            if not value.strip():
                self.fail("an empty path names no file", param, ctx)
            if value == "-" and not self.dash:
                self.fail("'-' (standard output or input) is not read or written here: name a file", param, ctx)
        return super().convert(value, param, ctx)


PATH = FilePath()
"""A path, neither empty nor ``-``."""
PATH_OR_DASH = FilePath(dash=True)
"""A path, or ``-`` for standard output (or input)."""


class Backends(click.ParamType):
    """Installed backend names (``armguard.backends.available``), comma-separated where ``many``: an unknown
    one is a usage error naming the installed ones (exit status 2, as the group's ``--backend``)."""

    name = "backend"

    def __init__(self, many: bool = False):
        self.many = many

    def convert(self, value, param, ctx):
        if not isinstance(value, str):
            return value
        from ..backends import available

        names = [b.strip() for b in value.split(",") if b.strip()] if self.many else [value]
        for b in names:
            if b not in available():
                self.fail(f"unknown backend {b!r}; installed backends are {list(available())}", param, ctx)
        return value


BACKEND = Backends()
"""One installed backend's name."""
BACKENDS = Backends(many=True)
"""Comma-separated installed backend names."""


def srdf_option(help_for: str):
    """``--srdf PATH|none``: the SRDF of SCENE in place of the one armguard finds (``load_model``'s ``srdf=``;
    ``none``: no SRDF at all) -- a built-in or public robot's name, a sidecar or a .urdf."""
    return click.option("--srdf", type=PATH, default=None, metavar="PATH|none",
                        help=f"The SRDF of {help_for} in place of the one found (docs/models.md), or 'none' for no SRDF.")


def scene_of(scene: str, srdf: str | None):
    """SCENE's Scene: ``load_scene`` without ``--srdf``, else the Model's with that SRDF (``none``: none)."""
    if srdf is None:
        from ..scene import load_scene

        return load_scene(scene)
    from pathlib import Path

    from ..model import load_model

    if Path(scene).suffix.lower() in (".yaml", ".yml"):  # a plain scene file: its robots name their own SRDFs
        from .._yaml import read_scene_yaml

        data = read_scene_yaml(Path(scene))
        if not (isinstance(data, dict) and "model" in data):
            raise click.UsageError("--srdf goes with a model: a built-in or public robot's name, a .urdf or a model "
                                   "sidecar (a scene file's URDF robot names its SRDF at robots[i].srdf)")
    return load_model(scene, srdf=False if srdf.strip().lower() == "none" else srdf).scene
