"""The vectorisation convention every matcher in this package uses — defined here, once.

A candidate match (i, j) pairs object i of view 1 (0 <= i < n) with object j of view 2
(0 <= j < m). Its index in every relaxed assignment vector x, every affinity matrix and every
tensor index triple is

    a = i * m + j          (row-major vec of the n x m assignment matrix X; X = x.reshape(n, m))

This is the Duchenne/RRWHM/BCAGM layout. pygmtools/ThinkMatch use the transposed one
(a = j * n + i); convert with :func:`from_column_major` / :func:`to_column_major`.
"""

from __future__ import annotations

import numpy as np


def match_index(i: np.ndarray | int, j: np.ndarray | int, m: int) -> np.ndarray | int:
    """Index a of the candidate match (i, j) when view 2 has m objects."""
    return i * m + j


def match_nodes(a: np.ndarray | int, m: int) -> tuple[np.ndarray | int, np.ndarray | int]:
    """(i, j) of candidate match index a when view 2 has m objects."""
    return np.divmod(a, m)


def as_matrix(x: np.ndarray, n: int, m: int) -> np.ndarray:
    """The n x m matrix X of a relaxed assignment vector x (a view, not a copy)."""
    return np.asarray(x).reshape(n, m)


def to_column_major(matrix: np.ndarray, n: int, m: int) -> np.ndarray:
    """Re-index an (nm x nm) affinity matrix from our a = i*m + j to pygmtools' a = j*n + i."""
    perm = np.arange(n * m).reshape(n, m).T.reshape(-1)  # perm[a_col] = a_row
    return matrix[np.ix_(perm, perm)]


def from_column_major(matrix: np.ndarray, n: int, m: int) -> np.ndarray:
    """Re-index an (nm x nm) affinity matrix from pygmtools' a = j*n + i to our a = i*m + j."""
    perm = np.arange(n * m).reshape(m, n).T.reshape(-1)  # perm[a_row] = a_col
    return matrix[np.ix_(perm, perm)]


def conflict_mask(n: int, m: int) -> np.ndarray:
    """(nm, nm) bool: True where two candidate matches share a node of either view (incl. a == b)."""
    i, j = np.divmod(np.arange(n * m), m)
    return (i[:, None] == i[None, :]) | (j[:, None] == j[None, :])
