"""The result of a pairwise proximity query."""

from __future__ import annotations

import numpy as np

__all__ = ["Proximity", "proximity_from_buffer"]


class Proximity:
    """Signed distance between shapes A and B with witness points.

    Invariants (tested):

    * ``distance > 0`` separated, ``== 0`` touching, ``< 0`` penetrating (``-distance`` is the
      penetration depth, the shortest translation of one shape that separates them);
    * ``p_WA`` lies on the surface of A and ``p_WB`` on the surface of B (W, m);
    * ``|p_WA - p_WB| == |distance|`` to 1e-9 m;
    * ``p_WB - p_WA == distance * nhat_AB_W`` — ``nhat_AB_W`` is the unit direction in which
      moving B away from A increases the distance (from A to B when separated);
    * swapping A and B swaps the points and negates ``nhat_AB_W``.

    Immutable; attributes are read-only arrays.  ``nhat_AB_W`` is arbitrary (but unit) when
    the cores touch exactly and no direction is defined.
    """

    __slots__ = ("_d", "_buf")

    def __init__(self, distance: float, p_WA, p_WB, nhat_AB_W) -> None:
        buf = np.empty(9, dtype=np.float64)
        buf[0:3] = p_WA
        buf[3:6] = p_WB
        buf[6:9] = nhat_AB_W
        buf.flags.writeable = False
        self._d = float(distance)
        self._buf = buf

    def _view(self, lo: int, hi: int) -> np.ndarray:
        buf = self._buf
        if buf.flags.writeable:
            buf.setflags(write=False)
        return buf[lo:hi]

    @property
    def distance(self) -> float:
        """Signed distance (m)."""
        return self._d

    @property
    def p_WA(self) -> np.ndarray:
        """``(3,) float64, m``: witness point on A's surface, in W."""
        return self._view(0, 3)

    @property
    def p_WB(self) -> np.ndarray:
        """``(3,) float64, m``: witness point on B's surface, in W."""
        return self._view(3, 6)

    @property
    def nhat_AB_W(self) -> np.ndarray:
        """``(3,) float64``: unit normal with ``p_WB - p_WA == distance * nhat_AB_W``."""
        return self._view(6, 9)

    @property
    def penetration_depth(self) -> float:
        """``max(0, -distance)`` (m)."""
        return max(0.0, -self._d)

    def swapped(self) -> "Proximity":
        """The same result with A and B exchanged."""
        return Proximity(self._d, self.p_WB, self.p_WA, -self.nhat_AB_W)

    def __setattr__(self, name, value):  # immutability after construction
        if hasattr(self, "_buf") and name in self.__slots__:
            raise AttributeError("Proximity is immutable")
        object.__setattr__(self, name, value)

    def __repr__(self) -> str:
        a = np.array2string(self.p_WA, precision=6)
        b = np.array2string(self.p_WB, precision=6)
        return f"Proximity(distance={self._d:.9g}, p_WA={a}, p_WB={b})"


_new = object.__new__
_set_d = Proximity._d.__set__  # the slots' own setters: bypass the immutability guard once
_set_buf = Proximity._buf.__set__


def proximity_from_buffer(distance: float, buf: np.ndarray) -> Proximity:
    """A :class:`Proximity` wrapping a kernel's ``(9,)`` output without copying (the single-call
    fast path: ``distance`` is already a Python float from the compiled kernel).  ``buf`` is
    made read-only on first access (see ``_view``): setting the flag costs as much as the whole
    query, and nothing else holds a reference to it."""
    obj = _new(Proximity)
    _set_d(obj, distance)
    _set_buf(obj, buf)
    return obj
