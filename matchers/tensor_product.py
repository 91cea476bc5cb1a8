"""The fused tensor-vector product of a :class:`~matchers.sparse_tensor.SparseTensor`.

Every iterative hypergraph matcher spends its time in one operation: for each stored triple
(a, b, c) with value h, add h * w(b, c) to slot a, h * w(a, c) to slot b and h * w(a, b) to
slot c, where w is x_b x_c (``slot_sums``) or y_b z_c + y_c z_b (``bilinear``). Written with
``np.bincount`` that is seven passes over 3N numbers (three gathers, four multiplies, the scatter).

:class:`SlotLayout` does it in one pass: the 3N (slot, pair) incidences are sorted once by slot
(a stable counting sort, so each slot keeps the order in which ``bincount`` would add them) into
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
:meth:`~matchers.sparse_tensor.SparseTensor.prepare_products` (TM: 100 fixed iterations).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

PAIR_LIMIT = 2048 * 2048  # largest (nm)^2 for which the outer product w is formed (32 MB)
FUSE_AFTER = 16  # products of an index pattern run as bincount passes before the layout is built


def index_dtype(size: int) -> type:
    """Smallest index dtype for match indices below ``size`` (int32 unless it does not fit)."""
    return np.int32 if size < 2**31 else np.int64


class SlotLayout:
    """The CSR incidence of a tensor's index pattern (shared by tensors that differ in values)."""

    def __init__(self, slots: np.ndarray, count: int, size: int):
        # slots: (3N,) slot 0, 1, 2 match indices of the N triples, concatenated
        self.size = size
        self.count = count
        key = slots.astype(np.uint16) if size <= 2**16 else slots  # uint16: a radix sort
        dtype = index_dtype(max(size * size, 3 * count + 1))
        self.order = np.argsort(key, kind="stable").astype(dtype)
        ia, ib, ic = slots[:count], slots[count : 2 * count], slots[2 * count :]
        pairs = np.empty(3 * count, dtype=dtype)  # column b*nm + c of each incidence
        np.add(np.multiply(ib, size, dtype=dtype), ic, out=pairs[:count])
        np.add(np.multiply(ia, size, dtype=dtype), ic, out=pairs[count : 2 * count])
        np.add(np.multiply(ia, size, dtype=dtype), ib, out=pairs[2 * count :])
        self.columns = pairs[self.order]
        indptr = np.zeros(size + 1, dtype=dtype)
        np.cumsum(np.bincount(slots, minlength=size), out=indptr[1:])
        self.indptr = indptr

    def matrix(self, values: np.ndarray) -> sp.csr_matrix:
        """The (nm, nm*nm) CSR matrix of these incidences with the triples' ``values``."""
        data = np.concatenate([values, values, values])[self.order]
        return sp.csr_matrix((data, self.columns, self.indptr), shape=(self.size, self.size**2))
