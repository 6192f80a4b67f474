"""The one sparse assembler: matrix entries collected as triplets, summed into CSR once.

Part models and the drivetrain both build their K, M and C here. Each entry
may carry an *owner* (a component's index), so that a quadratic form such as
a mode's strain energy φᵀKφ can be split exactly into the shares of the
components that put the entries there, without keeping one matrix per
component.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

__all__ = ["Triplets", "Entries"]


@dataclass(frozen=True)
class Entries:
    """Summed-later matrix entries with their owners (plain arrays).

    Attributes
    ----------
    rows, cols : ndarray of int
        Row and column of each entry.
    data : ndarray of float
        Its value (duplicates add up).
    owner : ndarray of int
        Who put it there (a component index, >= 0; −1: nobody in particular),
        for :meth:`quadratic_by_owner`.
    """

    rows: np.ndarray
    cols: np.ndarray
    data: np.ndarray
    owner: np.ndarray

    def quadratic_by_owner(self, V: np.ndarray, n_owners: int) -> np.ndarray:
        """Each owner's share of vᵀAv for every column v of ``V``, shape (n_owners, m).

        The shares add up to vᵀAv exactly (up to round-off); one share need
        not be positive where an owner's entries couple DOFs (a consistent
        mass), but an owner's whole block is, when it is positive
        semi-definite.
        """
        V = np.asarray(V)
        out = np.zeros((n_owners, V.shape[1]))
        owned = self.owner >= 0
        if not owned.any():
            return out
        rows, cols, data, owner = self.rows[owned], self.cols[owned], self.data[owned], self.owner[owned]
        # One mode at a time keeps the temporary at one float per entry.
        for k in range(V.shape[1]):
            v = V[:, k]
            out[:, k] = np.bincount(owner, weights=data * v[rows] * v[cols], minlength=n_owners)
        return out


class Triplets:
    """COO entries of a square matrix, summed when it is built (one pass for all blocks)."""

    def __init__(self) -> None:
        self._rows: list[np.ndarray] = []
        self._cols: list[np.ndarray] = []
        self._data: list[np.ndarray] = []
        self._owner: list[np.ndarray] = []

    @property
    def n_entries(self) -> int:
        """Number of entries collected so far (before summing)."""
        return sum(a.size for a in self._data)

    def add(self, rows, cols, data, owner: int = -1) -> None:
        """Entries (rows[i], cols[i]) += data[i]."""
        data = np.asarray(data, dtype=float).ravel()
        self._rows.append(np.asarray(rows, dtype=np.int64).ravel())
        self._cols.append(np.asarray(cols, dtype=np.int64).ravel())
        self._data.append(data)
        self._owner.append(np.full(data.size, owner, dtype=np.int64))

    def add_dense(self, dofs, block, owner: int = -1) -> None:
        """A dense block on the DOFs ``dofs`` (rows and columns)."""
        dofs = np.asarray(dofs, dtype=np.int64)
        r, c = np.meshgrid(dofs, dofs, indexing="ij")
        self.add(r, c, block, owner)

    def add_sparse(self, A, offset: int = 0, owner: int = -1) -> None:
        """A sparse matrix whose DOF 0 is global DOF ``offset``."""
        c = sp.coo_matrix(A)
        self.add(c.row + offset, c.col + offset, c.data, owner)

    def add_elements(self, dofs: np.ndarray, blocks: np.ndarray, owner=-1) -> None:
        """Element blocks ``blocks[e]`` (n_el, nb, nb) on the DOFs ``dofs[e]`` (n_el, nb).

        ``owner`` is one owner for all elements or one per element.
        """
        dofs = np.asarray(dofs, dtype=np.int64)
        blocks = np.asarray(blocks, dtype=float)
        nb = dofs.shape[1]
        rows = np.broadcast_to(dofs[:, :, None], blocks.shape)
        cols = np.broadcast_to(dofs[:, None, :], blocks.shape)
        owner = np.asarray(owner, dtype=np.int64)
        n = blocks.size
        self._rows.append(rows.ravel())
        self._cols.append(cols.ravel())
        self._data.append(blocks.ravel())
        own = np.full(n, owner, dtype=np.int64) if owner.ndim == 0 else np.repeat(owner, nb * nb)
        self._owner.append(own)

    def entries(self, index=None, scale=None) -> Entries:
        """All entries, with rows and columns mapped through ``index`` (an array) if given.

        Entries whose row or column maps to −1 are dropped (they must be zero:
        a DOF that is not a coordinate). ``scale`` (an array over the DOFs)
        multiplies entry (i, j) by scale[i]·scale[j] before the mapping: the
        congruence Tᵀ A T with T a mapping whose entries are ``scale`` (a DOF
        tied to another by a fixed ratio, as a rigid gear mesh ties its wheels).
        """
        if not self._data:
            z = np.zeros(0, dtype=np.int64)
            return Entries(z, z, np.zeros(0), z)

        def joined(chunks):
            return chunks[0] if len(chunks) == 1 else np.concatenate(chunks)

        rows, cols = joined(self._rows), joined(self._cols)
        data, owner = joined(self._data), joined(self._owner)
        if scale is not None:
            scale = np.asarray(scale, dtype=float)
            with np.errstate(over="ignore"):  # a product past double precision is inf, which callers refuse
                data = data * scale[rows] * scale[cols]
        if index is not None:
            index = np.asarray(index)
            rows, cols = index[rows], index[cols]
            keep = (rows >= 0) & (cols >= 0)
            if not keep.all():
                rows, cols, data, owner = rows[keep], cols[keep], data[keep], owner[keep]
        return Entries(rows, cols, data, owner)

    def build(self, n: int, index=None) -> sp.csr_matrix:
        """The n × n CSR matrix, duplicates summed; ``index`` maps DOFs to rows first."""
        return csr(self.entries(index), n)


def csr(entries: Entries, n: int) -> sp.csr_matrix:
    """Entries summed into an n × n CSR matrix with sorted indices."""
    A = sp.csr_matrix((entries.data, (entries.rows, entries.cols)), shape=(n, n))
    A.sum_duplicates()
    return A
