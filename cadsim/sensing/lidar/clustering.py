"""Clustering of non-ground LiDAR points into objects: connected components on a bird's-eye grid.

Points are binned into square cells of ``cell_m`` on the ground plane (LiDAR frame x, y,
metres); occupied cells are dilated by one cell (so gaps up to ≈ 2 cells are bridged — the
spacing of neighbouring rays at 80 m) and labelled by 8-connectivity (``scipy.ndimage.label``);
each point takes its cell's label. A component with fewer than ``min_points`` points is noise.
This is single-linkage clustering with a fixed link distance, as DBSCAN with a core size of one
would give, at the cost of one image labelling — no pairwise neighbour search over the cloud.
Labels are numbered by first appearance in raster order of the grid (deterministic). Objects
closer than the link distance merge; one seen through a gap splits: both are left as they come.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

CELL_M = 0.2
MIN_POINTS = 10
MAX_GRID_CELLS = 16_000_000  # 800 m × 800 m at 0.2 m


def cluster_points(points: np.ndarray, cell_m: float = CELL_M, min_points: int = MIN_POINTS) -> np.ndarray:  # fmt: skip
    """(n,) int64 cluster of each point of ``points`` (n, 3) metres, 0 … k−1, or −1 (noise)."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    labels = np.full(len(p), -1, dtype=np.int64)
    if len(p) == 0:
        return labels
    cell = np.floor(p[:, :2] / cell_m).astype(np.int64)
    lo = cell.min(axis=0) - 1
    cell -= lo
    shape = tuple(int(v) + 2 for v in cell.max(axis=0))
    if shape[0] * shape[1] > MAX_GRID_CELLS:
        raise ValueError(f"points: cloud spans {shape[0] * shape[1]} grid cells, more than {MAX_GRID_CELLS}")  # fmt: skip
    occupied = np.zeros(shape, dtype=bool)
    occupied[cell[:, 0], cell[:, 1]] = True
    grown = ndimage.binary_dilation(occupied, structure=np.ones((3, 3), dtype=bool))
    grid, count = ndimage.label(grown, structure=np.ones((3, 3), dtype=bool))
    raw = grid[cell[:, 0], cell[:, 1]] - 1  # 0 … count−1
    sizes = np.bincount(raw, minlength=count)
    kept = sizes >= min_points
    renumber = np.full(count, -1, dtype=np.int64)
    renumber[kept] = np.arange(int(kept.sum()))
    labels[:] = renumber[raw]
    return labels
