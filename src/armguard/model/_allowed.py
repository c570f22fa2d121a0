"""Which owner pairs a scene checks (:meth:`armguard.model.Scene.allowed_pairs`): its pair filters
applied to its robots' links, bodies and payloads."""

from __future__ import annotations

from ._items import CheckPair, PairCategory

__all__ = ["adjacent", "allowed_pairs"]


def allowed_pairs(scene) -> tuple[CheckPair, ...]:
    """:meth:`armguard.model.Scene.allowed_pairs` of ``scene`` (the caller holds its lock)."""
    links = []  # (robot, link, owner)
    for r, robot in scene._robots.items():
        links.extend((r, ln, f"{r}/{ln}") for ln in robot.link_names if robot.link_shapes.get(ln))
    out: list[CheckPair] = []

    def disabled(a: str, b: str, ra: str | None, rb: str | None) -> bool:
        for x in (a, ra):
            for y in (b, rb):
                if x is not None and y is not None and frozenset((x, y)) in scene._disabled:
                    return True
        return False

    for i in range(len(links)):
        ra, la, a = links[i]
        for j in range(i + 1, len(links)):
            rb, lb, b = links[j]
            if ra == rb:
                key = (la, lb) if la < lb else (lb, la)
                listed = scene._self_pairs.get(ra)
                if listed is not None:
                    if key not in listed:
                        continue
                elif scene._exclude_adjacent and adjacent(scene, ra, la, lb):
                    continue
            if not disabled(a, b, ra, rb):
                out.append(CheckPair(a, b, PairCategory.ARM_ARM))
    for r, _, a in links:
        for body in scene._bodies.values():
            cat = PairCategory.ARM_VEHICLE if body.category == "vehicle" else PairCategory.ARM_ENVIRONMENT
            if not disabled(a, body.name, r, None):
                out.append(CheckPair(a, body.name, cat))
    for r, _, a in links:
        for p in scene._payloads.values():
            if p.owner_link != a and not disabled(a, p.name, r, None):
                out.append(CheckPair(a, p.name, PairCategory.ARM_PAYLOAD))
    plist = list(scene._payloads.values())
    for p in plist:
        for body in scene._bodies.values():
            cat = PairCategory.PAYLOAD_VEHICLE if body.category == "vehicle" else PairCategory.PAYLOAD_ENVIRONMENT
            if not disabled(p.name, body.name, None, None):
                out.append(CheckPair(p.name, body.name, cat))
    for i in range(len(plist)):
        for j in range(i + 1, len(plist)):
            if not disabled(plist[i].name, plist[j].name, None, None):
                out.append(CheckPair(plist[i].name, plist[j].name, PairCategory.PAYLOAD_PAYLOAD))
    return tuple(out)


def adjacent(scene, robot: str, a: str, b: str) -> bool:
    """Whether links ``a`` and ``b`` are joined by one joint, or by a chain of joints whose
    intermediate links have no geometry (a zero-length link between two capsules, as in
    Ranger's and HERA's wrists: their shapes always touch at the shared joint)."""
    r = scene._robots[robot]
    key = (a, b) if a < b else (b, a)
    if key in r.adjacent_pairs:
        return True

    def shaped_ancestor(ln: str) -> str | None:
        p = r.parent_link(ln)
        while p is not None and not r.link_shapes.get(p):
            p = r.parent_link(p)
        return p

    return shaped_ancestor(a) == b or shaped_ancestor(b) == a
