"""A Model for a scene whose bodies or payloads changed, derived from the Model it was loaded as.

``add_body``, ``remove_body``, ``attach_payload``, ``release_payload`` and ``grasp`` change the
scene's shapes, not its robots.  The Model the scene was loaded as still holds the kinematics
(``pin_model``, ``q_index``, ``link_frames``, the SRDF), so :func:`derive_model` builds the new
Model from it instead of writing the scene as URDF and reading it back
(:func:`armguard.model.model_from_scene`):

* the GeometryModel is a copy of the old one (its coal geometries are shared, not copied) less
  the objects of the bodies and payloads that are gone, plus an object per shape of those that
  are new, made as the URDF writer and Pinocchio's reader would make it
  (:mod:`armguard.model.export`): shape ``i`` of owner ``N`` is the object ``N_i``; a body's
  objects are fixed to the universe, a payload's to its holding link's joint at
  ``X_JF X_FL X_LP X_PG``; a Prism or ConvexPolyhedron is a convex mesh hull
  (:func:`~armguard.model._hull.mesh_polytope`, in ``Model.hulls``), a Polygon a flat one, a
  Cylinder an exact ``coal.Cylinder``;
* the SRDF and the compiled kinematic trees are the old Model's; it has no source files (``files``,
  ``sha256`` empty, as a scene built in code: the files describe the loaded shapes, and a
  forbidden-values map or golden reference checked against them must not accept the new ones);
  the pairs follow the scene (``Model.pairs``).

A robot added after the loaded ones (``add_robot``) is written as URDF alone, read by Pinocchio
and appended (``pinocchio.appendModel`` on the universe; a frame, joint or object name the loaded
Model already has gets ``#k``), so the loaded robots keep their joints, frames, objects and SRDF
and only the new robot takes the writer's path.

The old Model is left as it was: Checkers and Detectors built on it keep answering for it.
``tests/test_model_derive.py`` holds a derived Model to the one the URDF round trip builds
(the same object names, placements and shapes) and the analytic engine's arrays to
``compile_scene``'s.
"""

from __future__ import annotations

import types

import numpy as np

from ..geometry import ConvexPolyhedron, Polygon, Prism
from ._from_pin import _inv, _se3
from ._hull import mesh_polytope
from ._model import Model, _frozen_spec
from ._shapes import coal_from_shape, convex_of_polytope

__all__ = ["derive_model", "derive_cost"]

# a Model's attributes that follow its GeometryModel: dropped or replaced in a derived one
_GEOMETRY_CACHES = ("_engine_shapes", "_pairs", "_bound")  # "_bound": Model.scene_for's copy, its own


def derive_cost(model: Model, scene) -> int:
    """About how many matrix entries Pinocchio copies to add the scene's new bodies' and payloads'
    objects to a copy of ``model``'s GeometryModel: ``addGeometryObject`` resizes an
    ``ngeoms x ngeoms`` pair map on every call, so adding ``k`` objects to ``n`` costs ``~k (n+k)^2``
    (10 000 boxes added one by one: minutes).  Callers with an alternative (the analytic engine's
    ``compile_scene``) use it above a budget."""
    old_bodies, old_payloads = model._parts
    kept = {n for n, b in old_bodies if scene.bodies.get(n) is b} | {n for n, p in old_payloads if scene.payloads.get(n) is p}
    k = sum(len(b.shapes) for n, b in scene.bodies.items() if n not in kept)
    k += sum(len(p.shapes) for n, p in scene.payloads.items() if n not in kept)
    n = int(model.collision_model.ngeoms) + k
    return k * n * n


