"""The summed matrix with one owner per stored entry: its energy shares against independent references.

An assembled model keeps, beside each of K and M, one small integer per stored
entry (who put it there) and a side list for the positions several owners
share. Two independent references check that this compact record splits
vᵀAv exactly as the owners' own matrices would:

- random entries: each owner's matrix summed by plain scipy from that owner's
  entries alone;
- assembled drivetrains: an owner's matrix as the change of the assembled
  matrix when that one owner's stiffness (or inertia) is doubled, through the
  public API only - nothing of the owner bookkeeping is used.
"""

import numpy as np
import pytest
import scipy.sparse as sp

import flexshaft as fs
from flexshaft.linalg.sparse import ROWS_PER_BLOCK, SHARED, Triplets
from flexshaft.sections import table_from_segments

RNG = np.random.default_rng(7)


def _abs_quadratic(A, V):
    """Σ_ij |A_ij·v_i·v_j| per column: the size of the terms a quadratic form sums."""
    A = abs(sp.csr_matrix(A))
    return np.einsum("ij,ij->j", np.abs(V), A @ np.abs(V))


def _random_triplets(n, n_owners, size, rng):
    rows = rng.integers(0, n, size)
    cols = rng.integers(0, n, size)
    data = rng.standard_normal(size)
    owner = rng.integers(-1, n_owners, size)  # -1: nobody in particular
    return rows, cols, data, owner


@pytest.mark.parametrize("mapped", [False, True])
def test_random_entries_split_like_each_owners_own_scipy_matrix(mapped):
    n_dofs, n_owners = 40, 5
    rows, cols, data, owner = _random_triplets(n_dofs, n_owners, 900, RNG)  # ~0.5 entries per position
    if mapped:
        # Three DOFs are dropped (not coordinates); two are tied to others by a ratio (rigid gears).
        index = np.arange(n_dofs) - 3
        index[:3] = -1
        index[[10, 20]] = index[[11, 21]]
        scale = np.ones(n_dofs)
        scale[[10, 20]] = [0.5, -3.0]
        n = n_dofs - 3
        data = np.where((index[rows] >= 0) & (index[cols] >= 0), data, 0.0)  # dropped ones must be 0
        ref_r, ref_c, ref_d = index[rows], index[cols], data * scale[rows] * scale[cols]
    else:
        index = scale = None
        n = n_dofs
        ref_r, ref_c, ref_d = rows, cols, data
    tr = Triplets()
    even = np.arange(owner.size) % 2 == 0
    for o in range(-1, n_owners):
        # Half of each owner's entries as triplets, half as 2×2 element blocks holding the entry at
        # (0, 1) and zeros elsewhere: both kinds of block, and explicit zeros, go through.
        sel = (owner == o) & even
        tr.add(rows[sel], cols[sel], data[sel], owner=o)
        sel = (owner == o) & ~even
        blocks = np.zeros((sel.sum(), 2, 2))
        blocks[:, 0, 1] = data[sel]
        tr.add_elements(np.column_stack([rows[sel], cols[sel]]), blocks, owner=o)
    e = tr.entries(n, index, scale)
    ok = (ref_r >= 0) & (ref_c >= 0)

    def plain(sel):
        s = sel & ok
        return sp.coo_matrix((ref_d[s], (ref_r[s], ref_c[s])), shape=(n, n)).tocsr()

    whole = plain(np.ones(owner.size, dtype=bool))
    # The same numbers summed in another order: a few ulps of the largest sum.
    assert abs(e.matrix - whole).max() <= 1e-14 * abs(whole).max()
    assert e.matrix.has_canonical_format and e.matrix.shape == (n, n)
    V = RNG.standard_normal((n, 3))
    shares = e.quadratic_by_owner(V, n_owners)
    for o in range(n_owners):
        A_o = plain(owner == o)
        ref = np.einsum("ij,ij->j", V, A_o @ V)
        # The same products summed in another order: round-off of ~n_terms·eps of the terms' sizes.
        assert shares[o] == pytest.approx(ref, abs=1e-13 * _abs_quadratic(A_o, V).max())
    # The shares and nobody's entries add up to the whole form.
    nobody = np.einsum("ij,ij->j", V, plain(owner == -1) @ V)
    total = np.einsum("ij,ij->j", V, whole @ V)
    assert shares.sum(axis=0) + nobody == pytest.approx(total, abs=1e-13 * _abs_quadratic(whole, V).max())
    # Positions of one owner (or nobody) are most; the side list holds only the shared ones.
    assert np.all(np.isin(e.shared_at, np.flatnonzero(e.owner == SHARED)))
    assert np.all(np.isin(np.flatnonzero(e.owner == SHARED), e.shared_at))


