"""The matching problem: two views of objects — positions, plus optional appearance features,
image positions (box centres in pixels) and a localisation prior (positions in a shared world
frame with their stated uncertainty)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def _as_array(name: str, value, ndim: int) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(
            f"{name}: expected a rectangular array of numbers, got {type(value).__name__} "
            "(ragged rows or non-numeric entries)"
        ) from None
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

    Optional, each pair given both or neither (matchers that do not use them ignore them):

    * pixels1: (n, 2), pixels2: (m, 2) — box centres in each view's image, in pixels (the
      ``pairwise="image"`` option of SM / RRWM / MOS).
    * world1: (n, 3), world2: (m, 3) — object positions in one shared world frame (metres;
      x, y horizontal, z up) as each agent's own noisy localisation (e.g. GPS pose) puts them:
      the localisation prior. world_sigma: its stated position uncertainty per view, metres
      (> 0; the standard deviation of one view's error along each horizontal axis). Requires
      world1/world2.
    * classes1: n strings, classes2: m strings — each detection's class label as its detector
      reports it (``"car"``, ``"label2"``); only equality between the views is meaningful.

    Validated on construction: NaN/inf or inconsistent shapes raise ``ValueError`` naming the array.

    >>> Problem(np.zeros((2, 3)), np.ones((1, 3)), world1=np.zeros((2, 3)),
    ...         world2=np.ones((1, 3)), world_sigma=1.2).world_sigma
    1.2
    """

    points1: np.ndarray
    points2: np.ndarray
    features1: np.ndarray | None = None
    features2: np.ndarray | None = None
    meta: dict = field(default_factory=dict, compare=False)
    pixels1: np.ndarray | None = None
    pixels2: np.ndarray | None = None
    world1: np.ndarray | None = None
    world2: np.ndarray | None = None
    world_sigma: float | None = None
    classes1: tuple[str, ...] | None = None
    classes2: tuple[str, ...] | None = None

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
        for first, second, width in (("pixels1", "pixels2", 2), ("world1", "world2", 3)):
            self._set_per_object(first, second, width)
        self._set_world_sigma()
        self._set_classes()

    def _set_classes(self) -> None:
        """Validate the optional class labels: both or neither, one string per detection."""
        if (self.classes1 is None) != (self.classes2 is None):
            raise ValueError("classes1/classes2: give both or neither")
        if self.classes1 is None:
            return
        for name, value, count in (
            ("classes1", self.classes1, self.n1),
            ("classes2", self.classes2, self.n2),
        ):
            if isinstance(value, str) or not all(isinstance(c, str) for c in value):
                raise ValueError(f"{name}: expected a sequence of class-name strings")
            labels = tuple(value)
            if len(labels) != count:
                raise ValueError(f"{name}: {len(labels)} labels for {count} points")
            object.__setattr__(self, name, labels)

    def _set_per_object(self, first: str, second: str, width: int) -> None:
        """Validate an optional pair of (n, width) / (m, width) per-object arrays."""
        a, b = getattr(self, first), getattr(self, second)
        if (a is None) != (b is None):
            raise ValueError(f"{first}/{second}: give both or neither")
        if a is None:
            return
        for name, value, count in ((first, a, self.n1), (second, b, self.n2)):
            arr = _as_array(name, value, 2)
            if count == 0 and arr.size == 0:
                arr = arr.reshape(0, width)
            if arr.shape != (count, width):
                raise ValueError(f"{name}: expected shape ({count}, {width}), got {arr.shape}")
            object.__setattr__(self, name, arr)

    def _set_world_sigma(self) -> None:
        if self.world_sigma is None:
            return
        if self.world1 is None:
            raise ValueError("world_sigma: given without world1/world2")
        value = self.world_sigma
        if isinstance(value, bool) or not isinstance(value, int | float | np.number):
            raise ValueError(f"world_sigma: expected a positive number of metres, got {value!r}")
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"world_sigma: expected a finite number > 0 (metres), got {value!r}")
        object.__setattr__(self, "world_sigma", float(value))

    @property
    def n1(self) -> int:
        return int(self.points1.shape[0])

    @property
    def n2(self) -> int:
        return int(self.points2.shape[0])

    @property
    def dim(self) -> int:
        return int(self.points1.shape[1])
