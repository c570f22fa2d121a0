"""The engine's element arrays and candidate pairs compiled straight from the Model.

:func:`compile_model` writes a :class:`armguard.scene.CompiledScene` (the layout of
:func:`armguard.scene.compile_scene`, its module docstring; :func:`armguard.model._compile.compile_owners`
is the one definition of it) from

* ``model.collision_model``: one element per GeometryObject, its shape the object's coal
  geometry (``coal.Capsule``, ``Sphere``, ``Box``, ``Cylinder``, ``Convex``:
  :func:`armguard.model._shapes.shape_from_coal`; a mesh's ``Convex`` as the hull it was built
  from, ``Model.hulls``, :func:`~armguard.model._shapes.shape_of_polytope`, so a hull keeps its
  vertex set and merged faces) at its placement.  Pinocchio places an object in its parent joint's
  frame (``oMg = oMi[parentJoint] * placement``); the element frame is the engine tree's link frame
  L of the scene link it is fixed to (:meth:`armguard.model.Model.kinematic_tree`: ``F_L = frames[link_frames[L]].placement
  X_FL`` in that joint's frame, ``Model.link_frames``, ``Model.link_placement``), so the element is
  at ``X_LG = F_L^-1 placement``; a static body's (parent joint 0, the universe, at the identity)
  is at ``X_WG = placement``; a payload's in its holding link's frame, the same way.  An object on
  another joint than its link's raises :class:`armguard.DetectionError` naming it;
* ``model.pairs`` (:class:`armguard.model.GeometryPairs`): its rows, by GeometryObject name, as
  the element pairs, consecutive rows of one owner pair as one owner pair of that category; the
  workspace rows are the engine's own (one per moving element, ``_model.build_model``);
* the Model's map from scene owners to GeometryObjects (``Model.geometry_name``): which objects
  make one owner, and the element order (owners as :meth:`Scene.owners` lists them, each owner's
  objects in its order), so the element and pair numbering is compile_scene's.

What the GeometryModel has no counterpart for comes from the Model too: the robots' names and
link order (``Model.robots``: the engine tree's rows, :meth:`armguard.model.Model.kinematic_tree`, index links that way),
which owners are static bodies, links or payloads and a body's category (``Model.bodies``,
``Model.payloads``: ``vehicle`` or ``environment``, an SRDF group), the link that holds a payload,
and the workspace box (``Model.workspace``: an axis-aligned box in W whose walls are no
GeometryObject).  Nothing is read from ``model.scene``.

The shapes are made once per Model (as its kinematic tree is, ``_model.engine_tree``: a Model's
GeometryModel and frames do not change; the owner pairs and the workspace box are read each time).

``_model.build_model`` compiles the scene's Model (``armguard.model.model_of``): after
``add_body``, ``attach_payload`` and the like, one derived from the Model the scene was loaded as
(:mod:`armguard.model._derive`).  ``compile_scene`` compiles a scene without robots that no Model
was made for and an edited scene with thousands of new objects (``_model._DERIVE_BUDGET``), and is
the slow reference the tests hold this to.
"""

from __future__ import annotations

import numpy as np

from armguard._errors import DetectionError
from armguard.model import WORKSPACE
from armguard.model._compile import OWNER_BODY, OWNER_LINK, OWNER_PAYLOAD, PAIR_CATEGORIES, compile_owners, scene_robots
from armguard.model._from_pin import _inv, _se3
from armguard.model._shapes import shape_from_coal, shape_of_polytope

__all__ = ["compile_model", "compile_model_parts"]

_CAT_CODE = {c.value: i for i, c in enumerate(PAIR_CATEGORIES)}


def compile_model(model):
    """The :class:`~armguard.scene.CompiledScene` of ``model`` (see the module docstring)."""
    return compile_model_parts(model)[0]


