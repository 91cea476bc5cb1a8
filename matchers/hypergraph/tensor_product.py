"""The fused tensor-vector product of a :class:`~matchers.hypergraph.sparse_tensor.SparseTensor`.

Every iterative hypergraph matcher spends its time in one operation: for each stored triple
(a, b, c) with value h, add h * w(b, c) to slot a, h * w(a, c) to slot b and h * w(a, b) to
slot c, where w is x_b x_c (``slot_sums``) or y_b z_c + y_c z_b (``bilinear``). Written with
``np.bincount`` that is seven passes over 3N numbers (three gathers, four multiplies, the scatter).
Every path adds the 3N incidences to their slots in one fixed order, triple by triple (slots 0,
1, 2 of triple 0, then of triple 1, ...): the order a single pass over the triples visits them,
so that the compiled loop reads each triple once.

:class:`SlotLayout` does it in one pass: the 3N (slot, pair) incidences are sorted once by slot
(a stable counting sort, so each slot keeps the order in which ``bincount`` adds them) into
a CSR matrix of shape (nm, nm*nm) whose column is the pair index b*nm + c; the product is then
that matrix times the flattened outer product w (nm*nm numbers). scipy's CSR product adds each
row's terms in storage order, in the same order and with the same roundings as ``bincount`` —
the two are bit-identical (a test checks it), so switching between them never changes a result.

The outer product needs (nm)^2 doubles, so the CSR path is used only while that is at most
:data:`PAIR_LIMIT` (nm <= 2048); larger problems use the ``bincount`` passes. The sort costs about
five ``bincount`` products and each fused product saves about 0.8 of one, so it pays only for
long runs: a tensor sorts its layout on its :data:`FUSE_AFTER`-th product (maximin's ~10 steps,
MOS's and RRWHM's typical runs and BCAGM's restricted tensors never pay for it; RRWHM runs that
do not converge early do), or at once on
:meth:`~matchers.hypergraph.sparse_tensor.SparseTensor.prepare_products` (TM: 100 fixed iterations).

With numba (:mod:`matchers.core.jit`) the ``bincount`` passes are replaced by :func:`compiled_slot_sums`
and :func:`compiled_bilinear`: one compiled pass over the triples — the same products, added to
each slot in the same order, so again bit-identical — with no sort, no outer product and no
temporaries, on a uint16 copy of the slot indices. They are faster than the CSR
product, so with numba the layout is never sorted (``prepare_products`` does nothing).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from matchers.core.jit import njit

PAIR_LIMIT = 2048 * 2048  # largest (nm)^2 for which the outer product w is formed (32 MB)
FUSE_AFTER = 16  # products of an index pattern run as bincount passes before the layout is built


def index_dtype(size: int) -> type:
    """Smallest index dtype for match indices below ``size`` (int32 unless it does not fit)."""
    return np.int32 if size < 2**31 else np.int64


class SlotLayout:
    """The CSR incidence of a tensor's index pattern (shared by tensors that differ in values)."""

    def __init__(self, indices: np.ndarray, size: int):
        # indices: (N, 3) match indices; incidences in triple order (slots 0, 1, 2 of triple 0,
        # then of triple 1, ...), the order every product adds them in
        count = indices.shape[0]
        self.size = size
        self.count = count
        incidences = indices.reshape(-1)  # triple-major
        key = incidences.astype(np.uint16) if size <= 2**16 else incidences  # uint16: a radix sort
        dtype = index_dtype(max(size * size, 3 * count + 1))
        self.order = np.argsort(key, kind="stable").astype(dtype)
        ia, ib, ic = indices[:, 0], indices[:, 1], indices[:, 2]
        pairs = np.empty((count, 3), dtype=dtype)  # column b*nm + c of each incidence
        np.add(np.multiply(ib, size, dtype=dtype), ic, out=pairs[:, 0])
        np.add(np.multiply(ia, size, dtype=dtype), ic, out=pairs[:, 1])
        np.add(np.multiply(ia, size, dtype=dtype), ib, out=pairs[:, 2])
        self.columns = pairs.reshape(-1)[self.order]
        indptr = np.zeros(size + 1, dtype=dtype)
        np.cumsum(np.bincount(incidences, minlength=size), out=indptr[1:])
        self.indptr = indptr

    def matrix(self, values: np.ndarray) -> sp.csr_matrix:
        """The (nm, nm*nm) CSR matrix of these incidences with the triples' ``values``."""
        data = np.repeat(values, 3)[self.order]
        return sp.csr_matrix((data, self.columns, self.indptr), shape=(self.size, self.size**2))


