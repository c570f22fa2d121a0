"""A Model's kinematic tree, compiled straight from its Pinocchio model: the one forward kinematics.

Pinocchio's conventions (Carpentier et al., "The Pinocchio C++ library", SII 2019, sec. III;
``pinocchio/multibody/model.hpp``): joint ``j`` has parent joint ``parents[j]`` (0 is the
universe, at the identity), a placement ``jointPlacements[j]`` in its parent joint's frame, and
a motion ``M_j(q)``, so ``oMi[j] = oMi[parents[j]] * jointPlacements[j] * M_j(q)``; a frame ``f``
(a URDF link is a BODY frame) sits at ``placement[f]`` in its joint ``parentJoint[f]``'s frame:
``oMf[f] = oMi[parentJoint[f]] * placement[f]``.  One-DoF joints: ``JointModelR{X,Y,Z}`` and
``RevoluteUnaligned`` (a rotation by q about the axis), ``P{X,Y,Z}`` and ``PrismaticUnaligned``
(a translation by q along it), ``RUB{X,Y,Z}`` and ``RevoluteUnboundedUnaligned`` (continuous: q
holds ``(cos, sin)`` of the angle), and ``JointModelMimic`` (``mimic=True`` loading: the motion of
its own joint model at ``scaling * q[primary] + offset``, no q of its own, ``idx_q`` the
primary's).  Fixed URDF joints are no joints: the links they join share a parent joint.

:func:`pin_tree` writes this as the :class:`armguard.kinematics._fk.FlatTree` the kernels run
(one row per scene link, scene order, joint terms over the scene's flat q, ``Model.q_index``):
for a link L fixed to BODY frame ``f_L`` at ``X_FL`` (``Model.link_frames``,
``Model.link_placement``) below link P (the nearest scene link of the same robot above it in
Pinocchio's frame tree; the universe for a robot's root), with ``F_L = placement[f_L] X_FL`` (L
in its joint's frame),

* same parent joint: ``X_pre = F_P^-1 F_L``, fixed;
* the joints ``j_1 .. j_n`` between them (``j_1`` below ``P``'s joint): ``X_pre =
  F_P^-1 jointPlacements[j_1]``, the motion of ``j_1 .. j_n`` as one, ``X_post = F_L``.
  ``n > 1`` (a coupled joint written as a chain of mimic joints, as :mod:`armguard.model.export`
  does) is one motion only when the lower joints' placements are the identity and every joint
  moves about (along) the same axis: then the values add, as terms.

Joint axes: the table above for the aligned kinds; the motion subspace ``S`` Pinocchio computes
for the unaligned kinds and for a mimic (``S = scaling * S_own``: the axis is ``S / scaling``;
its own joint model is not exposed to Python).

Anything else (a multi-DoF joint, a chain that does not collapse, a link below another robot)
raises :class:`armguard.DetectionError` naming the joint: the engine never approximates.
"""

from __future__ import annotations

import numpy as np

from .._errors import DetectionError
from ..kinematics._fk import JT_FIXED, JT_PRISMATIC, JT_REVOLUTE, FlatTree

__all__ = ["pin_tree"]

_E = {a: np.array(e) for a, e in (("X", (1.0, 0.0, 0.0)), ("Y", (0.0, 1.0, 0.0)), ("Z", (0.0, 0.0, 1.0)))}
_ALIGNED = {**{f"JointModelR{a}": (JT_REVOLUTE, e) for a, e in _E.items()},
            **{f"JointModelRUB{a}": (JT_REVOLUTE, e) for a, e in _E.items()},
            **{f"JointModelP{a}": (JT_PRISMATIC, e) for a, e in _E.items()}}
_UNALIGNED = {"JointModelRevoluteUnaligned": JT_REVOLUTE, "JointModelRevoluteUnboundedUnaligned": JT_REVOLUTE,
              "JointModelPrismaticUnaligned": JT_PRISMATIC}


def _se3(M) -> np.ndarray:
    return np.array(M.homogeneous, dtype=np.float64)


_I4 = np.eye(4)
_I4.flags.writeable = False


def _is_identity(X: np.ndarray) -> bool:
    return bool((X == _I4).all())


