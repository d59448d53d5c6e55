"""`Texts`: the texts of many waypoints made on demand, a block at a time (a long program's settings, no str each)."""

from collections.abc import Sequence

TEXT_BLOCK = 65536  # texts made at a time when `Texts` are iterated


class Texts(Sequence):
    """Non-empty texts of waypoints lo .. hi - 1 made on demand (a long program's settings without a str each).

    Parameters
    ----------
    make : callable
        ``make(lo, hi) -> list of str``: the texts of waypoints lo .. hi - 1,
        none empty.
    lo, hi : int
    """

    def __init__(self, make, lo, hi):
        self.make, self.lo, self.hi = make, lo, max(hi, lo)

    def __len__(self):
        return self.hi - self.lo

    def __getitem__(self, i):
        if isinstance(i, slice):
            start, stop, step = i.indices(len(self))
            if step != 1:
                return tuple(self)[i]
            return Texts(self.make, self.lo + start, self.lo + stop)
        i = i + len(self) if i < 0 else i
        if not 0 <= i < len(self):
            raise IndexError("text index out of range")
        return self.make(self.lo + i, self.lo + i + 1)[0]

    def __iter__(self):
        for lo in range(self.lo, self.hi, TEXT_BLOCK):
            yield from self.make(lo, min(lo + TEXT_BLOCK, self.hi))

    def __eq__(self, other):
        if not isinstance(other, (tuple, list, Texts)):
            return NotImplemented
        return len(self) == len(other) and all(a == b for a, b in zip(self, other))

    def __hash__(self):
        return hash(tuple(self))

    def __repr__(self):
        shown = "" if not len(self) else f": {self[0]!r}" if len(self) == 1 else f": {self[0]!r} .. {self[-1]!r}"
        return f"Texts({len(self)} texts{shown})"
