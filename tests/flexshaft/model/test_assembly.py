"""The one assembled model: its coordinates, DOF map and recovery, torsion and 6-DOF alike."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.sections import table_from_segments


def shaft(name, length, n, **kw):
    t = table_from_segments([{"length": length, "od": 0.1}], name=name)
    return fs.Shaft.from_sections(name, t, fs.STEEL, max_element_length=length / n, **kw)


def chain(dofs, reduce=None):
    return fs.Drivetrain(
        "m",
        [
            fs.Rigid("motor", 2.0),
            shaft("a", 1.0, 4, reduce=reduce),
            fs.Coupling("c", 1e4, 0.01),
            shaft("b", 0.5, 2),
            fs.Rigid("gen", 1.0),
        ],
        dofs=dofs,
    )


def test_torsion_chain_coordinates_are_its_nodes():
    m = fs.assemble(chain("torsion"))
    # 4 + 1 + 2 elements: 8 nodes, one θx each; the coordinates are the nodes, T is the identity.
    assert m.n_nodes == 8 and m.n_dof == 8 and m.bandwidth == 1
    assert m.coordinate_labels == tuple(f"node {i} θx" for i in range(8))
    assert abs(m.T - np.eye(8)).max() == 0.0
    assert [st.name for st in m.stations] == ["motor", "a/c", "c/b", "gen"]
    assert list(m.start_node) == [0, 0, 4, 5, 7] and list(m.end_node) == [0, 4, 5, 7, 7]


def test_full_chain_links_the_coupling_and_recovers_every_node_dof():
    m = fs.assemble(chain("full"))
    # 8 nodes × 6 DOFs, less the 5 DOFs the coupling links rigidly across it (node 5 shares node 4's).
    assert m.n_nodes == 8 and m.n_dof == 6 * 8 - 5
    labels = m.coordinate_labels
    assert "node 4 uy" in labels and "node 5 uy" not in labels and "node 5 θx" in labels
    # T copies each coordinate to its node DOF, and a linked DOF to both nodes.
    q = np.arange(m.n_dof, dtype=float)
    u = (m.T @ q).reshape(8, 6)
    np.testing.assert_array_equal(u[5, [0, 1, 2, 4, 5]], u[4, [0, 1, 2, 4, 5]])
    assert u[5, 3] != u[4, 3]


def test_flexible_body_coordinates_come_last_and_are_named():
    red = fs.Reduce(modes=2)
    m = fs.assemble(chain("torsion", reduce=red))
    body = m.bodies[0]
    # Shaft a keeps its two end nodes; its 3 interior nodes are recovered, not coordinates.
    assert list(body.interface_nodes) == [0, 4]
    assert np.all(m.modal[-body.body.n_modes :]) and not m.modal[: m.n_dof - body.body.n_modes].any()
    # Two kept modes; the interior has 3 DOFs, so only one residual vector is left outside their span.
    assert body.body.n_modes == 3 and body.body.n_residual == 1
    assert m.coordinate_labels[-3:] == ("a mode 1", "a mode 2", "a residual 1")
    # Interior nodes are rows of the body's own recovery matrix.
    V = np.random.default_rng(0).standard_normal((m.n_dof, 2))
    np.testing.assert_allclose((m.T @ V)[:5], body.recover(V), rtol=1e-14)


@pytest.mark.parametrize("dofs", ["torsion", "full"])
def test_component_entries_add_up_to_the_matrices(dofs):
    # Every K and M entry has an owner; their quadratic forms split vᵀKv and vᵀMv exactly.
    m = fs.assemble(chain(dofs, reduce=fs.Reduce(modes=2)))
    V = np.random.default_rng(1).standard_normal((m.n_dof, 3))
    for A, entries in ((m.K, m.stiffness_entries), (m.M, m.mass_entries)):
        parts = entries.quadratic_by_owner(V, m.n_owners)
        np.testing.assert_allclose(parts.sum(axis=0), np.einsum("ij,ij->j", V, A @ V), rtol=1e-12)


@pytest.mark.parametrize("dofs", ["torsion", "full"])
def test_a_flexible_bodys_own_modes_are_the_modal_result_of_a_model_holding_it(dofs):
    # FlexibleBody.free_hz is the reduced part's free-free spectrum (its orthonormalised basis);
    # the same body alone in a model gives it again through the one modal analysis.
    from flexshaft.reduction import craig_bampton

    t = table_from_segments([{"length": 1.2, "od": 0.1}, {"length": 0.4, "od": 0.07}], name="s")
    s = fs.Shaft.from_sections("s", t, fs.STEEL, max_element_length=0.05, reduce=fs.Reduce(modes=6))
    body = craig_bampton(fs.part_model(t, fs.STEEL, dofs=dofs, max_element_length=0.05), modes=6)
    r = fs.modal_analysis(fs.Drivetrain("one", [s], dofs=dofs), body.free_hz.size)
    assert r.rigid.sum() == np.sum(body.free_hz == 0.0)
    # Two symmetric eigensolves of the same reduced K and M: round-off of the larger eigenvalues'
    # scale (the residual vectors reach 1e5 Hz), 1e-9 relative on the lowest elastic ones.
    np.testing.assert_allclose(r.frequencies_hz[~r.rigid], body.free_hz[body.free_hz > 0], rtol=1e-9)


@pytest.mark.parametrize("dofs", ["torsion", "full"])
def test_without_damping_the_parts_modal_damping_is_left_out_and_nothing_else(dofs):
    # damping=False (the mesh check, the twist test) spares the dense eigen-solve behind each part's modal
    # damping; K, M and everything else are the same arrays, and a coupling's damper stays.
    d = fs.Drivetrain(
        "m",
        [
            fs.Rigid("motor", 2.0),
            shaft("a", 1.0, 4, damping_ratio=0.0053),
            fs.Coupling("c", 1e4, 0.01, damping=7.0),
            shaft("b", 0.5, 2, damping_ratio=0.0053),
            fs.Rigid("gen", 1.0),
        ],
        dofs=dofs,
    )
    full, bare = fs.assemble(d), fs.assemble(d, damping=False)
    assert abs(full.K - bare.K).max() == 0.0 and abs(full.M - bare.M).max() == 0.0
    damper = fs.assemble(
        dataclasses.replace(
            d,
            components=tuple(
                dataclasses.replace(c, damping_ratio=0.0) if c.type == "shaft" else c for c in d.components
            ),
        )
    )
    assert abs(bare.C - damper.C).max() == 0.0  # the coupling's damper alone
    assert abs(full.C - bare.C).max() > 0.0  # and the parts' modal damping was there to leave out