def _joint_motion(name: str, jm, pdata, j: int, scene_k: dict, where: str):
    """``(jtype, unit axis, offset, [(scene k, coeff)])`` of Pinocchio joint ``j`` (``jm``, named ``name``)."""
    short = jm.shortname()
    if short == "JointModelMimic":
        mim = jm.extract()
        scaling, offset = float(mim.scaling), float(mim.offset)
        # its own joint model is not exposed to Python: its motion subspace is, S = scaling * S_own
        S = np.asarray(pdata.joints[j].S, dtype=np.float64).ravel()
        lin, ang = S[:3], S[3:]
        if scaling == 0.0 or (np.any(lin) and np.any(ang)) or not (np.any(lin) or np.any(ang)):
            raise DetectionError(f"{where}: mimic joint {name!r} (scaling {scaling}, motion subspace {S.tolist()}) is not a "
                                 "revolute or prismatic mimic the analytic engine can express")
        jt, axis = (JT_REVOLUTE, ang) if np.any(ang) else (JT_PRISMATIC, lin)
        axis = axis / scaling
        k = scene_k.get(int(jm.idx_q))
        if k is None or k[1]:
            raise DetectionError(f"{where}: mimic joint {name!r} follows pin q[{jm.idx_q}], which is not a one-value "
                                 "joint of the scene (a continuous joint's angle cannot be scaled)")
        terms = [(k[0], scaling)]
    elif short in _ALIGNED or short in _UNALIGNED:
        if short in _ALIGNED:
            jt, axis = _ALIGNED[short]
            k = scene_k.get(int(jm.idx_q))
            if k is None:
                raise DetectionError(f"{where}: joint {name!r} (pin q[{jm.idx_q}]) is no joint of the scene's flat q")
            return jt, axis, 0.0, [(k[0], 1.0)]
        else:  # the axis as the motion subspace holds it (RevoluteUnboundedUnaligned does not expose .axis)
            S = np.asarray(pdata.joints[j].S, dtype=np.float64).ravel()
            jt = _UNALIGNED[short]
            axis, other = (S[3:], S[:3]) if jt == JT_REVOLUTE else (S[:3], S[3:])
            if np.any(other):
                raise DetectionError(f"{where}: joint {name!r} ({short}) has motion subspace {S.tolist()}, not a pure axis")
        k = scene_k.get(int(jm.idx_q))
        if k is None:
            raise DetectionError(f"{where}: joint {name!r} (pin q[{jm.idx_q}]) is no joint of the scene's flat q")
        offset, terms = 0.0, [(k[0], 1.0)]
    else:
        raise DetectionError(f"{where}: joint {name!r} is a Pinocchio {short}; the analytic engine expresses revolute, "
                             "prismatic, continuous, fixed and mimic joints")
    axis = np.asarray(axis, dtype=np.float64)
    n = float(np.linalg.norm(axis))
    if not n > 0.0:
        raise DetectionError(f"{where}: joint {name!r} has a zero axis")
    return jt, axis / n, offset, terms


