"""What a highway-env vehicle looks like in 3-D: its kind (class, mesh, size) and body colour.

highway-env simulates every vehicle as a 5 m × 2 m box. The scenario lists kinds with weights
and sizes, and a small colour palette; each vehicle draws one kind and one colour when it first
appears, from the source's seeded generator. A palette smaller than the number of vehicles makes
look-alike vehicles (same kind and colour) occur, as the benchmark needs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

RGB = tuple[float, float, float]


@dataclass(frozen=True)
class VehicleKind:
    """cls: semantic class ("car", "van", "bus", "truck"); shape: the renderer's mesh key;
    weight: relative frequency (> 0); size: (length, width, height) metres."""

    cls: str
    shape: str
    weight: float
    size: tuple[float, float, float]


@dataclass(frozen=True)
class Appearance:
    kind: VehicleKind
    color: RGB


class AppearanceSampler:
    """Draws (kind, colour) per new vehicle from ``rng``: kinds by weight, colours uniformly."""

    def __init__(
        self, kinds: tuple[VehicleKind, ...], palette: tuple[RGB, ...], rng: np.random.Generator
    ) -> None:
        if not kinds:
            raise ValueError("AppearanceSampler: at least one vehicle kind is needed")
        if not palette:
            raise ValueError("AppearanceSampler: the colour palette is empty")
        self.kinds = kinds
        self.palette = palette
        weights = np.array([k.weight for k in kinds], dtype=float)
        self._p = weights / weights.sum()
        self._rng = rng

    def draw(self) -> Appearance:
        kind = self.kinds[int(self._rng.choice(len(self.kinds), p=self._p))]
        color = self.palette[int(self._rng.integers(len(self.palette)))]
        return Appearance(kind=kind, color=color)