def test_compact_record_one_owner_per_stored_entry_and_a_side_list_where_they_meet():
    # Two owners on a chain of 2×2 blocks meeting at one node: only that node's diagonal is shared.
    k = np.array([[1.0, -1.0], [-1.0, 1.0]])
    tr = Triplets()
    first = np.column_stack([np.arange(4), np.arange(1, 5)])  # nodes 0 … 4
    second = np.column_stack([np.arange(4, 7), np.arange(5, 8)])  # nodes 4 … 7
    tr.add_elements(first, np.broadcast_to(k, (4, 2, 2)), owner=0)
    tr.add_elements(second, np.broadcast_to(2 * k, (3, 2, 2)), owner=1)
    e = tr.entries(8)
    A = e.matrix
    assert e.owner.size == A.nnz and e.owner.dtype == np.int8
    junction = np.flatnonzero(e.owner == SHARED)
    assert junction.size == 1
    p = int(junction[0])
    assert A.indices[p] == 4 and A.indptr[4] <= p < A.indptr[5]  # the diagonal entry of node 4
    assert sorted(e.shared_owner.tolist()) == [0, 1] and np.all(e.shared_at == p)
    assert e.shared_data.sum() == A.data[p]
    assert e.dominant_owner(4, 4) == 1 and e.dominant_owner(0, 1) == 0 and e.dominant_owner(0, 7) == -1
    # The triplets, summed by position, give the matrix back.
    r, c, d, o = e.triplets()
    assert abs(sp.coo_matrix((d, (r, c)), shape=A.shape).tocsr() - A).max() == 0.0
    # build() gives the same matrix without the owners.
    assert abs(tr.build(8) - A).max() == 0.0


def test_no_entries_give_an_empty_matrix():
    e = Triplets().entries(5)
    assert e.matrix.shape == (5, 5) and e.matrix.nnz == 0
    assert np.all(e.quadratic_by_owner(np.ones((5, 2)), 3) == 0.0)


# --- Assembled models against the change of the matrix when one owner is doubled -------------


def _torsion_chain(k=None, j=None, elements=(5, 4)):
    """Motor, two shafts and a coupling between them, generator: components share every junction node."""
    k = k or {}
    j = j or {}
    return fs.Drivetrain(
        "c",
        [
            fs.Rigid("motor", 58.1 * j.get("motor", 1)),
            fs.Shaft("p1", 3.08e5 * k.get("p1", 1), 0.44 * j.get("p1", 1), elements=elements[0]),
            fs.Coupling("p3", 5.5e4 * k.get("p3", 1), 0.06 * j.get("p3", 1)),
            fs.Shaft("p2", 1.57e5 * k.get("p2", 1), 0.75 * j.get("p2", 1), elements=elements[1]),
            fs.Rigid("gen", 6.67 * j.get("gen", 1)),
        ],
    )


def _geared_chain(rigid_mesh, k=None, j=None):
    """A stage of ratio 3.7 between two shafts: a rigid mesh ties the driven side by the ratio."""
    k = k or {}
    j = j or {}
    mesh = None if rigid_mesh else 8e5 * k.get("g", 1)
    return fs.Drivetrain(
        "g",
        [
            fs.Rigid("motor", 2.0 * j.get("motor", 1)),
            fs.Shaft("in", 2e5 * k.get("in", 1), 0.3 * j.get("in", 1), elements=3),
            fs.Gear(
                "g",
                3.7,
                inertia_in=0.05 * j.get("g", 1),
                inertia_out=0.4 * j.get("g", 1),
                mesh_stiffness=mesh,
            ),
            fs.Shaft("out", 9e5 * k.get("out", 1), 1.1 * j.get("out", 1), elements=4),
            fs.Rigid("load", 30.0 * j.get("load", 1)),
        ],
    )


