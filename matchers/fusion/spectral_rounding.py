"""From a spectral embedding of every detection to one object per row, one detection per view.

Shared by :mod:`matchers.fusion.spectral` and :mod:`matchers.fusion.clear`: the rows of the k
eigenvectors are normalised, k cluster centres are picked among them (each the row least similar
to the centres already picked, starting from row 0: the pivoting of CLEAR, Fathian et al. 2020),
and each view's detections go to distinct centres by a linear assignment on their similarity
(Hungarian, scipy) — so no object holds two detections of one view. Similarities are rounded to
1e-9 first: eigenvectors of repeated eigenvalues differ between LAPACK builds by a rotation that
the row similarities do not see, and by last bits that the rounding removes.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from matchers.core.memory_budget import check_memory
from matchers.fusion.evidence import PairwiseEvidence
from matchers.fusion.universe import Universe, from_labels

DECIMALS = 9
DEGENERATE = 1e-8
"""Eigenvalues closer than this are one eigenvalue: an embedding never cuts through its space."""
EIGEN_DECIMALS = 8
"""Eigenvalues are rounded to this before they are counted against a threshold (an eigenvalue of
exactly 0.5, common in small graphs, must fall on the same side on every LAPACK build)."""


def object_count(inside: np.ndarray, evidence: PairwiseEvidence) -> int:
    """How many eigenvalues are on the objects' side (``inside``, bool per eigenvalue, decided on
    eigenvalues rounded to :data:`EIGEN_DECIMALS`), kept between the largest view (every
    detection of a view is a different object) and the total."""
    largest = max(evidence.sizes, default=0)
    return int(np.clip(np.count_nonzero(inside), largest, max(evidence.total, largest)))


def round_embedding(
    values: np.ndarray, vectors: np.ndarray, k: int, evidence: PairwiseEvidence
) -> np.ndarray:
    """Global-row labels of k objects from the eigenvectors ``vectors`` (D, D), columns ordered
    by ``values`` from the most relevant (module docstring). The embedding takes the first k
    columns and every further one whose eigenvalue equals the k-th (within
    :data:`DEGENERATE`): a basis of part of an eigenspace is arbitrary (LAPACK builds differ),
    the whole space's row similarities are not."""
    total = vectors.shape[0]
    if total == 0 or k == 0:
        return np.empty(0, dtype=np.int64)
    width = k + int(np.count_nonzero(np.abs(values[k:] - values[k - 1]) <= DEGENERATE))
    vectors = vectors[:, :width]
    norms = np.sqrt(np.sum(vectors * vectors, axis=1, keepdims=True))
    unit = np.divide(vectors, norms, out=np.zeros_like(vectors), where=norms > 0)
    similarity = np.round(unit @ unit.T, DECIMALS)  # (D, D), basis-free
    centres = [0]
    closest = similarity[0].copy()  # each row's similarity to its most similar centre
    for _ in range(1, k):
        closest[centres] = np.inf
        nxt = int(np.argmin(closest))  # first of the least similar rows
        centres.append(nxt)
        closest = np.maximum(closest, similarity[nxt])
    to_centre = similarity[:, centres]  # (D, k)
    labels = np.empty(total, dtype=np.int64)
    off = evidence.offsets
    for v in range(len(evidence.sizes)):
        rows = slice(off[v], off[v + 1])
        if off[v + 1] == off[v]:
            continue
        r, c = linear_sum_assignment(to_centre[rows], maximize=True)
        labels[off[v] + r] = c
    return labels


def memory_bytes(evidence: PairwiseEvidence) -> float:
    """Working memory of a dense spectral fusion: the (D, D) matrix, its eigenvectors, the
    similarities and LAPACK's workspace."""
    return 6.0 * 8.0 * float(evidence.total) ** 2


def check_dense(evidence: PairwiseEvidence, method: str) -> None:
    """Refuse (``ProblemTooLarge``) a dense fusion over the per-process memory budget."""
    check_memory(
        f"{method} fusion ({evidence.total} detections)",
        memory_bytes(evidence),
        "the number of views or detections",
    )


def fuse_spectrum(
    evidence: PairwiseEvidence,
    matrix: np.ndarray,
    largest: bool,
    threshold: float,
    method: str,
    started: float,
) -> Universe:
    """The universe from the spectrum of the symmetric (D, D) ``matrix``: objects are its
    eigenvalues above ``threshold`` (``largest``) or below it, the embedding their eigenvectors
    (:func:`object_count`, :func:`round_embedding`)."""
    if not evidence.total:
        return from_labels(evidence, np.empty(0, np.int64), method, started)
    values, vectors = np.linalg.eigh(matrix)  # ascending
    rounded = np.round(values, EIGEN_DECIMALS)
    k = object_count(rounded > threshold if largest else rounded < threshold, evidence)
    if largest:
        values, vectors = values[::-1], vectors[:, ::-1]
    return from_labels(evidence, round_embedding(values, vectors, k, evidence), method, started)
