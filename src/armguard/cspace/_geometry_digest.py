"""What a forbidden-values map's verdicts depend on, as one digest: the mapped links against every static body.

A map built for one scene answers only for the pairs it was built on (the robot's links 1-3 against
the scene's static bodies, at its base).  A map built from a Scene object has no files to compare, and
:func:`armguard.cspace.map_model` took such a scene "as given": a body added to it, or the robot's base
moved, was answered by the map that never saw it (a 0.5 m sphere on Hermes's link 3: FREE where the
exact check says -0.68 m).  The digest is the SHA-256 of the static bodies' names and of
:func:`armguard.model._certificate.pair_digest` of each mapped link with each body (the shapes, their
placements, the joints between them and their limits), recorded in the map's header when it is built
and compared whenever a model or scene is put to it.
"""

from __future__ import annotations

import hashlib

__all__ = ["geometry_digest"]

_VERSION = b"armguard cspace geometry 1"


def geometry_digest(model, robot: str, links) -> tuple[str, list[str]]:
    """``(digest, bodies)``: the hex digest of the map's pairs in ``model`` (a Model) for ``robot``'s ``links``
    (their names in the robot), and the sorted names of the static bodies they are checked against."""
    import pinocchio as pin

    from ..model._certificate import pair_digest

    pm, gm = model.pin_model, model.collision_model
    bodies = sorted(str(b) for b in model.bodies)
    frames = [pm.frames[model.link_frames[f"{robot}/{ln}"]].name for ln in links]
    h = hashlib.sha256(_VERSION)
    h.update(repr(bodies).encode())
    for b in bodies:
        h.update(b" body " + b.encode())
        for go in gm.geometryObjects:  # a body's frame is its name; its shapes hang from it
            if pm.frames[int(go.parentFrame)].name == b and pm.frames[int(go.parentFrame)].type == pin.BODY:
                for f in frames:
                    d = pair_digest(pm, gm, f, b, margin=0.0, method="cspace")
                    h.update(d if d is not None else b"none")
                break
    return h.hexdigest(), bodies
