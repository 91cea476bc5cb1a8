"""``clear``: CLEAR (Fathian, Khosoussi, Tian, Lusk & How, IEEE T-RO 2020)."""

from __future__ import annotations

import time

import numpy as np

from matchers.fusion.evidence import PairwiseEvidence
from matchers.fusion.spectral import association_matrix
from matchers.fusion.spectral_rounding import check_dense, fuse_spectrum, memory_bytes
from matchers.fusion.universe import Universe

EIGENVALUE_CEILING = 0.5
"""An eigenvalue of the normalised Laplacian below this counts as an object: a consistent
matching's graph is one clique per object, whose normalised spectrum is 0 once and 1 otherwise."""


def clear(evidence: PairwiseEvidence, ceiling: float = EIGENVALUE_CEILING) -> Universe:
    """CLEAR's consistent lifting: the association graph of the declared matches (unweighted),
    its Laplacian L = D - A normalised by the degrees plus one, (D + I)^-1/2 L (D + I)^-1/2; the
    number of objects is the count of its eigenvalues below ``ceiling`` (0.5; between the largest
    view and the total), the eigenvectors of those smallest eigenvalues embed every detection,
    and the embedding is rounded by pivot rows and one assignment per view
    (:mod:`matchers.fusion.spectral_rounding`). Consistent by construction."""
    started = time.perf_counter()
    check_dense(evidence, "clear")
    if not ceiling > 0:
        raise ValueError(f"ceiling: expected a positive number, got {ceiling!r}")
    adjacency = association_matrix(evidence, weighted=False) - np.eye(evidence.total)
    degree = adjacency.sum(axis=1)
    scale = 1.0 / np.sqrt(degree + 1.0)
    laplacian = (np.diag(degree) - adjacency) * scale[:, None] * scale[None, :]
    return fuse_spectrum(evidence, laplacian, False, ceiling, "clear", started)


clear.deterministic = True
clear.memory_bytes = memory_bytes
