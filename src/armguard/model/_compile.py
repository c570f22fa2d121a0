"""``compile_scene``: a Scene as flat structure-of-arrays for the numba kernels.

Layout (all arrays C-contiguous; float64 in m, int64 indices; ``*_start`` arrays are CSR
offsets of length ``count + 1``: the items of entry ``i`` are ``start[i]:start[i + 1]``):

Owners (``n_owners``; order of :meth:`Scene.owners`: bodies, links, payloads)
    ``owner_names`` tuple[str]; ``owner_kind`` (0 body, 1 link, 2 payload);
    ``owner_robot`` robot id (-1 for bodies); ``owner_link`` link index in that robot's
    ``link_names`` (for payloads: the holding link; -1 for bodies); ``owner_category``
    (0 vehicle, 1 environment, -1 for links and payloads).

Robots (``n_robots``; scene order)
    ``robot_names``; ``robot_joint_start`` (n_robots + 1): a robot's joints in the flat q;
    ``robot_n_links``.

Elements: one per shape (``n_elem``), grouped by owner (``owner_elem_start``, n_owners + 1)
    ``elem_owner``, ``elem_kind``, ``elem_robot``, ``elem_link`` (copies of their owner's);
    ``elem_core`` (:class:`armguard.geometry.CoreKind`); ``elem_radius`` (m).
    Geometry is in the element's *frame*: the world W for bodies, the link frame L for links
    and payloads (a payload's ``X_LP`` is already applied), so a kernel moves it with X_WL.
    ``elem_vert_start`` -> ``verts`` (nv, 3): the core points (sphere 1, capsule 2, box 8,
    prism 2n, polyhedron V, polygon n; a cylinder: the 2 x 16 corners of its circumscribed prism,
    a hull that contains it, for bounds only -- its kernels use the exact cylinder).
    ``elem_box_center`` (n_elem, 3), ``elem_box_axes`` (n_elem, 3, 3) with the box axes as
    columns (R_FB), ``elem_box_half`` (n_elem, 3): zeros for non-boxes; a cylinder stores its
    centre, R_FC (the axis as third column) and ``(radius, radius, half_length)`` there (its
    bounding box, and the 15-float buffer of ``armguard.geometry._pair_cylinder``).
    ``elem_sphere`` (n_elem, 4): a bounding sphere ``[centre, radius]`` (Hermes's pre-test).
    ``elem_plane_start`` -> ``planes`` (np, 4): ``[n, d]`` with unit outward n, inside
    ``n . x <= d`` (a polygon has one plane, its normal side).
    ``elem_face_start`` -> faces; ``face_vert_start`` (n_faces + 1) -> ``face_verts``: global
    indices into ``verts``, counter-clockwise seen from outside (face ``f`` of an element
    has plane ``planes[elem_plane_start[e] + f - elem_face_start[e]]``).
    ``elem_edge_start`` -> ``edges`` (ne, 2): global vertex indices (a capsule's segment is one
    edge; a sphere and a cylinder have none, nor faces or planes).

Pairs
    ``pair_a``, ``pair_b`` (owner ids), ``pair_category`` (index into ``PAIR_CATEGORIES``):
    :meth:`Scene.allowed_pairs`.  ``pair_elem_start`` (n_pairs + 1) -> ``elem_pair_a``,
    ``elem_pair_b``: the element pairs of each owner pair.

Workspace
    ``has_workspace``; ``workspace_lo``, ``workspace_hi`` (3,) in W (zeros when absent).
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass, fields

import numpy as np

from ..geometry import Box, Capsule, ConvexPolyhedron, Cylinder, Polygon, Prism, Sphere
from ._scene import PairCategory, Scene

__all__ = ["CompiledScene", "compile_scene", "compile_owners", "scene_robots", "PAIR_CATEGORIES", "OWNER_BODY", "OWNER_LINK", "OWNER_PAYLOAD"]

OWNER_BODY, OWNER_LINK, OWNER_PAYLOAD = 0, 1, 2
PAIR_CATEGORIES: tuple[PairCategory, ...] = tuple(PairCategory)


@dataclass(frozen=True, eq=False)
class CompiledScene:
    """A Scene as flat arrays; see the module docstring for the layout.  Read-only."""

    owner_names: tuple
    owner_kind: np.ndarray
    owner_robot: np.ndarray
    owner_link: np.ndarray
    owner_category: np.ndarray
    owner_elem_start: np.ndarray
    robot_names: tuple
    robot_joint_start: np.ndarray
    robot_n_links: np.ndarray
    elem_owner: np.ndarray
    elem_kind: np.ndarray
    elem_robot: np.ndarray
    elem_link: np.ndarray
    elem_core: np.ndarray
    elem_radius: np.ndarray
    elem_sphere: np.ndarray
    elem_vert_start: np.ndarray
    verts: np.ndarray
    elem_box_center: np.ndarray
    elem_box_axes: np.ndarray
    elem_box_half: np.ndarray
    elem_plane_start: np.ndarray
    planes: np.ndarray
    elem_face_start: np.ndarray
    face_vert_start: np.ndarray
    face_verts: np.ndarray
    elem_edge_start: np.ndarray
    edges: np.ndarray
    pair_a: np.ndarray
    pair_b: np.ndarray
    pair_category: np.ndarray
    pair_elem_start: np.ndarray
    elem_pair_a: np.ndarray
    elem_pair_b: np.ndarray
    has_workspace: bool
    workspace_lo: np.ndarray
    workspace_hi: np.ndarray

    @property
    def n_elements(self) -> int:
        """Number of shapes (elements)."""
        return int(self.elem_owner.shape[0])

    @property
    def n_faces(self) -> int:
        """Number of faces of all polytope elements (boxes, prisms, polyhedra, polygons)."""
        return int(self.face_vert_start.shape[0] - 1)

    @property
    def nbytes(self) -> int:
        """Size of the numeric arrays in bytes (the compiled database; names excluded)."""
        return int(sum(getattr(self, f.name).nbytes for f in fields(self) if isinstance(getattr(self, f.name), np.ndarray)))


def _ccw(verts: np.ndarray, idx, n: np.ndarray) -> list[int]:
    """Order the vertex indices ``idx`` of a planar face counter-clockwise about the outward ``n``."""
    pts = verts[list(idx)]
    c = pts.mean(axis=0)
    u = pts[0] - c
    u = u - n * float(u @ n)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    ang = np.arctan2((pts - c) @ v, (pts - c) @ u)
    return [int(list(idx)[k]) for k in np.argsort(ang)]


def _box_topology(box: Box):
    """Faces and planes of a box without a hull computation (6 faces of 4 corners)."""
    V = box.vertices
    faces, planes = [], []
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    for axis in range(3):
        for s in (-1, 1):
            idx = np.flatnonzero(signs[:, axis] == s)
            n = s * box.rotation[:, axis]
            faces.append(_ccw(V, idx, n))
            planes.append([*n, float(n @ box.center) + box.half_extents[axis]])
    return V, faces, np.array(planes)


def _polytope(shape):
    """``(verts, faces, planes, edges)`` of a polytope shape: faces as ``(flat local vertex
    indices, per-face lengths)`` int64 arrays, edges ``(ne, 2)`` local index pairs ``a < b``,
    sorted, each once."""
    if isinstance(shape, Box):
        V, faces, planes = _box_topology(shape)
    elif isinstance(shape, Polygon):
        V = shape.vertices
        faces = [list(range(len(V)))]
        planes = np.array([[*shape.normal, shape.offset]])
    else:
        poly = shape.as_polyhedron() if isinstance(shape, Prism) else shape
        if not isinstance(poly, ConvexPolyhedron):  # pragma: no cover - every polytope is handled above
            raise TypeError(type(shape).__name__)
        V, faces, planes = poly.vertices, poly.faces, poly.planes
    lens = np.fromiter((len(f) for f in faces), dtype=np.int64, count=len(faces))
    flat = np.concatenate([np.asarray(f, dtype=np.int64) for f in faces]) if len(faces) else np.zeros(0, np.int64)
    # each face's edges (f[i], f[i + 1 mod n]): the next index is one on, the last wraps to the first
    start = np.repeat(np.cumsum(lens) - lens, lens)
    pos = np.arange(len(flat)) - start
    nxt = flat[start + (pos + 1) % np.repeat(lens, lens)]
    e = np.stack([np.minimum(flat, nxt), np.maximum(flat, nxt)], axis=1)
    edges = np.unique(e, axis=0) if len(e) else np.zeros((0, 2), np.int64)
    return V, (flat, lens), np.asarray(planes, dtype=np.float64).reshape(-1, 4), edges


_SEGMENT_EDGE = np.array([[0, 1]], dtype=np.int64)  # a capsule's segment
_NO_EDGE = np.zeros((0, 2), dtype=np.int64)
_NO_FACE = np.zeros(0, dtype=np.int64)


def _ro(a, dtype) -> np.ndarray:
    a = np.ascontiguousarray(np.asarray(a, dtype=dtype))
    a.flags.writeable = False
    return a


def compile_scene(scene: Scene) -> CompiledScene:
    """Flatten ``scene`` into a :class:`CompiledScene` (explicit, repeatable; the scene is unchanged),
    holding its lock (:attr:`Scene.lock`): an edit on another thread waits, never lands half-read."""
    lock = getattr(scene, "lock", None)
    with lock if lock is not None else contextlib.nullcontext():
        return _compile_scene(scene)


def _compile_scene(scene: Scene) -> CompiledScene:
    robot_names = tuple(scene.robots)
    rid = {r: i for i, r in enumerate(robot_names)}
    # owners and their shapes in the element frame
    owners: list[tuple[str, int, int, int, int, tuple]] = []  # name, kind, robot, link, category, shapes
    for b in scene.bodies.values():
        owners.append((b.name, OWNER_BODY, -1, -1, 0 if b.category == "vehicle" else 1, b.shapes))
    for r in robot_names:
        robot = scene.robots[r]
        for i, ln in enumerate(robot.link_names):
            shapes = tuple(robot.link_shapes.get(ln, ()))
            if shapes:
                owners.append((f"{r}/{ln}", OWNER_LINK, rid[r], i, -1, shapes))
    for p in scene.payloads.values():
        robot = scene.robots[p.robot]
        shapes = tuple(s.transformed(p.X_LP) for s in p.shapes)
        owners.append((p.name, OWNER_PAYLOAD, rid[p.robot], robot.link_index(p.link), -1, shapes))
    oid = {o[0]: i for i, o in enumerate(owners)}
    cat_code = {c: i for i, c in enumerate(PAIR_CATEGORIES)}
    pairs = []
    for p in scene.allowed_pairs():
        a, b = oid[p.a], oid[p.b]
        pairs.append((a, b, cat_code[p.category], [(i, j) for i in range(len(owners[a][5])) for j in range(len(owners[b][5]))]))
    return compile_owners(scene_robots(scene), owners, pairs, scene.workspace)


def scene_robots(scene: Scene) -> tuple:
    """``(robot_names, joint_start, n_links)`` of ``scene``'s robots, as :func:`compile_owners` takes them."""
    robot_names = tuple(scene.robots)
    joint_start = [0]
    for r in robot_names:
        joint_start.append(joint_start[-1] + len(scene.robots[r].joint_names))
    return robot_names, joint_start, [len(scene.robots[r].link_names) for r in robot_names]


