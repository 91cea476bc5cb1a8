"""The matching problem: two views of objects, positions plus optional appearance features."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def _as_array(name: str, value, ndim: int) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 1 and arr.size == 0:
        arr = arr.reshape(0, 0)
    if arr.ndim != ndim:
        raise ValueError(f"{name}: expected a {ndim}-D array, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: contains NaN or inf")
    return arr


@dataclass(frozen=True)
class Problem:
    """Two views to match.

    points1: (n, D) object positions in view 1 (D = 2 or 3; metres in the observer's own frame
    for CoID data, any unit for synthetic/landmark data). points2: (m, D), same D.
    features1: (n, d) and features2: (m, d) appearance features, or None for uniform appearance.
    Validated on construction: NaN/inf or inconsistent shapes raise ``ValueError`` naming the array.
    """

    points1: np.ndarray
    points2: np.ndarray
    features1: np.ndarray | None = None
    features2: np.ndarray | None = None
    meta: dict = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        p1 = _as_array("points1", self.points1, 2)
        p2 = _as_array("points2", self.points2, 2)
        d1 = p1.shape[1] if p1.shape[0] else None
        d2 = p2.shape[1] if p2.shape[0] else None
        dims = {d for d in (d1, d2) if d is not None}
        if len(dims) > 1:
            raise ValueError(f"points2: dimension {d2} differs from points1's {d1}")
        if dims and not dims <= {2, 3}:
            raise ValueError(f"points1/points2: positions must be 2-D or 3-D, got D={dims.pop()}")
        dim = dims.pop() if dims else 3
        p1 = p1.reshape(p1.shape[0], dim) if p1.shape[0] == 0 else p1
        p2 = p2.reshape(p2.shape[0], dim) if p2.shape[0] == 0 else p2
        object.__setattr__(self, "points1", p1)
        object.__setattr__(self, "points2", p2)
        if (self.features1 is None) != (self.features2 is None):
            raise ValueError("features1/features2: give both or neither")
        if self.features1 is not None:
            f1 = _as_array("features1", self.features1, 2) if len(p1) else np.zeros((0, 0))
            f2 = _as_array("features2", self.features2, 2) if len(p2) else np.zeros((0, 0))
            if len(p1) and f1.shape[0] != p1.shape[0]:
                raise ValueError(f"features1: {f1.shape[0]} rows for {p1.shape[0]} points")
            if len(p2) and f2.shape[0] != p2.shape[0]:
                raise ValueError(f"features2: {f2.shape[0]} rows for {p2.shape[0]} points")
            if len(p1) and len(p2) and f1.shape[1] != f2.shape[1]:
                raise ValueError(
                    f"features2: width {f2.shape[1]} differs from features1's {f1.shape[1]}"
                )
            object.__setattr__(self, "features1", f1)
            object.__setattr__(self, "features2", f2)

    @property
    def n1(self) -> int:
        return int(self.points1.shape[0])

    @property
    def n2(self) -> int:
        return int(self.points2.shape[0])

    @property
    def dim(self) -> int:
        return int(self.points1.shape[1])