def derive_model(model: Model, scene) -> Model | None:
    """A Model of ``scene`` from ``model``: its kinematics (with the robots ``set_robot_base``
    moved, and those ``add_robot`` added after its own appended) and ``scene``'s bodies and
    payloads; None when a robot of ``model`` was removed, reordered or changed otherwise."""
    import pinocchio as pin

    moved = _rebased(model, scene)
    if moved is None:
        return None
    added = list(scene.robots)[len(model._robots):]
    old_bodies, old_payloads = model._parts
    kept = {n for n, b in old_bodies if scene.bodies.get(n) is b} | {n for n, p in old_payloads if scene.payloads.get(n) is p}
    gone = {n for n, _ in (*old_bodies, *old_payloads)} - kept
    new_parts = [n for n in (*scene.bodies, *scene.payloads) if n not in kept]
    if not gone and not new_parts and not moved and not added:  # pair filters or the workspace only
        return _with_spec(model, scene)
    geom = model.collision_model.copy()
    names = {k: v for k, v in model._geom.items() if k[0] not in gone}
    for (owner, _), gname in model._geom.items():
        if owner in gone:
            geom.removeGeometryObject(gname)
    notes = {k: v for k, v in model.notes.items() if k in set(names.values())}
    hulls = {k: v for k, v in model.hulls.items() if k in set(names.values())}
    used = {go.name for go in geom.geometryObjects}

    def add(owner: str, shapes, joint: int, frame: int, X_JS: np.ndarray) -> None:
        for i, shape in enumerate(shapes):
            g, X_SG, mp = _coal_object(shape)
            gname = _fresh(f"{owner}_{i}", used)
            X = X_JS @ X_SG
            geom.addGeometryObject(pin.GeometryObject(gname, joint, frame, pin.SE3(X[:3, :3], X[:3, 3]), g))
            names[(owner, i)] = gname
            if mp is not None:
                hulls[gname] = mp

    pin_model = _moved_bases(model, geom, names, moved, scene) if moved else model.pin_model
    kin = None
    if added:
        pin_model, geom, kin = _append_robots(model, pin_model, geom, names, used, scene, added)
        notes.update(kin.pop("notes"))
        hulls.update(kin.pop("hulls"))
    for name, body in scene.bodies.items():
        if name not in kept:
            add(name, body.shapes, 0, 0, np.eye(4))
    link_frames = kin["link_frames"] if kin is not None else model.link_frames
    placements = kin["_link_placements"] if kin is not None else model._link_placements
    for name, p in scene.payloads.items():
        if name not in kept:
            f = int(link_frames[p.owner_link])
            fr = pin_model.frames[f]
            X_FL = placements.get(p.owner_link)
            X_JL = _se3(fr.placement) @ (np.eye(4) if X_FL is None else X_FL)
            add(name, p.shapes, int(fr.parentJoint), f, X_JL @ np.asarray(p.X_LP, dtype=np.float64))

    new = object.__new__(Model)
    new.__dict__.update({k: v for k, v in model.__dict__.items() if k not in _GEOMETRY_CACHES})
    new.collision_model = geom
    if moved or added:  # other kinematics: the robots, and trees compiled again
        new.pin_model, new._robots = pin_model, tuple(scene.robots.items())
        new.__dict__.pop("_kinematic_trees", None)
    if kin is not None:  # joint and frame indices of the appended model
        new.__dict__.update(kin)
    # no source files: the files describe the loaded Model's shapes, not these (a forbidden-values
    # map or a golden reference checked against them must not accept this Model), as for a scene
    # built in code
    new.files, new.sha256, new.hull_cache = (), types.MappingProxyType({}), None
    new.scene = scene
    new._geom = names
    new._geom_index = {go.name: i for i, go in enumerate(geom.geometryObjects)}
    new.notes = types.MappingProxyType(notes)
    new.hulls = types.MappingProxyType(hulls)
    new._parts = (tuple(scene.bodies.items()), tuple(scene.payloads.items()))
    new._pairs = None
    new._spec, new._spec_revision = _frozen_spec(scene), scene.revision
    links = {f"{r}/{ln}" for r, robot in scene.robots.items() for ln in robot.link_names}
    shapes = model.__dict__.get("_engine_shapes")
    if shapes is not None and not moved and not added:  # the robots' link shapes are the same objects in the same frames
        # (owner, link) -> shapes; not "owners" or "local" (GeometryObject names): made again
        new._engine_shapes = {k: v for k, v in shapes.items() if isinstance(k, tuple) and k[0] in links}
    scene._model_of_record = new
    return new


def _with_spec(model: Model, scene) -> Model:
    """``model`` for ``scene`` whose shapes and kinematics it holds as they are and whose pair
    filters or workspace box changed: the same Pinocchio model and GeometryModel (shared, not
    copied: neither is changed after it is made) and the shapes made for the engine, pairs listed
    again.  No source files: the pairs may not be the files' (a forbidden-values map or golden
    reference checked against the files must not accept it)."""
    new = object.__new__(Model)
    new.__dict__.update({k: v for k, v in model.__dict__.items() if k not in ("_pairs", "_bound")})
    new.files, new.sha256, new.hull_cache = (), types.MappingProxyType({}), None
    new.scene = scene
    new._pairs = None
    new._parts = (tuple(scene.bodies.items()), tuple(scene.payloads.items()))
    new._spec, new._spec_revision = _frozen_spec(scene), scene.revision
    scene._model_of_record = new
    return new