def compile_owners(robots: tuple, owners: list, pairs: list, workspace) -> CompiledScene:
    """The :class:`CompiledScene` of owners and pairs given as lists (the layout's one definition,
    shared by :func:`compile_scene` and the analytic engine's ``compile_model``).

    ``robots``: ``(robot_names, joint_start, n_links)`` (:func:`scene_robots`); ``owners``: one
    ``(name, kind, robot, link, category, shapes)`` per owner, shapes in the element frame (W for
    bodies, the link frame for links and payloads); ``pairs``: one ``(owner a, owner b, category
    code, [(shape i of a, shape j of b), ...])`` per owner pair; ``workspace``: a
    :class:`~armguard.scene.WorkspaceBox` or None."""
    robot_names, joint_start, n_links = robots
    owner_elem_start = [0]
    e_owner, e_kind, e_robot, e_link, e_core, e_rad, e_sphere = [], [], [], [], [], [], []
    vstart, verts = [0], []
    bc, ba, bh = [], [], []
    pstart, planes = [0], []
    fstart, fvstart, fverts = [0], [np.zeros(1, np.int64)], []
    estart, edges = [0], []
    nv = n_fv = n_e = 0
    for k, (_, kind, r, ln, _, shapes) in enumerate(owners):
        for s in shapes:
            e_owner.append(k)
            e_kind.append(kind)
            e_robot.append(r)
            e_link.append(ln)
            e_core.append(int(s.core_kind))
            e_rad.append(float(s.core_radius))
            cs = s.circumscribed_sphere()
            e_sphere.append([*cs.center, cs.radius])
            if isinstance(s, Box):
                bc.append(s.center), ba.append(s.rotation), bh.append(s.half_extents)
            elif isinstance(s, Cylinder):  # its pose and size in the box slots: [c, (r, r, h), R_FC]
                bc.append(s.center), ba.append(s.rotation), bh.append(np.array([s.radius, s.radius, s.half_length]))
            else:
                bc.append(np.zeros(3)), ba.append(np.zeros((3, 3))), bh.append(np.zeros(3))
            if isinstance(s, (Sphere, Capsule, Cylinder)):
                V = s.core_points  # a Cylinder: the circumscribed prism's corners, bounds only
                local_edges = _SEGMENT_EDGE if isinstance(s, Capsule) else _NO_EDGE
                flat, lens, pl = _NO_FACE, _NO_FACE, np.zeros((0, 4))
            else:
                V, (flat, lens), pl, local_edges = _polytope(s)
            verts.append(np.asarray(V, dtype=np.float64))
            planes.append(pl)
            fverts.append(flat + nv)
            fvstart.append(n_fv + np.cumsum(lens))
            n_fv += len(flat)
            edges.append(local_edges + nv)
            n_e += len(local_edges)
            nv += len(V)
            vstart.append(nv)
            pstart.append(pstart[-1] + len(pl))
            fstart.append(fstart[-1] + len(lens))
            estart.append(n_e)
        owner_elem_start.append(len(e_owner))

    pa, pb, pc, pestart, epa, epb = [], [], [], [0], [], []
    for a, b, c, shape_pairs in pairs:
        pa.append(a), pb.append(b), pc.append(c)
        ea, eb = owner_elem_start[a], owner_elem_start[b]
        for i, j in shape_pairs:
            epa.append(ea + i), epb.append(eb + j)
        pestart.append(len(epa))

    ws = workspace
    i64, f64 = np.int64, np.float64
    return CompiledScene(
        owner_names=tuple(o[0] for o in owners),
        owner_kind=_ro([o[1] for o in owners], i64),
        owner_robot=_ro([o[2] for o in owners], i64),
        owner_link=_ro([o[3] for o in owners], i64),
        owner_category=_ro([o[4] if o[1] == OWNER_BODY else -1 for o in owners], i64),
        owner_elem_start=_ro(owner_elem_start, i64),
        robot_names=tuple(robot_names),
        robot_joint_start=_ro(joint_start, i64),
        robot_n_links=_ro(n_links, i64),
        elem_owner=_ro(e_owner, i64),
        elem_kind=_ro(e_kind, i64),
        elem_robot=_ro(e_robot, i64),
        elem_link=_ro(e_link, i64),
        elem_core=_ro(e_core, i64),
        elem_radius=_ro(e_rad, f64),
        elem_sphere=_ro(np.reshape(e_sphere, (-1, 4)), f64),
        elem_vert_start=_ro(vstart, i64),
        verts=_ro(np.vstack(verts) if verts else np.zeros((0, 3)), f64),
        elem_box_center=_ro(np.reshape(bc, (-1, 3)), f64),
        elem_box_axes=_ro(np.reshape(ba, (-1, 3, 3)), f64),
        elem_box_half=_ro(np.reshape(bh, (-1, 3)), f64),
        elem_plane_start=_ro(pstart, i64),
        planes=_ro(np.vstack(planes) if planes else np.zeros((0, 4)), f64),
        elem_face_start=_ro(fstart, i64),
        face_vert_start=_ro(np.concatenate(fvstart), i64),
        face_verts=_ro(np.concatenate(fverts) if fverts else np.zeros(0), i64),
        elem_edge_start=_ro(estart, i64),
        edges=_ro(np.concatenate(edges) if edges else np.zeros((0, 2)), i64),
        pair_a=_ro(pa, i64),
        pair_b=_ro(pb, i64),
        pair_category=_ro(pc, i64),
        pair_elem_start=_ro(pestart, i64),
        elem_pair_a=_ro(epa, i64),
        elem_pair_b=_ro(epb, i64),
        has_workspace=ws is not None,
        workspace_lo=_ro(ws.lo if ws is not None else np.zeros(3), f64),
        workspace_hi=_ro(ws.hi if ws is not None else np.zeros(3), f64),
    )
