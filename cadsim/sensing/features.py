"""Appearance feature vector of one detection: HOG | HSV colour histogram | attributes.

Layout (``FEATURE_LAYOUT``; width ``FEATURE_DIM`` is the same for every view and scenario):

- ``hog``: HOG (OpenCV's default layout, see ``hog_descriptor``) of the grey box crop resized to
  32x32 px (cells 8 px, blocks 16 px with stride 8, 9 orientation bins): 3x3 blocks x 4 cells x
  9 bins = 324 values.
- ``color``: 3-D HSV histogram of the object's visible pixels only (its instance mask inside the
  box), 12 hue x 4 saturation x 4 value bins = 192 values.
- ``attributes``: one-hot class over ``FEATURE_CLASSES`` (unknown classes -> "other") followed by
  the object's (length, width, height) / 10 m.

Each block is L2-normalised, all entries are non-negative, so the cosine similarity of two feature
vectors is the mean of the three blocks' cosines, in [0, 1].
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np

FEATURE_CLASSES: tuple[str, ...] = (
    "car",
    "van",
    "bus",
    "truck",
    "bicycle",
    "person",
    "traffic_light",
    "sign",
    "robot",
    "box",
    "cone",
    "other",
)
HOG_WINDOW_PX = 32
HSV_BINS = (12, 4, 4)
SIZE_SCALE_M = 10.0

_HOG_DIM = 324
_COLOR_DIM = int(np.prod(HSV_BINS))
_ATTR_DIM = len(FEATURE_CLASSES) + 3
FEATURE_LAYOUT: dict[str, slice] = {
    "hog": slice(0, _HOG_DIM),
    "color": slice(_HOG_DIM, _HOG_DIM + _COLOR_DIM),
    "attributes": slice(_HOG_DIM + _COLOR_DIM, _HOG_DIM + _COLOR_DIM + _ATTR_DIM),
}
FEATURE_DIM = _HOG_DIM + _COLOR_DIM + _ATTR_DIM

HOG_CELL_PX = 8
HOG_BINS = 9


def _l2(v: np.ndarray) -> np.ndarray:
    # the norm by numpy's own (pairwise, fixed-order) sum, not np.linalg.norm: that calls BLAS,
    # whose kernel (and so the float32 summation order) OpenBLAS picks by CPU model, which gave
    # other feature bits on an AVX-512 CPU (DESIGN §10: the same dataset on any CPU)
    v = np.maximum(np.asarray(v, dtype=np.float32).ravel(), 0.0)
    n = float(np.sqrt(np.sum(v * v)))
    return v / n if n > 0 else v


def hog_descriptor(gray: np.ndarray) -> np.ndarray:
    """Dalal-Triggs HOG of a square uint8 image whose side is a multiple of 8 px, in OpenCV's
    default layout: centred [-1, 0, 1] gradients, 8 px cells, 9 unsigned orientation bins (0-180°)
    with linear interpolation between neighbouring bins, 2x2-cell blocks with a one-cell stride,
    L2-Hys block normalisation (clip 0.2). (OpenCV 5 no longer ships cv2.HOGDescriptor.)"""
    g = gray.astype(np.float32)
    gx = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=1)
    gy = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=1)
    mag, ang = cv2.cartToPolar(gx, gy, angleInDegrees=True)
    pos = (ang % 180.0) / (180.0 / HOG_BINS) - 0.5  # bin centres at 10°, 30°, ...
    lo = np.floor(pos)
    w_hi = (pos - lo).ravel()
    b_lo = (lo.astype(np.int64) % HOG_BINS).ravel()
    b_hi = (b_lo + 1) % HOG_BINS
    n_cells = g.shape[0] // HOG_CELL_PX
    rows, cols = np.indices(g.shape)
    cell = ((rows // HOG_CELL_PX) * n_cells + cols // HOG_CELL_PX).ravel() * HOG_BINS
    m = mag.ravel().astype(np.float64)
    size = n_cells * n_cells * HOG_BINS
    hist = np.bincount(cell + b_lo, m * (1.0 - w_hi), minlength=size) + np.bincount(
        cell + b_hi, m * w_hi, minlength=size
    )
    hist = hist.reshape(n_cells, n_cells, HOG_BINS)
    # 2x2-cell blocks: (by, bx, bin, 2, 2) -> (by, bx, cell, bin) -> one row per block
    blocks = np.lib.stride_tricks.sliding_window_view(hist, (2, 2), axis=(0, 1))
    blocks = blocks.transpose(0, 1, 3, 4, 2).reshape(-1, 4 * HOG_BINS)
    eps = 1e-3
    blocks = blocks / np.sqrt((blocks**2).sum(axis=1, keepdims=True) + eps**2)
    blocks = np.minimum(blocks, 0.2)
    blocks = blocks / np.sqrt((blocks**2).sum(axis=1, keepdims=True) + eps**2)
    return blocks.ravel().astype(np.float32)


def hog_block(gray_crop: np.ndarray) -> np.ndarray:
    """(324,) L2-normalised HOG of a uint8 grey crop (any size, resized to 32x32)."""
    patch = cv2.resize(gray_crop, (HOG_WINDOW_PX, HOG_WINDOW_PX), interpolation=cv2.INTER_AREA)
    return _l2(hog_descriptor(patch))


def color_block(rgb_crop: np.ndarray, mask_crop: np.ndarray) -> np.ndarray:
    """(192,) L2-normalised HSV histogram of the uint8 RGB crop's pixels where ``mask_crop`` != 0."""
    hsv = cv2.cvtColor(rgb_crop, cv2.COLOR_RGB2HSV)
    hist = cv2.calcHist([hsv], [0, 1, 2], mask_crop, list(HSV_BINS), [0, 180, 0, 256, 0, 256])
    return _l2(hist)


