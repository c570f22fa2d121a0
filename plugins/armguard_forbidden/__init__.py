"""The forbidden backend: Hermes's Fig. 14 as a Checker — a forbidden-values map plus a geometric backend.

``armguard.checker(model, "forbidden", {"map": PATH, "geometric": "analytic"})`` opens the map at
``PATH`` (an ``.agmap`` written by ``armguard cspace build``) and answers ``collides(Q, margin)``
(``Q`` ``(M, nq)`` in ``pin_model``'s order) with :class:`armguard.cspace.CombinedChecker`:

* the pairs the map covers — its mapped links (HERA's links 1–3) against the static bodies — by a
  map lookup of joints 1–3: a configuration the map does not allow counts as a collision;
* every other active pair of the Model by the geometric backend's own ``collides`` at ``margin``
  (any installed backend: analytic by default, coal, fcl, clip, …), over a Model that shares this
  one's geometry with the map's pairs disabled.

It never says free where the full geometric check at the same margin says collision, as long as
``margin`` does not exceed the map's stopping distance (plus ``Tolerances.cspace_contact``): the
map's "allowed" is proven for every configuration of its cell × bin box at that clearance.  A
larger margin is refused (BackendError: rebuild the map with that stopping distance).  A smaller
one is answered at the map's stopping distance for the mapped pairs (conservative).

**Verdicts only** (``capabilities = {VERDICTS}``).  The map holds no distances — only that a
configuration's mapped pairs are farther than the stopping distance, or not proven so — and the
interface's ``pair_distances`` promises signed distances with witness points for every pair, which
a lower bound without witness points would not honour.  ``pair_distances``, ``nearest`` and
``min_distance_many`` raise BackendError.

**The model check.**  The map's header records the name and sha256 of the model files it was built
from (sidecar, URDF, SRDF and every mesh); they must equal ``model.files``'s, else BackendError
saying what changed (rebuild the map).  A damaged map (a checksum or a decoding check fails) is a BackendError too.  A missing map
is a BackendError with the command that builds it.

Options: ``map`` (path, required), ``geometric`` (backend name, default ``"analytic"``),
``geometric_options`` (a mapping) or ``geometric.KEY`` entries (``--backend-option
forbidden.geometric.threads=1``) for the geometric backend's options.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import numpy as np

from armguard._errors import BackendError, ForbiddenMapError
from armguard.backends import Capability, CheckerBase, check_margin, check_Q

__all__ = ["ForbiddenBackend", "ForbiddenChecker", "build_command"]

_OPTIONS = ("geometric", "geometric_options", "geometric.KEY", "map")


def build_command(model, out, stopping_distance: float | str = "<worst case, m>") -> str:
    """The ``armguard cspace build`` command line that writes a map for ``model`` at ``out``."""
    from armguard.model import builtin_model_names

    spec = model.name if model.name in builtin_model_names() else (str(model.files[0]) if model.files else model.name)
    return f"armguard cspace build {spec} --resolution 1deg --stopping-distance {stopping_distance} --out {out}"


def _split_options(options: Mapping | None) -> tuple[str, str, dict]:
    opts = dict(options or {})
    path = opts.pop("map", None)
    geometric = str(opts.pop("geometric", "analytic"))
    geo = dict(opts.pop("geometric_options", None) or {})
    for key in [k for k in opts if str(k).startswith("geometric.")]:
        geo[str(key).split(".", 1)[1]] = opts.pop(key)
    if opts:
        raise BackendError(f"forbidden: unknown options {sorted(opts)}; options are {list(_OPTIONS)}")
    if geometric == "forbidden":
        raise BackendError("forbidden: geometric must be another backend (analytic, coal, ...), not forbidden itself")
    return path, geometric, geo


class ForbiddenChecker(CheckerBase):
    """A verdicts-only Checker: a forbidden-values map for its pairs, a geometric backend for the rest.

    Attributes
    ----------
    combined : armguard.cspace.CombinedChecker
        The Fig. 14 logic (``combined.map``, ``combined.geometric``: the geometric backend's Checker).
    max_margin : float, m
        The largest ``margin`` answered: the map's stopping distance plus ``cspace_contact``.
    """

    name = "forbidden"
    capabilities = frozenset({Capability.VERDICTS})

    def __init__(self, model, options: Mapping | None = None) -> None:
        from armguard.cspace import CombinedChecker, ForbiddenMap

        super().__init__(model)
        path, geometric, geo = _split_options(options)
        if path is None:
            raise BackendError("forbidden: option 'map' is required (the .agmap file); build one with "
                               f"`{build_command(model, 'maps/' + model.name + '.agmap')}`")
        path = Path(str(path)).expanduser()
        if path.is_dir():
            raise BackendError(f"forbidden: map {path} is a folder, not a .agmap file; build one with "
                               f"`{build_command(model, path / (model.name + '.agmap'))}`")
        if not path.is_file():
            raise BackendError(f"forbidden: map {path} not found; build it with `{build_command(model, path)}`")
        if not model.files:
            raise BackendError(f"forbidden: model {model.name!r} has no source files, so the map {path} cannot be "
                               "checked against it; load the model with armguard.load_model(name or path)")
        try:
            fmap = ForbiddenMap.load(path, model=[str(p) for p in model.files])
            self.combined = CombinedChecker(fmap, model, backend=geometric, backend_options=geo).prepare()
        except ForbiddenMapError as exc:
            raise BackendError(f"forbidden: {exc}; for model {model.name!r}: "
                               f"`{build_command(model, path, _sd(path))}`") from None
        self.map = fmap
        self.geometric = self.combined.geometric
        self.max_margin = self.combined.max_margin
        self.representation = dict(getattr(self.geometric, "representation", {}) or {})

    def _margin(self, margin) -> float:
        m = check_margin(margin)
        if m > self.max_margin:
            raise BackendError(f"forbidden: margin {m} m exceeds the map's stopping distance "
                               f"{self.map.stopping_distance} m (the map proves links {self.map.links} clear by that "
                               f"much only); rebuild it with `{build_command(self.model, self.map.path, m)}`")
        return m

    def verdicts(self, Q, *, margin: float = 0.0):
        """:class:`armguard.cspace.CombinedBatch` for ``Q`` ``(M, nq)``: per row FREE, MAP_FORBIDDEN or COLLISION."""
        Q = check_Q(self.model, Q)
        return self.combined.check_many_pin(Q, margin=self._margin(margin))

    def collides(self, Q, *, margin: float = 0.0) -> np.ndarray:
        """``(M,) bool`` for ``Q`` ``(M, nq)``: the map forbids joints 1–3, or another pair is within ``margin`` (m)."""
        return self.verdicts(Q, margin=margin).collision

    def pair_distances(self, q):
        self._require(Capability.DISTANCES)


def _sd(path) -> str:
    try:
        from armguard.cspace._format import read_header

        return str(read_header(path)[0]["stopping_distance"])
    except Exception:  # noqa: BLE001 - only for the message
        return "<worst case, m>"


class ForbiddenBackend:
    """Entry point ``forbidden`` of the group ``armguard.backends``."""

    name = "forbidden"

    def build(self, model, options: Mapping | None = None) -> ForbiddenChecker:
        return ForbiddenChecker(model, options)