def _rebased(model: Model, scene) -> dict | None:
    """Robot name -> ``D = X_WB' X_WB^-1`` for each robot of ``scene`` that is ``model``'s mounted
    elsewhere (``set_robot_base``: the same joints, links and shapes, another ``X_WB``); ``{}`` when
    ``model`` moves ``scene``'s first robots as they are (robots added after them are
    :func:`_append_robots`'); None when a robot was removed, reordered or changed otherwise."""
    old = dict(model._robots)
    if list(old) != list(scene.robots)[:len(old)]:
        return None
    moved = {}
    for r, o in old.items():
        new = scene.robots[r]
        if new is o:
            continue
        same = (new.joints is o.joints and new.joint_names == o.joint_names and new.link_names == o.link_names
                and new.tool_link == o.tool_link  # not the IK routine (set_robot_ik): pin_model has none
                and all(new.link_shapes[ln] is o.link_shapes[ln] for ln in o.link_names))
        if not same:
            return None
        moved[r] = np.asarray(new.X_WB, dtype=np.float64) @ _inv(np.asarray(o.X_WB, dtype=np.float64))
    return moved


def _moved_bases(model: Model, geom, names: dict, moved: dict, scene):
    """A copy of ``pin_model`` with each robot of ``moved`` mounted at ``D X_WB``: its root joints'
    placements, the frames on the universe that lead only to its links (its root link and the fixed
    joints above it; not a frame shared with another robot or a body, as the URDF writer's
    ``world``), and in ``geom`` its objects on the universe (its fixed links' and payloads') become
    ``D X``."""
    import pinocchio as pin

    pm = pin.Model(model.pin_model)
    frames = pm.frames

    def up(f: int) -> list:  # f and the frames above it on the universe, to (not including) frame 0
        out = []
        while f != 0 and int(frames[f].parentJoint) == 0:
            out.append(f)
            f = int(frames[f].parentFrame)
        return out

    robot_of_frame: dict[int, set] = {}
    for owner, f in model.link_frames.items():
        r = owner.split("/", 1)[0]
        for g in up(int(f)):
            robot_of_frame.setdefault(g, set()).add(r)
    for (owner, _), gname in names.items():  # a body's objects hold their frames for no robot
        go = geom.geometryObjects[geom.getGeometryId(gname)]
        if owner in scene.bodies and int(go.parentJoint) == 0:
            for g in up(int(go.parentFrame)):
                robot_of_frame.setdefault(g, set()).add(None)
    joint_robot = {}
    for owner, f in model.link_frames.items():
        j = int(frames[int(f)].parentJoint)
        while j != 0 and int(pm.parents[j]) != 0:
            j = int(pm.parents[j])
        if j != 0:
            joint_robot[j] = owner.split("/", 1)[0]
    for r, D in moved.items():
        S = pin.SE3(D[:3, :3], D[:3, 3])
        for f, rs in robot_of_frame.items():
            if rs == {r}:
                frames[f].placement = S * frames[f].placement
        for j, rj in joint_robot.items():
            if rj == r:
                pm.jointPlacements[j] = S * pm.jointPlacements[j]
        for (owner, _), gname in names.items():
            held = scene.payloads[owner].robot if owner in scene.payloads else owner.split("/", 1)[0] if "/" in owner else None
            go = geom.geometryObjects[geom.getGeometryId(gname)]
            if held == r and int(go.parentJoint) == 0:
                go.placement = S * go.placement
    return pm