def compile_model_parts(model) -> tuple:
    """``(compiled, static_shapes)``: :func:`compile_model`'s arrays and, per static element number,
    its shape in W (the detector's static polytopes and feature annotations use the shape objects)."""
    # made once per Model: its GeometryModel does not change (a derived Model starts with the links' shapes)
    cache = model.__dict__.setdefault("_engine_shapes", {})
    names = cache.get("owners")
    if names is None:
        names = cache.setdefault("owners", _owner_objects(model))

    def shapes_in(owner: str, link: str | None) -> tuple:
        """``owner``'s objects as shapes in scene link ``link``'s frame (None: in W), made once per Model."""
        hit = cache.get((owner, link))
        if hit is None:
            hit = cache[(owner, link)] = _shapes_in(model, names.get(owner, ()), owner, link)
        return hit

    robots = scene_robots(model)
    rid = {r: i for i, r in enumerate(robots[0])}
    owners = []  # name, kind, robot, link, category, shapes: compile_owners' input, compile_scene's order
    static_shapes, g = {}, 0
    for b in model.bodies.values():
        shapes = shapes_in(b.name, None)
        owners.append((b.name, OWNER_BODY, -1, -1, 0 if b.category == "vehicle" else 1, shapes))
        for s in shapes:
            static_shapes[g] = s
            g += 1
    for r, robot in model.robots.items():
        for i, ln in enumerate(robot.link_names):
            owner = f"{r}/{ln}"
            if owner in names:
                owners.append((owner, OWNER_LINK, rid[r], i, -1, shapes_in(owner, owner)))
    for p in model.payloads.values():
        owners.append((p.name, OWNER_PAYLOAD, rid[p.robot], model.robots[p.robot].link_index(p.link), -1,
                       shapes_in(p.name, p.owner_link)))

    # the pairs: Model.pairs' rows, consecutive rows of one owner pair as one owner pair
    oid = {o[0]: k for k, o in enumerate(owners)}
    local = cache.get("local")
    if local is None:
        local = cache["local"] = {gname: i for lst in names.values() for i, gname in enumerate(lst)}
    pairs: list = []
    P = model.pairs
    key = None
    for a, b, oa, ob, cat in zip(P.a, P.b, P.owner_a, P.owner_b, P.category):
        if b == WORKSPACE:
            continue
        if (oa, ob, cat) != key:
            key = (oa, ob, cat)
            pairs.append((oid[oa], oid[ob], _CAT_CODE[cat], []))
        pairs[-1][3].append((local[a], local[b]))
    return compile_owners(robots, owners, pairs, model.workspace), static_shapes


def _owner_objects(model) -> dict:
    """Scene owner -> its GeometryObject names, in shape order (``Model.geometry_name``'s map)."""
    names: dict[str, list] = {}
    for (owner, i), gname in model._geom.items():
        lst = names.setdefault(owner, [])
        lst.extend([None] * (i + 1 - len(lst)))
        lst[i] = gname
    for owner, lst in names.items():
        if None in lst:
            raise DetectionError(f"model {model.name!r}: owner {owner!r} has a shape with no GeometryObject "
                                 f"(shape {lst.index(None)})")
    return names


def _shapes_in(model, gnames, owner: str, link: str | None) -> tuple:
    """The GeometryObjects ``gnames`` of ``owner`` as shapes in scene link ``link``'s frame L
    (``X_LG = F_L^-1 placement``, F_L: L in its parent joint's frame), or in W for ``link`` None
    (``X_WG = placement``: the object is on the universe)."""
    where = f"model {model.name!r}"
    if link is None:
        joint, X_inv = 0, None
    else:
        try:
            fr = model.pin_model.frames[int(model.link_frames[link])]
        except KeyError:
            raise DetectionError(f"{where}: scene link {link!r} has no frame in pin_model (Model.link_frames)") from None
        joint, X_inv = int(fr.parentJoint), _inv(_se3(fr.placement) @ model.link_placement(link))
    objs = model.collision_model.geometryObjects
    out = []
    for gname in gnames:
        go = objs[model.geometry_index(gname)]
        if int(go.parentJoint) != joint:
            on = "the universe (a static body)" if link is None else f"the joint of link {link!r}"
            raise DetectionError(f"{where}: GeometryObject {gname!r} of {owner!r} moves with Pinocchio joint "
                                 f"{int(go.parentJoint)}, not with {on}")
        X = _se3(go.placement) if X_inv is None else X_inv @ _se3(go.placement)
        mp = model.hulls.get(gname)
        out.append(shape_of_polytope(mp, X) if mp is not None else shape_from_coal(go.geometry, X)[0])
    return tuple(out)
