"""What the renderer returns for one camera: colour, exact depth and the instance map."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class RenderedView:
    """One rendered view, all arrays (H, W) in image layout (row = v, column = u).

    color: (H, W, 3) uint8 RGB. depth: (H, W) float32, metres along the optical axis (z of the
    OpenCV camera frame), 0 where no surface was hit; exact (no multisampling). instance: (H, W)
    int32 index into ``snapshot.objects`` of the visible surface, -1 for background (sky, and the
    renderer's own ground plane).
    """

    color: np.ndarray
    depth: np.ndarray
    instance: np.ndarray

    def __post_init__(self) -> None:
        if self.color.ndim != 3 or self.color.shape[2] != 3 or self.color.dtype != np.uint8:
            raise ValueError(
                f"RenderedView.color must be (H, W, 3) uint8, got {self.color.shape} {self.color.dtype}"
            )
        hw = self.color.shape[:2]
        if self.depth.shape != hw:
            raise ValueError(f"RenderedView.depth must be {hw}, got {self.depth.shape}")
        if self.instance.shape != hw:
            raise ValueError(f"RenderedView.instance must be {hw}, got {self.instance.shape}")
        self.depth = np.asarray(self.depth, dtype=np.float32)
        self.instance = np.asarray(self.instance, dtype=np.int32)

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W) in pixels."""
        return self.color.shape[:2]
