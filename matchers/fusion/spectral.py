"""``spectral``: permutation synchronisation (Pachauri, Kondor & Singh, NIPS 2013)."""

from __future__ import annotations

import time

import numpy as np

from matchers.fusion.evidence import PairwiseEvidence
from matchers.fusion.spectral_rounding import check_dense, fuse_spectrum, memory_bytes
from matchers.fusion.universe import Universe

EIGENVALUE_FLOOR = 0.5
"""An eigenvalue of the association matrix above this counts as an object: a consistent
matching's are the objects' detection counts (>= 1) and 0."""


def association_matrix(evidence: PairwiseEvidence, weighted: bool) -> np.ndarray:
    """(D, D) symmetric: identity within each view, the declared matches between views (their
    scores when ``weighted``, else 1), 0 elsewhere."""
    a, b, score = evidence.edges()
    w = np.eye(evidence.total)
    values = score if weighted else np.ones_like(score)
    w[a, b] = values
    w[b, a] = values
    return w


def spectral(evidence: PairwiseEvidence, floor: float = EIGENVALUE_FLOOR) -> Universe:
    """Pachauri et al.'s synchronisation: the leading eigenvectors of the score-weighted
    association matrix W (identity blocks on the diagonal, each pair of views' declared matches
    weighted by their scores) embed every detection; W of a consistent matching is P P^T (P the
    detections-by-objects membership), so its eigenvalues are the objects' detection counts and
    0 — the number of objects is the count of eigenvalues above ``floor`` (0.5), between the
    largest view and the total. Partial views (not every object in every view) are rounded as in
    CLEAR (:mod:`matchers.fusion.spectral_rounding`). Consistent by construction."""
    started = time.perf_counter()
    check_dense(evidence, "spectral")
    if not floor > 0:
        raise ValueError(f"floor: expected a positive number, got {floor!r}")
    w = association_matrix(evidence, weighted=True)
    return fuse_spectrum(evidence, w, True, floor, "spectral", started)


spectral.deterministic = True
spectral.memory_bytes = memory_bytes
