"""A robot's recorded trajectory: its sampled (time, x, y), kept compact.

A list of ``(t, x, y)`` tuples of floats costs ~136 bytes a sample; a 1,000-robot
mission sampled at 2 Hz for 1,800 s holds 3.6 million samples, ~490 MB. A
:class:`Trajectory` keeps them as one flat array of doubles (24 bytes a sample, the same
values bit for bit) and reads as the sequence of tuples it replaces.
"""

from __future__ import annotations

from array import array
from collections.abc import Iterable, Iterator, Sequence
from typing import overload

Sample = tuple[float, float, float]


class Trajectory(Sequence[Sample]):
    """Samples ``(t, x, y)`` in the order they were taken."""

    __slots__ = ("_values",)

    def __init__(self, samples: Iterable[Sample] = ()) -> None:
        self._values = array("d")
        for sample in samples:
            self.append(sample)

    def append(self, sample: Sample) -> None:
        t, x, y = sample
        self._values.extend((t, x, y))

    def __len__(self) -> int:
        return len(self._values) // 3

    @overload
    def __getitem__(self, index: int) -> Sample: ...

    @overload
    def __getitem__(self, index: slice) -> list[Sample]: ...

    def __getitem__(self, index: int | slice) -> Sample | list[Sample]:
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(len(self)))]
        n = len(self)
        i = index + n if index < 0 else index
        if not 0 <= i < n:
            raise IndexError("trajectory index out of range")
        v = self._values
        return v[3 * i], v[3 * i + 1], v[3 * i + 2]

    def __iter__(self) -> Iterator[Sample]:
        values = iter(self._values)
        return zip(values, values, values, strict=True)

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Trajectory):
            return self._values == other._values
        if isinstance(other, Sequence):
            return list(self) == list(other)
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]  # mutable, as the list it replaces

    def __repr__(self) -> str:
        return f"Trajectory({list(self)!r})"