def _full_chain(k=None, j=None, bearing=1.0):
    """A 6-DOF line: a shaft entered as a flexible body, a coupling, a plain shaft, two bearings."""
    k = k or {}
    j = j or {}

    def steel(name):
        return fs.Material(E=fs.STEEL.E * k.get(name, 1), nu=fs.STEEL.nu, rho=fs.STEEL.rho * j.get(name, 1))

    def shaft(name, length, n, **kw):
        t = table_from_segments([{"length": length, "od": 0.1}], name=name)
        return fs.Shaft.from_sections(name, t, steel(name), max_element_length=length / n, **kw)

    return fs.Drivetrain(
        "f",
        [
            fs.Rigid(
                "motor",
                2.0 * j.get("motor", 1),
                mass=20.0 * j.get("motor", 1),
                diametral_inertia=1.0 * j.get("motor", 1),
            ),
            shaft("a", 1.0, 8, reduce=fs.Reduce(modes=3)),
            fs.Coupling("c", 1e4 * k.get("c", 1), 0.01 * j.get("c", 1)),
            shaft("b", 0.5, 3),
            fs.Rigid(
                "gen",
                1.0 * j.get("gen", 1),
                mass=10.0 * j.get("gen", 1),
                diametral_inertia=0.5 * j.get("gen", 1),
            ),
        ],
        dofs="full",
        bearings=(("motor", 1e8 * bearing), ("c/b", 3e7)),
    )


def _doubling_shares(build, model, names, V, what):
    """vᵀ(A(owner doubled) − A)v per owner in ``names``: each owner's form, from the public API alone."""
    A = getattr(model, what)
    base = np.einsum("ij,ij->j", V, A @ V)
    out = {}
    for name in names:
        other = fs.assemble(build(name))
        assert other.n_dof == model.n_dof
        out[name] = np.einsum("ij,ij->j", V, getattr(other, what) @ V) - base
    return out


LONG = (ROWS_PER_BLOCK + 7, 2 * ROWS_PER_BLOCK - 3)  # the shares are summed over blocks of rows

CASES = {
    "torsion chain": (
        _torsion_chain,
        lambda name: _torsion_chain(k={name: 2}),
        lambda name: _torsion_chain(j={name: 2}),
        ["p1", "p3", "p2"],
        ["motor", "p1", "p3", "p2", "gen"],
    ),
    "long torsion chain": (
        lambda: _torsion_chain(elements=LONG),
        lambda name: _torsion_chain(k={name: 2}, elements=LONG),
        lambda name: _torsion_chain(j={name: 2}, elements=LONG),
        ["p1", "p3", "p2"],
        ["motor", "p1", "p3", "p2", "gen"],
    ),
    "rigid gear mesh": (
        lambda: _geared_chain(True),
        lambda name: _geared_chain(True, k={name: 2}),
        lambda name: _geared_chain(True, j={name: 2}),
        ["in", "out"],
        ["motor", "in", "g", "out", "load"],
    ),
    "elastic gear mesh": (
        lambda: _geared_chain(False),
        lambda name: _geared_chain(False, k={name: 2}),
        lambda name: _geared_chain(False, j={name: 2}),
        ["in", "g", "out"],
        ["motor", "in", "g", "out", "load"],
    ),
}


@pytest.mark.parametrize("case", list(CASES))
def test_torsion_shares_are_each_owners_change_of_the_matrix(case):
    base, stiffer, heavier, k_names, j_names = CASES[case]
    model = fs.assemble(base())
    V = RNG.standard_normal((model.n_dof, 4))
    names = model.component_names
    for what, entries, build, which in (
        ("K", model.stiffness_entries, stiffer, k_names),
        ("M", model.mass_entries, heavier, j_names),
    ):
        assert entries.matrix is getattr(model, what)  # the model's matrix itself, not a copy
        shares = entries.quadratic_by_owner(V, model.n_owners)
        ref = _doubling_shares(build, model, which, V, what)
        # A difference of two assembled matrices: at a node shared with other owners the doubled
        # entry is summed with theirs, which leaves eps × their size; 1e-13 of the whole form's terms.
        tol = 1e-13 * _abs_quadratic(getattr(model, what), V).max()
        for name in which:
            assert shares[names.index(name)] == pytest.approx(ref[name], abs=tol), (what, name)
        # Owners not listed (rigid components' stiffness, a rigid mesh's) hold nothing.
        for name in set(names) - set(which):
            assert shares[names.index(name)] == pytest.approx(0.0, abs=tol), (what, name)