def pin_tree(model, robot_names) -> tuple[FlatTree, np.ndarray, np.ndarray]:
    """``(tree, link_off, joint_off)`` of the robots ``robot_names`` (the scene's, in its order)
    from ``model.pin_model`` (see the module docstring); the layout of
    :func:`armguard.detect._common.combined_tree`: global link = ``link_off[r]`` + link index,
    joint terms index the scene's flat q."""
    if not robot_names:
        z = np.zeros(0, np.int64)
        return FlatTree(parent=z, X_pre=np.zeros((0, 4, 4)), axis=np.zeros((0, 3)), jtype=z.copy(), X_post=np.zeros((0, 4, 4)),
                        has_post=np.zeros(0, np.bool_), offset=np.zeros(0), term_start=np.zeros(1, np.int64),
                        term_joint=z.copy(), term_coeff=np.zeros(0)), z.copy(), z.copy()
    import pinocchio as pin

    pm = model.pin_model
    robots = model.robots  # the Robots pin_model moves (names, link order)
    where = f"model {model.name!r}"
    pdata = pm.createData()
    pin.forwardKinematics(pm, pdata, pin.neutral(pm))  # fills each joint's motion subspace S (mimic axes)
    scene_k = {}  # pin idx_q -> (scene flat k, continuous?)
    circular = set(int(k) for k in model._circular)
    for k, iq in enumerate(model.q_index):
        scene_k[int(iq)] = (k, k in circular)
    frames = list(pm.frames)  # one read of each vector (an element read through the bindings is slow)
    parents = [int(x) for x in pm.parents]
    joints = list(pm.joints)
    names = list(pm.names)
    placements = [_se3(x) for x in pm.jointPlacements]
    try:
        links_of_all = {int(model.link_frames[f"{r}/{ln}"]) for r, rb in robots.items() for ln in rb.link_names}
    except KeyError as exc:
        raise DetectionError(f"{where}: scene link {exc.args[0]!r} has no frame in pin_model (Model.link_frames)") from None
    rows = {k: [] for k in ("parent", "axis", "jtype", "offset", "term_start", "term_joint", "term_coeff")}
    F, first = [], []  # F[i]: link i in its joint's frame; first[i]: the first joint below its parent (-1: none)
    rows["term_start"].append(0)
    link_off, joint_off = [], []
    nl = nj = 0
    for r in robot_names:
        robot = robots[r]
        link_off.append(nl)
        joint_off.append(nj)
        fid = [int(model.link_frames[f"{r}/{ln}"]) for ln in robot.link_names]
        mine = {f: nl + i for i, f in enumerate(fid)}
        # each link in its BODY frame's joint frame: F = placement[f] X_FL
        F += [_se3(frames[f].placement) @ model.link_placement(f"{r}/{ln}") for f, ln in zip(fid, robot.link_names)]
        for i, f in enumerate(fid):
            wl = f"{where}, link {r}/{robot.link_names[i]}"
            # the parent link: up Pinocchio's frame tree (BODY -> its joint frame -> the BODY above)
            p, g = -1, f
            while True:
                jf = frames[g].parentFrame
                if jf == g or jf == 0:
                    break
                g = frames[jf].parentFrame
                if g in mine:
                    p = mine[g]
                    break
                if g in links_of_all:
                    raise DetectionError(f"{wl}: its parent {frames[g].name!r} is a link of another robot")
            if p >= nl + i:
                raise DetectionError(f"{wl}: its parent comes after it in the scene's link order")
            j_P = 0 if p < 0 else int(frames[fid[p - nl]].parentJoint)
            chain, j = [], int(frames[f].parentJoint)
            while j != j_P:
                if j == 0:
                    raise DetectionError(f"{wl}: its joint chain does not pass its parent link's joint")
                chain.append(j)
                j = parents[j]
            chain.reverse()
            offset, terms = 0.0, []
            if not chain:
                jt, axis = JT_FIXED, _E["X"]
            else:
                jt = axis = None
                for j in chain:
                    t, a, off, tm = _joint_motion(names[j], joints[j], pdata, j, scene_k, wl)
                    if jt is not None and (t != jt or not np.array_equal(a, axis) or not _is_identity(placements[j])):
                        raise DetectionError(f"{wl}: joints {[names[c] for c in chain]} move it as a chain that is not "
                                             "one motion (placements between them, or different axes or types)")
                    jt, axis = t, a
                    offset += off
                    terms += tm
            first.append(chain[0] if chain else -1)
            rows["parent"].append(p)
            rows["axis"].append(axis)
            rows["jtype"].append(jt)
            rows["offset"].append(offset)
            rows["term_joint"] += [k for k, _ in terms]
            rows["term_coeff"] += [c for _, c in terms]
            rows["term_start"].append(len(rows["term_joint"]))
        nl += len(fid)
        nj += len(robot.joint_names)

    def arr(k, shape, dt):
        return np.ascontiguousarray(np.asarray(rows[k], dtype=dt).reshape(shape))

    n = nl
    # the matrices, all links at once: F_P^-1 (identity for a root), then X_pre and X_post (module docstring)
    F = np.asarray(F, dtype=np.float64).reshape(n, 4, 4)
    parent = arr("parent", (n,), np.int64)
    first = np.asarray(first, dtype=np.int64)
    F_P = np.where((parent >= 0)[:, None, None], F[np.maximum(parent, 0)], _I4)
    iP = np.zeros((n, 4, 4))
    iP[:, :3, :3] = np.swapaxes(F_P[:, :3, :3], 1, 2)
    iP[:, :3, 3] = -np.einsum("nji,nj->ni", F_P[:, :3, :3], F_P[:, :3, 3])
    iP[:, 3, 3] = 1.0
    moves = (first >= 0)[:, None, None]
    J1 = np.asarray(placements, dtype=np.float64)[np.maximum(first, 0)] if n else np.zeros((0, 4, 4))
    X_pre = iP @ np.where(moves, J1, F)
    X_post = np.where(moves, F, _I4)
    has_post = ~np.all(X_post == _I4, axis=(1, 2))
    tree = FlatTree(parent=parent, X_pre=np.ascontiguousarray(X_pre),
                    axis=arr("axis", (n, 3), np.float64), jtype=arr("jtype", (n,), np.int64),
                    X_post=np.ascontiguousarray(X_post), has_post=np.ascontiguousarray(has_post),
                    offset=arr("offset", (n,), np.float64), term_start=arr("term_start", (n + 1,), np.int64),
                    term_joint=arr("term_joint", (-1,), np.int64), term_coeff=arr("term_coeff", (-1,), np.float64))
    return tree, np.asarray(link_off, dtype=np.int64), np.asarray(joint_off, dtype=np.int64)