def _append_robots(model: Model, pin_model, geom, names: dict, used: set, scene, added: list) -> tuple:
    """``(pin model, GeometryModel, attributes)``: ``pin_model`` and ``geom`` with the robots
    ``added`` appended on the universe.  They are written as URDF alone and read by Pinocchio
    (:func:`~armguard.model._load.model_from_scene` of a scene of just them, at their own
    ``X_WB``); a frame, joint or object name ``pin_model`` or ``geom`` already has gets ``#k``.
    ``names`` gets their objects; ``attributes`` are the new Model's ``_q_index``, ``_circular``,
    ``link_frames``, ``_link_placements`` (joints and frames renumbered by name) and the new
    robots' ``notes`` and ``hulls``."""
    import pinocchio as pin

    from ._load import model_from_scene
    from ._scene import Scene

    alone = Scene(f"{scene.name}+")
    for r in added:
        alone.add_robot(scene.robots[r], home=scene.home(r))
    sub = model_from_scene(alone)
    sp, sg = pin.Model(sub.pin_model), sub.collision_model.copy()
    frame_names = {f.name for f in pin_model.frames}
    for f in list(sp.frames)[1:]:
        if f.name in frame_names:
            f.name = _fresh(f.name, frame_names)
    joint_names = set(pin_model.names)
    for j in range(1, sp.njoints):
        if sp.names[j] in joint_names:
            sp.names[j] = _fresh(sp.names[j], joint_names)
    renamed = {}
    for go in sg.geometryObjects:
        renamed[go.name] = go.name = _fresh(go.name, used)
    # appendModel looks frames up by name alone, which fails where a URDF names a joint and a link
    # alike (rover's arm_turret, z1's gripperStator, so100's gripper): such names are made unique
    # for the call and given back after it
    pa = pin.Model(pin_model)
    restore = {**_unique_frame_names(pa, frame_names), **_unique_frame_names(sp, frame_names)}
    pm, gm = pin.appendModel(pa, sp, geom, sg, 0, pin.SE3.Identity())
    for f in pm.frames:
        if f.name in restore:
            f.name = restore[f.name]
    for src in (pa, sp):
        for f in src.frames:
            if f.name in restore:
                f.name = restore[f.name]
    gm.removeAllCollisionPairs()  # appendModel pairs every object of A with every one of B; the Model's pairs are its own

    def joint_map(src) -> dict:  # idx_q in src -> idx_q in pm, through the joint names
        out = {}
        for j in range(1, src.njoints):
            jm = src.joints[j]
            if jm.nq > 0:
                k = pm.joints[pm.getJointId(src.names[j])].idx_q
                out.update({jm.idx_q + i: k + i for i in range(jm.nq)})
        return out

    def frame_map(src, frames: dict) -> dict:
        return {o: int(pm.getFrameId(src.frames[int(f)].name, src.frames[int(f)].type)) for o, f in frames.items()}

    old_q, new_q = joint_map(pin_model), joint_map(sp)
    q_index = np.concatenate([[old_q[int(i)] for i in model._q_index], [new_q[int(i)] for i in sub._q_index]]).astype(np.int64)
    q_index.flags.writeable = False
    n_old = len(model._q_index)
    for (owner, i), gname in sub._geom.items():
        names[(owner, i)] = renamed[gname]
    return pm, gm, {
        "_q_index": q_index,
        "_circular": np.concatenate([model._circular, np.asarray(sub._circular, dtype=np.int64) + n_old]).astype(np.int64),
        "link_frames": types.MappingProxyType({**frame_map(pin_model, model.link_frames), **frame_map(sp, sub.link_frames)}),
        "_link_placements": {**model._link_placements, **sub._link_placements},
        "notes": {renamed[k]: v for k, v in sub.notes.items()},
        "hulls": {renamed[k]: v for k, v in sub.hulls.items()},
    }


def _unique_frame_names(pm, used: set) -> dict:
    """Rename, in ``pm``, each frame other than a BODY frame whose name another frame of ``pm`` has
    (to a name in no frame of ``used`` or ``pm``); returns new name -> old name."""
    import collections

    count = collections.Counter(f.name for f in pm.frames)
    taken = used | set(count)
    out = {}
    for f in pm.frames:
        if count[f.name] > 1 and f.type.name != "BODY":
            new = _fresh(f"{f.name}#{f.type.name.lower()}", taken)
            out[new] = f.name
            f.name = new
    return out


def _fresh(name: str, used: set) -> str:
    """``name``, or ``name#k`` for the least k that no GeometryObject has yet; recorded in ``used``."""
    out, k = name, 1
    while out in used:
        out, k = f"{name}#{k}", k + 1
    used.add(out)
    return out


def _coal_object(shape) -> tuple:
    """``(coal geometry, X_SG (4, 4), MeshPolytope or None)``: ``shape`` (given in frame S) as the
    URDF writer writes it and Pinocchio reads it back (see the module docstring); a zero-length
    Capsule stays a ``coal.Capsule`` (the writer makes it a sphere: the same points)."""
    if isinstance(shape, Prism):
        local = Prism(np.zeros(3), np.eye(3), shape.apothem, shape.half_length, shape.n_sides).as_polyhedron()
        X = np.eye(4)
        X[:3, :3], X[:3, 3] = shape.rotation, shape.center
        mp = mesh_polytope(np.asarray(local.vertices, dtype=np.float64))
        return convex_of_polytope(mp), X, mp
    if isinstance(shape, (ConvexPolyhedron, Polygon)):
        mp = mesh_polytope(np.asarray(shape.vertices, dtype=np.float64))
        return convex_of_polytope(mp), np.eye(4), mp
    g, X = coal_from_shape(shape)
    return g, X, None
