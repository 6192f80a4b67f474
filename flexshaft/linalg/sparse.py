"""The one sparse assembler: matrix entries collected in blocks, summed into CSR once.

Part models and the drivetrain both build their K, M and C here. Each block
of entries may carry an *owner* (a component's index), so that a quadratic
form such as a mode's strain energy φᵀKφ can be split exactly into the
shares of the components that put the entries there, without keeping one
matrix per component.

How the owners are kept (:class:`Entries`): one small integer per stored
entry of the summed matrix - the owner of everything summed there - and a
short side list for the few positions where several owners' entries add up
(the nodes where components meet), with each owner's own sum. The shares
then cost an owner array beside the matrix, not a second, unsummed copy of
it: a 1 M-element torsion chain keeps 3 MB of owners where a list of its
4 M unsummed entries took 128 MB.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

__all__ = ["Triplets", "Entries", "SHARED", "csr"]

#: Owner code of a stored entry summed from the entries of several owners (see Entries.shared_at).
SHARED = -2
#: Rows per block in :meth:`Entries.quadratic_by_owner`: its temporaries are a block's entries × modes.
ROWS_PER_BLOCK = 1 << 14


def _owner_dtype(largest: int) -> np.dtype:
    """The smallest signed integer type holding owners up to ``largest`` and the codes −1, −2."""
    for dtype in (np.int8, np.int16, np.int32):
        if largest <= np.iinfo(dtype).max:
            return np.dtype(dtype)
    return np.dtype(np.int64)


def _index_dtype(largest: int) -> np.dtype:
    """int32 for indices up to 2³¹ − 1 (what scipy.sparse picks itself), else int64."""
    return np.dtype(np.int32) if largest <= np.iinfo(np.int32).max else np.dtype(np.int64)


@dataclass(frozen=True)
class Entries:
    """A summed sparse matrix and who put each of its entries there.

    Attributes
    ----------
    matrix : scipy.sparse.csr_matrix, shape (n, n)
        The matrix, duplicates summed, column indices sorted in each row (in
        the units of what was assembled: N·m/rad, kg·m², ...). An assembled
        model's ``K`` is this very object, not a copy.
    owner : ndarray of int, shape (nnz,)
        For each stored entry (``matrix.data[p]``): the owner of all that was
        summed there (a component index, >= 0), −1 for nobody in particular,
        or :data:`SHARED` (−2) where several owners' entries add up.
    shared_at : ndarray of int, shape (s,)
        The side list, for the SHARED positions: the position ``p`` in
        ``matrix.data`` of each item (sorted; a position holds one item per
        owner summed there) ...
    shared_owner : ndarray of int, shape (s,)
        ... the owner (or −1) ...
    shared_data : ndarray, shape (s,)
        ... and the sum of that owner's entries there. At a SHARED position
        the items add up to ``matrix.data[p]`` up to round-off.
    """

    matrix: sp.csr_matrix
    owner: np.ndarray
    shared_at: np.ndarray
    shared_owner: np.ndarray
    shared_data: np.ndarray

    @property
    def shape(self) -> tuple[int, int]:
        """The matrix's shape."""
        return self.matrix.shape

    def _row_of_entries(self) -> np.ndarray:
        """Row of each stored entry, shape (nnz,)."""
        A = self.matrix
        return np.repeat(np.arange(A.shape[0], dtype=A.indices.dtype), np.diff(A.indptr))

    def quadratic_by_owner(self, V: np.ndarray, n_owners: int) -> np.ndarray:
        """Each owner's share of vᵀAv for every column v of ``V``, shape (n_owners, m).

        The shares add up to vᵀAv exactly (up to round-off): a stored entry
        counts for its owner, one at a SHARED position for each owner by that
        owner's own sum there. One share need not be positive where an
        owner's entries couple DOFs (a consistent mass), but an owner's whole
        block is, when it is positive semi-definite. Entries of nobody (−1)
        count for no one. Works over blocks of rows: the temporaries are a
        block's entries, whatever the size of the matrix.
        """
        V = np.asarray(V)
        m = V.shape[1]
        out = np.zeros((n_owners, m))
        if not np.any(self.owner >= 0) and not np.any(self.shared_owner >= 0):
            return out
        A = self.matrix
        # bincount wants non-negative bins: owner o goes to bin o + 2, nobody and SHARED to 1 and 0
        # (dropped): a SHARED entry counts through the side list instead.
        largest = max(int(self.owner.max(initial=-1)), int(self.shared_owner.max(initial=-1)))
        size = max(n_owners, largest + 1) + 2
        per = np.zeros((size, m))
        n = A.shape[0]
        for start in range(0, n, ROWS_PER_BLOCK):
            stop = min(start + ROWS_PER_BLOCK, n)
            a, b = int(A.indptr[start]), int(A.indptr[stop])
            if a == b:
                continue
            rows = np.repeat(np.arange(start, stop), np.diff(A.indptr[start : stop + 1]))
            cols = A.indices[a:b]
            bins = self.owner[a:b].astype(np.intp) + 2
            w = A.data[a:b, None] * V[rows] * V[cols]  # (entries of the block, m)
            for k in range(m):
                per[:, k] += np.bincount(bins, weights=w[:, k], minlength=size)
        if self.shared_at.size:
            rows = np.searchsorted(A.indptr, self.shared_at, side="right") - 1
            cols = A.indices[self.shared_at]
            w = self.shared_data[:, None] * V[rows] * V[cols]
            bins = self.shared_owner.astype(np.intp) + 2
            for k in range(m):
                per[:, k] += np.bincount(bins, weights=w[:, k], minlength=size)
        out[:] = per[2 : 2 + n_owners]
        return out

    def dominant_owner(self, row: int, col: int) -> int:
        """The owner with the largest ``|sum of its entries|`` at (row, col); −1 if none owns any there."""
        A = self.matrix
        lo, hi = int(A.indptr[row]), int(A.indptr[row + 1])
        hit = np.flatnonzero(A.indices[lo:hi] == col)
        if hit.size == 0:
            return -1
        p = lo + int(hit[0])
        who = int(self.owner[p])
        if who != SHARED:
            return who
        items = np.flatnonzero((self.shared_at == p) & (self.shared_owner >= 0))
        if items.size == 0:
            return -1
        return int(self.shared_owner[items[np.argmax(np.abs(self.shared_data[items]))]])

    def triplets(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The entries as COO triplets (rows, cols, data, owner), one per owner and position.

        Built on demand (O(nnz) memory): an entry for every stored entry owned
        by one owner (or nobody), and the side list's items in place of the
        SHARED ones. ``data`` summed by position gives ``matrix``.
        """
        A = self.matrix
        rows = self._row_of_entries()
        single = self.owner != SHARED
        return (
            np.concatenate([rows[single], rows[self.shared_at]]),
            np.concatenate([A.indices[single], A.indices[self.shared_at]]),
            np.concatenate([A.data[single], self.shared_data]),
            np.concatenate([self.owner[single], self.shared_owner]).astype(np.int64),
        )


def _owners(owner: np.ndarray, data: np.ndarray, first: np.ndarray, starts: np.ndarray):
    """The owner of each stored entry and the side list, from the sorted flat entries.

    ``first`` flags the flat entries that begin a stored entry's run,
    ``starts`` lists them. A run with one owner gives the stored entry that
    owner; one with several gives it SHARED, and each of its owners an item
    of the side list with the sum of its entries there.
    """
    own_first = owner[starts]
    # Runs with more than one owner: where the owner changes between two entries of the same run.
    change = np.flatnonzero(owner[1:] != owner[:-1]) + 1
    change = change[~first[change]]
    if change.size == 0:
        return own_first, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=owner.dtype), np.zeros(0)
    shared = np.unique(np.searchsorted(starts, change, side="right") - 1)
    own_first[shared] = SHARED
    # The flat entries of the shared runs (few: where components meet), summed per (position, owner).
    ends = np.append(starts[1:], owner.size)
    lengths = ends[shared] - starts[shared]
    first_of_run = np.repeat(starts[shared] - np.concatenate([[0], np.cumsum(lengths)[:-1]]), lengths)
    members = first_of_run + np.arange(int(lengths.sum()))
    pos, own, val = np.repeat(shared, lengths), owner[members], data[members]
    by = np.lexsort((own, pos))
    pos, own, val = pos[by], own[by], val[by]
    head = np.flatnonzero(np.concatenate([[True], (pos[1:] != pos[:-1]) | (own[1:] != own[:-1])]))
    with np.errstate(over="ignore"):  # as the stored entries' sums: inf is refused by the callers
        sums = np.add.reduceat(val, head)
    return own_first, pos[head].astype(np.int64), own[head], sums


class Triplets:
    """Entries of a square matrix in blocks, summed when it is built (one pass for all blocks).

    Blocks are kept as given, not copied or expanded to one (row, col) pair
    per entry until the matrix is built: the arrays passed in must not be
    changed before then.
    """

    def __init__(self) -> None:
        # ("coo", rows, cols, data, owner) with rows, cols, data 1-D; or ("elements", dofs (E, nb),
        # blocks (E, nb, nb), owner) with owner a scalar or one per element.
        self._blocks: list[tuple] = []

    @property
    def n_entries(self) -> int:
        """Number of entries collected so far (before summing)."""
        return sum(b[3].size if b[0] == "coo" else b[2].size for b in self._blocks)

    def add(self, rows, cols, data, owner: int = -1) -> None:
        """Entries (rows[i], cols[i]) += data[i]."""
        data = np.asarray(data, dtype=float).ravel()
        rows = np.asarray(rows, dtype=np.int64).ravel()
        cols = np.asarray(cols, dtype=np.int64).ravel()
        if not rows.size == cols.size == data.size:
            raise ValueError("rows, cols and data must have the same size")
        self._blocks.append(("coo", rows, cols, data, int(owner)))

    def add_dense(self, dofs, block, owner: int = -1) -> None:
        """A dense block on the DOFs ``dofs`` (rows and columns)."""
        dofs = np.asarray(dofs, dtype=np.int64).ravel()
        block = np.asarray(block, dtype=float).reshape(dofs.size, dofs.size)
        self._blocks.append(("elements", dofs[None, :], block[None], int(owner)))

    def add_sparse(self, A, offset: int = 0, owner: int = -1) -> None:
        """A sparse matrix whose DOF 0 is global DOF ``offset``."""
        c = sp.coo_matrix(A)
        self.add(c.row.astype(np.int64) + offset, c.col.astype(np.int64) + offset, c.data, owner)

    def add_elements(self, dofs: np.ndarray, blocks: np.ndarray, owner=-1) -> None:
        """Element blocks ``blocks[e]`` (n_el, nb, nb) on the DOFs ``dofs[e]`` (n_el, nb).

        ``owner`` is one owner for all elements or one per element.
        """
        dofs = np.asarray(dofs, dtype=np.int64)
        blocks = np.asarray(blocks, dtype=float)
        if blocks.shape != dofs.shape + dofs.shape[1:]:
            raise ValueError(f"blocks of shape {blocks.shape} for DOFs of shape {dofs.shape}")
        owner = np.asarray(owner, dtype=np.int64)
        self._blocks.append(("elements", dofs, blocks, int(owner) if owner.ndim == 0 else owner.ravel()))

    def _owner_dtype(self) -> np.dtype:
        """The owner type of these entries: big enough for the largest owner and the codes −1, −2."""
        largest = -1
        for block in self._blocks:
            own = block[4] if block[0] == "coo" else block[3]
            if np.size(own):
                largest = max(largest, int(np.max(own)))
        return _owner_dtype(largest)

    def _flat(self, n: int, index, scale, with_owner: bool):
        """Every entry as (row, col, value, owner), mapped, scaled and with dropped ones left out.

        One flat array each, filled block by block: the only full-length
        copies of the entries are these (rows and columns in the index type
        of the matrix, int32 below 2³¹; the owner in the smallest integer
        type that holds it).
        """
        total = self.n_entries
        idx = _index_dtype(max(n, total))
        rows = np.empty(total, dtype=idx)
        cols = np.empty(total, dtype=idx)
        data = np.empty(total)
        owner = np.empty(total, dtype=self._owner_dtype()) if with_owner else None
        at = 0
        for block in self._blocks:
            if block[0] == "coo":
                _, r, c, d, own = block
                if index is not None:
                    r, c = index[r], index[c]
                if scale is not None:
                    d = d * scale[block[1]] * scale[block[2]]
                if index is not None:
                    keep = (r >= 0) & (c >= 0)
                    if not keep.all():
                        r, c, d = r[keep], c[keep], d[keep]
                size = d.size
                rows[at : at + size] = r
                cols[at : at + size] = c
                data[at : at + size] = d
                if with_owner:
                    owner[at : at + size] = own
                at += size
                continue
            _, dofs, blocks, own = block
            nb = dofs.shape[1]
            mapped = dofs if index is None else index[dofs]
            if scale is not None:
                s = scale[dofs]
                blocks = blocks * s[:, :, None] * s[:, None, :]
            each = own if np.ndim(own) == 0 else np.repeat(own, nb * nb)
            if index is not None and np.any(mapped < 0):
                # A DOF mapped to −1 is not a coordinate: its rows and columns are dropped.
                i, j = np.repeat(np.arange(nb), nb), np.tile(np.arange(nb), nb)
                ok = (mapped[:, i] >= 0) & (mapped[:, j] >= 0)
                size = int(ok.sum())
                rows[at : at + size] = mapped[:, i][ok]
                cols[at : at + size] = mapped[:, j][ok]
                data[at : at + size] = np.broadcast_to(blocks, ok.shape[:1] + (nb, nb)).reshape(ok.shape)[ok]
                if with_owner:
                    owner[at : at + size] = each if np.ndim(each) == 0 else each[ok.ravel()]
            else:
                n_el = dofs.shape[0]
                size = n_el * nb * nb
                r_ = rows[at : at + size].reshape(n_el, nb, nb)
                c_ = cols[at : at + size].reshape(n_el, nb, nb)
                values = data[at : at + size].reshape(n_el, nb, nb)
                if n_el >= nb * nb:
                    # Many small blocks (a chain's elements): one pass per block entry (i, j) over all
                    # elements - long loops, where numpy's broadcasting over the small (nb, nb) inner
                    # shape runs ~5x slower. A block broadcast over the elements (a uniform shaft)
                    # is read as it is.
                    for i in range(nb):
                        for j in range(nb):
                            r_[:, i, j] = mapped[:, i]
                            c_[:, i, j] = mapped[:, j]
                            values[:, i, j] = blocks[:, i, j]
                else:  # a few large dense blocks (flexible bodies)
                    r_[...] = mapped[:, :, None]
                    c_[...] = mapped[:, None, :]
                    values[...] = blocks
                if with_owner:
                    owner[at : at + size] = each
            at += size
        return rows[:at], cols[:at], data[:at], (owner[:at] if with_owner else None)

    def _summed(self, n: int, index, scale, with_owner: bool):
        """The summed CSR matrix, and (with owners) the owner per stored entry and the side list.

        Arrays are let go as soon as they are used up: the building's peak is
        the flat entries (16 bytes and an owner each) and two arrays of the
        stored entries.
        """
        if index is not None:
            index = np.asarray(index, dtype=np.int64)
        if scale is not None:
            scale = np.asarray(scale, dtype=float)
        with np.errstate(over="ignore"):  # a product past double precision is inf, which callers refuse
            rows, cols, data, owner = self._flat(n, index, scale, with_owner)
        n_flat = data.size
        if n_flat == 0:
            empty = np.zeros(0, dtype=np.int8)
            return sp.csr_matrix((n, n)), empty, np.zeros(0, dtype=np.int64), empty, np.zeros(0)
        # Sort the entries by (row, column). A chain's element blocks come in order already (the
        # common case: a comparison pass, no sort); anything else takes a stable sort, which keeps
        # duplicates in the order they were added.
        same_row = rows[1:] == rows[:-1]
        if np.any(rows[1:] < rows[:-1]) or np.any(same_row & (cols[1:] < cols[:-1])):
            order = np.argsort(rows.astype(np.int64) * n + cols, kind="stable")
            rows, cols, data = rows[order], cols[order], data[order]
            if owner is not None:
                owner = owner[order]
            del order
            same_row = rows[1:] == rows[:-1]
        first = np.empty(n_flat, dtype=bool)  # where a stored entry's run of duplicates begins
        first[0] = True
        np.not_equal(cols[1:], cols[:-1], out=first[1:])
        first[1:] |= ~same_row
        del same_row
        starts = np.flatnonzero(first)
        side = None
        if owner is not None:
            side = _owners(owner, data, first, starts)
            del owner
        del first
        with np.errstate(over="ignore"):  # a sum past double precision is inf, which callers refuse
            summed = np.add.reduceat(data, starts)
        del data
        indices = cols[starts]
        del cols
        # Row i's stored entries begin where the (sorted) rows of the stored entries reach i.
        indptr = np.searchsorted(rows[starts], np.arange(n + 1, dtype=rows.dtype)).astype(indices.dtype)
        del rows, starts
        A = sp.csr_matrix((summed, indices, indptr), shape=(n, n))
        # Built sorted and summed: spare scipy its own checks and sorts later.
        A.has_sorted_indices = True
        A.has_canonical_format = True
        if side is None:
            return A, None, None, None, None
        return (A, *side)

    def entries(self, n: int, index=None, scale=None) -> Entries:
        """The n × n matrix with its owners, rows and columns mapped through ``index`` if given.

        Parameters
        ----------
        n : int
            Size of the matrix (after the mapping).
        index : ndarray of int, optional
            Row (and column) of each DOF; entries whose row or column maps to
            −1 are dropped (they must be zero: a DOF that is not a coordinate).
        scale : ndarray, optional
            Over the DOFs: entry (i, j) is multiplied by scale[i]·scale[j]
            before the mapping - the congruence Tᵀ A T with T a mapping whose
            entries are ``scale`` (a DOF tied to another by a fixed ratio, as
            a rigid gear mesh ties its wheels).

        Returns
        -------
        Entries
        """
        A, owner, at, who, val = self._summed(n, index, scale, with_owner=True)
        return Entries(A, owner, at, who, val)

    def build(self, n: int, index=None, scale=None) -> sp.csr_matrix:
        """The n × n CSR matrix, duplicates summed; ``index`` and ``scale`` as in :meth:`entries`."""
        return self._summed(n, index, scale, with_owner=False)[0]


def csr(entries: Entries, n: int) -> sp.csr_matrix:
    """The n × n summed matrix of ``entries`` (sorted indices): ``entries.matrix`` itself."""
    if entries.matrix.shape != (n, n):
        raise ValueError(f"entries of a {entries.matrix.shape} matrix, not ({n}, {n})")
    return entries.matrix