def attribute_block(cls: str, size: Sequence[float]) -> np.ndarray:
    """(len(FEATURE_CLASSES) + 3,) L2-normalised one-hot class + size (metres / 10)."""
    v = np.zeros(_ATTR_DIM, dtype=np.float32)
    k = FEATURE_CLASSES.index(cls) if cls in FEATURE_CLASSES else FEATURE_CLASSES.index("other")
    v[k] = 1.0
    v[len(FEATURE_CLASSES) :] = np.maximum(np.asarray(size, dtype=np.float32), 0.0) / SIZE_SCALE_M
    return _l2(v)


def object_features(
    color: np.ndarray,
    box: tuple[int, int, int, int],
    mask_crop: np.ndarray,
    cls: str,
    size: Sequence[float],
) -> np.ndarray:
    """(FEATURE_DIM,) float32 feature of one object. color: (H, W, 3) uint8 RGB view; box: integer
    pixel box (x0, y0, x1, y1), x1/y1 exclusive; mask_crop: (y1-y0, x1-x0) uint8, non-zero on the
    object's visible pixels."""
    x0, y0, x1, y1 = box
    crop = np.ascontiguousarray(color[y0:y1, x0:x1])
    gray = cv2.cvtColor(crop, cv2.COLOR_RGB2GRAY)
    return np.concatenate(
        [hog_block(gray), color_block(crop, mask_crop), attribute_block(cls, size)]
    ).astype(np.float32)


def reported_sizes(features: np.ndarray) -> np.ndarray | None:
    """(k, 3) sizes (length, width, height, metres) the detector reported for k detections, read
    back from their attribute blocks (the inverse of :func:`attribute_block`: the size part over
    the one-hot entry, times ``SIZE_SCALE_M``); None when ``features`` (k, d) is not this
    module's layout (d ≠ ``FEATURE_DIM``) or a row has no class entry."""
    f = np.asarray(features, dtype=np.float64)
    if f.ndim != 2 or f.shape[1] != FEATURE_DIM:
        return None
    attributes = f[:, FEATURE_LAYOUT["attributes"]]
    one_hot = attributes[:, : len(FEATURE_CLASSES)].max(axis=1, initial=0.0)
    if (one_hot <= 0).any():
        return None
    return attributes[:, len(FEATURE_CLASSES) :] / one_hot[:, None] * SIZE_SCALE_M