def test_full_model_with_a_flexible_body_and_bearings_shares_its_strain_energy_exactly():
    model = fs.assemble(_full_chain())
    assert model.bodies and model.n_owners == len(model.component_names) + 2
    V = RNG.standard_normal((model.n_dof, 4))
    names = model.component_names
    shares = model.stiffness_entries.quadratic_by_owner(V, model.n_owners)
    ref = _doubling_shares(lambda name: _full_chain(k={name: 2}), model, ["a", "c", "b"], V, "K")
    stiffer_bearing = fs.assemble(_full_chain(bearing=2.0)).K
    ref["bearing at motor"] = np.einsum("ij,ij->j", V, (stiffer_bearing - model.K) @ V)
    scale = _abs_quadratic(model.K, V).max()
    # Plain shaft, coupling and bearing: a difference of two assembled matrices (see above).
    for name, row in (("c", names.index("c")), ("b", names.index("b")), ("bearing at motor", len(names))):
        assert shares[row] == pytest.approx(ref[name], abs=1e-13 * scale), name
    # The flexible body: doubling E and G re-runs its reduction (a constraint-mode solve and an
    # eigensolve of the interior). A factor of two leaves that arithmetic exact (measured 6e-17 of
    # the terms, like the others) unless a kernel's choices depend on scale: 1e-12 leaves room.
    assert shares[names.index("a")] == pytest.approx(ref["a"], abs=1e-12 * scale)
    # Rigid components carry no stiffness; the shares and the rest add up to vᵀKv.
    for name in ("motor", "gen"):
        assert shares[names.index(name)] == pytest.approx(0.0, abs=1e-13 * scale)
    total = np.einsum("ij,ij->j", V, model.K @ V)
    assert shares.sum(axis=0) == pytest.approx(total, abs=1e-13 * scale)


def test_full_model_kinetic_shares_of_the_plain_owners():
    # A flexible body's modal coordinates change scale with its density (they are mass-normalised),
    # so only the other owners' inertia is doubled here; the body's share is the rest.
    model = fs.assemble(_full_chain())
    V = RNG.standard_normal((model.n_dof, 4))
    names = model.component_names
    shares = model.mass_entries.quadratic_by_owner(V, model.n_owners)
    ref = _doubling_shares(lambda name: _full_chain(j={name: 2}), model, ["motor", "c", "b", "gen"], V, "M")
    scale = _abs_quadratic(model.M, V).max()
    for name in ref:
        # A difference of two assembled matrices (see the torsion test).
        assert shares[names.index(name)] == pytest.approx(ref[name], abs=1e-13 * scale), name
    assert shares[len(names) :] == pytest.approx(0.0, abs=1e-13 * scale)  # bearings have no mass


def test_a_long_uniform_shaft_keeps_its_matrices_once_and_constant_arrays_as_one_value():
    n = 100_000
    stiffness, inertia = 4.0e6, 1.5
    m = fs.assemble(fs.Drivetrain("u", [fs.Shaft("s", stiffness, inertia, elements=n)]))
    # The owners cost one byte per stored entry beside the matrix; no junction, no side list.
    for entries, A in ((m.stiffness_entries, m.K), (m.mass_entries, m.M)):
        assert entries.matrix is A
        assert entries.owner.nbytes == A.nnz and entries.shared_at.size == 0
        assert np.all(entries.owner == 0)
    assert m.K.indices.dtype == np.int32
    # Constant per-element and per-node arrays read as full arrays but hold one value.
    constant = {
        "element_stiffness": stiffness * n,
        "element_damping": 0.0,
        "element_component": 0,
        "element_ratio": 1.0,
        "speed_ratio": 1.0,
        "x": 0.0,  # a shaft given by numbers has no length
    }
    for name, value in constant.items():
        a = getattr(m, name)
        assert a.strides == (0,) and not a.flags.writeable, name
        assert np.array_equal(a, np.full(a.size, value)), name
    assert m.element_stiffness.size == n and m.speed_ratio.size == n + 1