def _slot_sums_kernel(slots: np.ndarray, values: np.ndarray, x: np.ndarray, size: int):
    # triple order: slot 0, 1, 2 of triple 0, then of triple 1, ...; weight (x x) * h
    count = values.shape[0]
    out = np.zeros(size)
    for i in range(count):
        a, b, c = slots[i], slots[count + i], slots[2 * count + i]
        h = values[i]
        xa, xb, xc = x[a], x[b], x[c]
        out[a] += (xb * xc) * h
        out[b] += (xa * xc) * h
        out[c] += (xa * xb) * h
    return out


def _bilinear_kernel(
    slots: np.ndarray, values: np.ndarray, y: np.ndarray, z: np.ndarray, size: int
):
    count = values.shape[0]
    out = np.zeros(size)
    for i in range(count):
        a, b, c = slots[i], slots[count + i], slots[2 * count + i]
        h = values[i]
        ya, yb, yc = y[a], y[b], y[c]
        za, zb, zc = z[a], z[b], z[c]
        out[a] += (yb * zc + yc * zb) * h
        out[b] += (ya * zc + yc * za) * h
        out[c] += (ya * zb + yb * za) * h
    return out


def _degrees_kernel(slots: np.ndarray, values: np.ndarray, size: int):
    # np.bincount(row-major indices, np.repeat(values, 3)): the three slots of each triple in turn
    count = values.shape[0]
    out = np.zeros(size)
    for i in range(count):
        h = values[i]
        out[slots[i]] += h
        out[slots[count + i]] += h
        out[slots[2 * count + i]] += h
    return out


def _min_weighted_kernel(slots: np.ndarray, values: np.ndarray, b: np.ndarray):
    # values * b[indices].min(axis=1)
    count = values.shape[0]
    out = np.empty(count)
    for i in range(count):
        low = min(b[slots[i]], b[slots[count + i]], b[slots[2 * count + i]])
        out[i] = values[i] * low
    return out


def _restricted_kernel(slots: np.ndarray, values: np.ndarray, mask: np.ndarray):
    # the triples with at least two of their three matches in mask, in order: (3, K) slot-major
    # match indices (the column-major layout SparseTensor keeps) and their (K,) values
    count = values.shape[0]
    kept = 0
    for i in range(count):
        if mask[slots[i]] + mask[slots[count + i]] + mask[slots[2 * count + i]] >= 2:
            kept += 1
    indices = np.empty((3, kept), dtype=np.intp)
    out = np.empty(kept)
    k = 0
    for i in range(count):
        if mask[slots[i]] + mask[slots[count + i]] + mask[slots[2 * count + i]] >= 2:
            for f in range(3):
                indices[f, k] = slots[f * count + i]
            out[k] = values[i]
            k += 1
    return indices, out


slot_sums_jit = njit(_slot_sums_kernel)
"""The compiled product (or None), for loops that call it from compiled code (TM's)."""
_restricted_jit = njit(_restricted_kernel)
_bilinear_jit = njit(_bilinear_kernel)
_degrees_jit = njit(_degrees_kernel)
_min_weighted_jit = njit(_min_weighted_kernel)
COMPILED = all(
    kernel is not None
    for kernel in (
        slot_sums_jit,
        _bilinear_jit,
        _degrees_jit,
        _min_weighted_jit,
        _restricted_jit,
    )
)


def compiled_slot_sums(slots: np.ndarray, values: np.ndarray, x: np.ndarray, size: int):
    """``SparseTensor.slot_sums`` from the concatenated (3N,) slot indices; needs numba
    (:data:`COMPILED`)."""
    return slot_sums_jit(slots, values, np.ascontiguousarray(x, dtype=np.float64), size)


def compiled_bilinear(
    slots: np.ndarray, values: np.ndarray, y: np.ndarray, z: np.ndarray, size: int
):
    """``SparseTensor.bilinear`` from the concatenated (3N,) slot indices; needs numba."""
    y = np.ascontiguousarray(y, dtype=np.float64)
    z = np.ascontiguousarray(z, dtype=np.float64)
    return _bilinear_jit(slots, values, y, z, size)


def compiled_degrees(slots: np.ndarray, values: np.ndarray, size: int):
    """``SparseTensor.degrees`` from the concatenated (3N,) slot indices; needs numba."""
    return _degrees_jit(slots, values, size)


def compiled_min_weighted(slots: np.ndarray, values: np.ndarray, b: np.ndarray):
    """``SparseTensor.min_weighted``: each value times the smallest of b over its triple's
    three matches; needs numba."""
    return _min_weighted_jit(slots, values, np.ascontiguousarray(b, dtype=np.float64))


def compiled_restricted(slots: np.ndarray, values: np.ndarray, mask: np.ndarray):
    """``SparseTensor.restricted``'s triples and values: ((3, K) slot-major match indices, (K,)
    values) of the triples with at least two matches in the bool ``mask``; needs numba."""
    return _restricted_jit(slots, values, np.ascontiguousarray(mask, dtype=np.uint8))
