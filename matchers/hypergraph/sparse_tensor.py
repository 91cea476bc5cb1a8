"""Sparse super-symmetric third-order affinity tensor over the n*m candidate matches.

Storage: one row per unordered triple of distinct candidate matches, ``indices`` (N, 3) int64
(numpy's own index type: narrower indices would be converted on every gather and ``bincount``;
the fused product's CSR layout, read by compiled code, uses int32; match index a = i*m + j, see
:mod:`matchers.core.indexing`; rows are in increasing order a < b < c
unless the tensor was built with ``assume_unique``, where they are in the builder's order — no
operation depends on the order inside a row) and ``values`` (N,) > 0.
The tensor it stands for is super-symmetric: T[a, b, c] = value for all 6 permutations of a stored
triple; every other entry — including any with a repeated index — is 0. Memory is linear in N;
no dense (nm)^3 array is ever formed (except by :meth:`SparseTensor.dense`, for tests).
Products run as one fused pass (:mod:`matchers.hypergraph.tensor_product`), bit-identical to the
``np.bincount`` formulation they replace.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import permutations

import numpy as np

from matchers.hypergraph.tensor_product import (
    COMPILED,
    FUSE_AFTER,
    PAIR_LIMIT,
    SlotLayout,
    compiled_bilinear,
    compiled_degrees,
    compiled_min_weighted,
    compiled_restricted,
    compiled_slot_sums,
)


@dataclass(frozen=True, eq=False)
class SparseTensor:
    """Super-symmetric sparse tensor; build it with :meth:`from_entries` (or :meth:`empty`)."""

    indices: np.ndarray  # (N, 3) platform int, three distinct indices per row, no triple twice
    values: np.ndarray  # (N,) float
    n: int
    m: int
    info: dict | None = None
    # product plan shared by tensors with the same indices: {"layout": SlotLayout, "calls": int};
    # per tensor: the CSR matrix with its own values
    _plan: dict = field(default_factory=dict, repr=False, compare=False)
    _matrix: list = field(default_factory=list, repr=False, compare=False)

    @property
    def size(self) -> int:
        """Number of candidate matches n*m (the length of every vector the tensor acts on)."""
        return self.n * self.m

    @property
    def nnz(self) -> int:
        """Number of stored (unordered) triples."""
        return int(self.values.shape[0])

    @classmethod
    def empty(cls, n: int, m: int, info: dict | None = None) -> SparseTensor:
        return cls(np.zeros((0, 3), dtype=np.intp), np.zeros(0), n, m, info)

    @classmethod
    def from_entries(
        cls,
        indices: np.ndarray,
        values: np.ndarray,
        n: int,
        m: int,
        info: dict | None = None,
        assume_unique: bool = False,
    ) -> SparseTensor:
        """Canonicalise raw entries: sort each triple, drop triples with a repeated match index
        and non-positive or non-finite values, and de-duplicate — a triple found several times
        (by different sampled triangles or vertex orders) keeps its largest value. Raw entries
        need not be symmetric: each stands for its whole permutation class. ``assume_unique``
        skips the sorting and de-duplication (an O(N log N) sort) when the caller guarantees
        three distinct indices per row and no repeated triple; rows then keep their input order."""
        indices = np.asarray(indices).reshape(-1, 3)
        if indices.dtype.kind not in "iu":
            indices = indices.astype(np.int64)
        values = np.asarray(values, dtype=float).reshape(-1)
        if indices.shape[0] != values.shape[0]:
            raise ValueError(f"values: {values.shape[0]} values for {indices.shape[0]} triples")
        if assume_unique:  # caller guarantees valid, distinct indices per row, no triple twice
            if values.size and not (values.min() > 0 and np.isfinite(values.max())):
                keep = (values > 0) & np.isfinite(values)
                indices, values = indices[keep], values[keep]
            return cls(indices, values, n, m, info)
        size = n * m
        indices = indices.astype(np.int64, copy=False)
        if indices.size and (indices.min() < 0 or indices.max() >= size):
            raise ValueError(f"indices: match indices must lie in [0, {size})")
        indices = _sort_rows(indices)
        keep = (indices[:, 0] < indices[:, 1]) & (indices[:, 1] < indices[:, 2]) & (values > 0)
        keep &= np.isfinite(values)
        indices, values = indices[keep], values[keep]
        if not values.size:
            return cls.empty(n, m, info)
        if size**3 < 2**62:  # one int64 key per triple: a single argsort
            key = (indices[:, 0] * size + indices[:, 1]) * size + indices[:, 2]
            order = np.argsort(key, kind="stable")
            new = key[order][1:] != key[order][:-1]
        else:
            order = np.lexsort((indices[:, 2], indices[:, 1], indices[:, 0]))
            new = np.any(indices[order][1:] != indices[order][:-1], axis=1)
        starts = np.flatnonzero(np.concatenate(([True], new)))
        values = np.maximum.reduceat(values[order], starts)
        indices = indices[order[starts]]
        return cls(np.ascontiguousarray(indices), values, n, m, info)

    def with_values(self, values: np.ndarray) -> SparseTensor:
        """Same sparsity pattern, new values (e.g. re-weighted or normalised)."""
        values = np.asarray(values, dtype=float)
        if values.shape != self.values.shape:
            raise ValueError(f"values: expected shape {self.values.shape}, got {values.shape}")
        return SparseTensor(self.indices, values, self.n, self.m, self.info, self._plan)

    def __post_init__(self) -> None:
        # column-major layout: indices is the transpose of a C-contiguous (3, N) array, so the
        # three slots are contiguous (fast gathers) and their concatenation is a free reshape
        object.__setattr__(self, "indices", np.ascontiguousarray(self.indices.T, dtype=np.intp).T)
        object.__setattr__(self, "values", np.ascontiguousarray(self.values, dtype=np.float64))

    def prepare_products(self) -> None:
        """Sort the fused-product layout now (a caller about to run many products, like TM's
        100 fixed iterations); otherwise it is sorted on the :data:`FUSE_AFTER`-th product, or
        never when the products are compiled (:data:`~matchers.hypergraph.tensor_product.COMPILED`: the
        compiled loops on :attr:`compact_slots` are faster than the sorted layout)."""
        if not COMPILED:
            self._fused(now=True)

    def _fused(self, now: bool = False) -> object | None:
        """The CSR product matrix (:mod:`matchers.hypergraph.tensor_product`), or None while the bincount
        passes are cheaper: the layout is sorted on the FUSE_AFTER-th product of an index
        pattern (or on :meth:`prepare_products`), and only when the (nm)^2 outer product fits
        :data:`PAIR_LIMIT`."""
        if self._matrix:
            return self._matrix[0]
        if self.size * self.size > PAIR_LIMIT or not self.nnz:
            return None
        plan = self._plan
        if "layout" not in plan and COMPILED and not now:
            return None  # compiled products are faster than the sorted layout
        if "layout" not in plan:
            plan["calls"] = plan.get("calls", 0) + (0 if now else 1)
            if plan["calls"] < FUSE_AFTER and not now:
                return None
            plan["layout"] = SlotLayout(self.indices, self.size)
        self._matrix.append(plan["layout"].matrix(self.values))
        return self._matrix[0]

    @property
    def compact_slots(self) -> np.ndarray:
        """:attr:`_slots` as uint16 when every match index fits (nm <= 65536), for the compiled
        products: 6 instead of 24 index bytes per triple to stream (computed once per index
        pattern, shared with :meth:`with_values` copies)."""
        compact = self._plan.get("compact")
        if compact is None:
            slots = self._slots
            compact = slots.astype(np.uint16) if self.size <= 2**16 else slots
            self._plan["compact"] = compact
        return compact

    @property
    def _columns(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Slot 0, 1, 2 match indices as contiguous arrays."""
        by_slot = self.indices.T
        return by_slot[0], by_slot[1], by_slot[2]

    @property
    def _slots(self) -> np.ndarray:
        """Match index of slot 0, 1, 2 of every triple, concatenated: (3N,) (a view)."""
        return self.indices.T.reshape(-1)

    @property
    def _incidences(self) -> np.ndarray:
        """Match index of slot 0, 1, 2 of triple 0, then of triple 1, ...: (3N,) in the order
        every product adds them (a copy: :attr:`indices` is stored column-major)."""
        return self.indices.reshape(-1)

    def restricted(self, mask: np.ndarray) -> SparseTensor:
        """The triples with at least two of their three matches in ``mask`` (bool, length nm).

        ``bilinear(y, z)`` of the result equals that of the full tensor whenever y and z vanish
        outside ``mask`` — BCAGM's block updates use this to skip the entries that cannot
        contribute (its reference code keeps an (i, j)-pair index for the same purpose)."""
        if COMPILED:  # one pass, straight into the column-major layout
            by_slot, values = compiled_restricted(self.compact_slots, self.values, mask)
            return SparseTensor(by_slot.T, values, self.n, self.m, self.info)
        inside = np.asarray(mask, dtype=bool)[self.indices].sum(axis=1) >= 2
        return SparseTensor(self.indices[inside], self.values[inside], self.n, self.m, self.info)

    def symmetrised(self) -> tuple[np.ndarray, np.ndarray]:
        """All 6 permutations of every stored triple: ((6N, 3) indices, (6N,) values), sorted
        lexicographically — the layout BCAGM's reference code expects."""
        perms = np.concatenate([self.indices[:, list(p)] for p in permutations(range(3))])
        vals = np.tile(self.values, 6)
        order = np.lexsort((perms[:, 2], perms[:, 1], perms[:, 0]))
        return perms[order], vals[order]

    def bilinear(self, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        """out[a] = sum_{b,c} T[a, b, c] y[b] z[c]  (mode-1 product with y and z), length n*m."""
        if not self.nnz:
            return np.zeros(self.size)
        fused = self._fused()
        if fused is not None:
            pair = np.outer(y, z)
            pair += pair.T  # [b, c] = y_b z_c + y_c z_b, the same sum in the same order
            return fused @ pair.reshape(-1)
        if COMPILED:
            return compiled_bilinear(self.compact_slots, self.values, y, z, self.size)
        ia, ib, ic = self._columns
        ya, yb, yc = np.take(y, ia), np.take(y, ib), np.take(y, ic)
        za, zb, zc = np.take(z, ia), np.take(z, ib), np.take(z, ic)
        weights = np.empty((self.nnz, 3))
        weights[:, 0] = yb * zc + yc * zb
        weights[:, 1] = ya * zc + yc * za
        weights[:, 2] = ya * zb + yb * za
        weights *= self.values[:, None]
        return np.bincount(self._incidences, weights.reshape(-1), minlength=self.size)

    def product(self, x: np.ndarray) -> np.ndarray:
        """(T x_2 x x_3 x)[a] = sum_{b,c} T[a, b, c] x[b] x[c], length n*m (2x the 3-slot sum)."""
        return 2.0 * self.slot_sums(x)

    def slot_sums(self, x: np.ndarray) -> np.ndarray:
        """out[a] = sum over stored triples containing a of h * (product of the other two x's).

        This is the accumulation of the reference RRWHM/TM code on a list that stores each triple
        once; it is half of :meth:`product`."""
        if not self.nnz:
            return np.zeros(self.size)
        fused = self._fused()
        if fused is not None:
            return fused @ np.outer(x, x).reshape(-1)
        if COMPILED:
            return compiled_slot_sums(self.compact_slots, self.values, x, self.size)
        ia, ib, ic = self._columns
        xa, xb, xc = np.take(x, ia), np.take(x, ib), np.take(x, ic)
        weights = np.empty((self.nnz, 3))
        np.multiply(xb, xc, out=weights[:, 0])
        np.multiply(xa, xc, out=weights[:, 1])
        np.multiply(xa, xb, out=weights[:, 2])
        weights *= self.values[:, None]
        return np.bincount(self._incidences, weights.reshape(-1), minlength=self.size)

    def degrees(self) -> np.ndarray:
        """Stored-entry degree d[a] = sum of h over stored triples containing a (3-slot count);
        the full mode-1 row sum sum_{b,c} T[a, b, c] is 2 * d[a]."""
        if not self.nnz:
            return np.zeros(self.size)
        if COMPILED:
            return compiled_degrees(self.compact_slots, self.values, self.size)
        return np.bincount(self._incidences, np.repeat(self.values, 3), minlength=self.size)

    def min_weighted(self, b: np.ndarray) -> np.ndarray:
        """Each stored value times the smallest of ``b`` (length nm) over its triple's three
        matches: h * min(b_a, b_b, b_c) per stored triple (maximin's worst case, Eq. 5)."""
        if COMPILED and self.nnz:
            return compiled_min_weighted(self.compact_slots, self.values, b)
        return self.values * np.asarray(b, dtype=float)[self.indices].min(axis=1)

    def value(self, x: np.ndarray) -> float:
        """Objective sum_{a,b,c} T[a, b, c] x[a] x[b] x[c] (= 6 * sum h x_a x_b x_c)."""
        if not self.nnz:
            return 0.0
        ia, ib, ic = self._columns
        return float(6.0 * np.sum(self.values * np.take(x, ia) * np.take(x, ib) * np.take(x, ic)))

    def dense(self) -> np.ndarray:
        """The full (nm)^3 array — for tests on tiny problems only (refuses above 10^6 cells)."""
        if self.size**3 > 10**6:
            raise ValueError(f"dense: (nm)^3 = {self.size**3} cells is too large")
        out = np.zeros((self.size,) * 3)
        for p in permutations(range(3)):
            idx = self.indices[:, list(p)]
            out[idx[:, 0], idx[:, 1], idx[:, 2]] = self.values
        return out


def _sort_rows(triples: np.ndarray) -> np.ndarray:
    """Each row of an (N, 3) int array in increasing order (min/max network, no full sort)."""
    a, b, c = triples[:, 0], triples[:, 1], triples[:, 2]
    lo = np.minimum(np.minimum(a, b), c)
    hi = np.maximum(np.maximum(a, b), c)
    return np.stack([lo, a + b + c - lo - hi, hi], axis=1)
