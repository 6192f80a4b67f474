"""Rigid interfaces of a solid part (RBE2): the tie reproduces rigid motions exactly, a free part's tied
stiffness still has them as its null space, and bad faces are refused."""

from __future__ import annotations

import numpy as np
import pytest

from flexshaft.elements.materials import STEEL
from flexshaft.elements.tet10 import solid_matrices
from flexshaft.elements.tetmesh import TetMesh
from flexshaft.errors import ModelError
from flexshaft.linalg.spd import rigid_body_modes
from flexshaft.parts.solidties import constrain, rigid_interface
from tests.flexshaft.elements.test_tet10 import box_mesh, tri6_faces_on


def _bar():
    nodes, tets = box_mesh(np.array((4, 2, 2)), (0.4, 0.1, 0.1))
    faces = {"start": tri6_faces_on(nodes, tets, 0, 0.0), "end": tri6_faces_on(nodes, tets, 0, 0.4)}
    return TetMesh("bar", nodes, tets, faces=faces)


def test_the_master_is_the_face_centroid():
    mesh = _bar()
    end = rigid_interface(mesh, "end")
    np.testing.assert_allclose(end.master, [0.4, 0.05, 0.05], atol=1e-15)
    assert end.area == pytest.approx(0.01, rel=1e-14)
    # every node of the face once: the 5 x 5 grid of corner and mid-side nodes of a 2 x 2 cell face
    assert end.nodes.size == 25


def test_the_tie_reproduces_rigid_motions_and_keeps_them_free():
    mesh = _bar()
    K = solid_matrices(mesh, STEEL).K
    system = constrain(K, mesh, [rigid_interface(mesh, "start"), rigid_interface(mesh, "end")])
    # u = T·q of the near-null space's columns is the body's rigid motion, node by node: the tie's
    # rows are u = t + θ × (x − x_m) exactly, so to round-off of the coordinates (1e-16 · 0.4 m)
    np.testing.assert_allclose(system.T @ system.near_null, rigid_body_modes(mesh.nodes), atol=1e-14)
    # tied but not clamped, the part is still free: K'·null = Tᵀ K (T null) = 0 to K's round-off
    Kn = system.K @ system.near_null
    assert np.abs(Kn).max() <= 1e-12 * abs(system.K).max() * np.abs(system.near_null).max()
    assert set(system.masters) == {"start", "end"}


def test_a_clamped_interface_has_no_master_dofs():
    mesh = _bar()
    K = solid_matrices(mesh, STEEL).K
    system = constrain(
        K, mesh, [rigid_interface(mesh, "start"), rigid_interface(mesh, "end")], clamped=("start",)
    )
    assert set(system.masters) == {"end"}
    n_face = rigid_interface(mesh, "start").nodes.size + rigid_interface(mesh, "end").nodes.size
    assert system.K.shape[0] == 3 * (mesh.n_nodes - n_face) + 6


def test_bad_interfaces_are_refused():
    mesh = _bar()
    with pytest.raises(ModelError, match="is not a face set") as e:
        rigid_interface(mesh, "middle")
    assert e.value.field == "interface"
    K = solid_matrices(mesh, STEEL).K
    end = rigid_interface(mesh, "end")
    with pytest.raises(ModelError, match="shares nodes"):
        constrain(K, mesh, [end, end])
    with pytest.raises(ModelError, match="is not an interface"):
        constrain(K, mesh, [end], clamped=("start",))


def test_an_averaging_face_weighs_its_nodes_by_their_consistent_areas():
    from flexshaft.parts.solidties import _face_weights, averaging_interface

    mesh = _bar()
    tri = mesh.faces["end"]
    w = _face_weights(mesh, tri)
    # a straight 6-node triangle: ∫N_i dA is 0 at the corners and A/3 at the mid-sides (the quadratic
    # basis' closed form); the face's total is its area
    c = mesh.nodes[tri[:, :3]]
    area = 0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1)
    np.testing.assert_allclose(w[:, :3], 0.0, atol=1e-16)
    np.testing.assert_allclose(w[:, 3:], np.repeat(area[:, None] / 3, 3, axis=1), rtol=1e-13)
    end = averaging_interface(mesh, "end")
    assert end.area == pytest.approx(0.01, rel=1e-13)
    # W fits rigid motions exactly: the face moving rigidly gives its master that motion
    B = rigid_body_modes(mesh.nodes)
    dofs = (3 * end.nodes[:, None] + np.arange(3)).ravel()
    np.testing.assert_allclose(end.W @ B[dofs], _master_motion(end.master, mesh.nodes), atol=1e-12)


def _master_motion(master, nodes):
    # the rigid_body_modes columns seen at the master: translations, and rotations ω (scaled by the RMS
    # radius about the centroid) moving it by ω × (x_m − c)
    c = nodes.mean(axis=0)
    scale = np.sqrt(np.mean(np.sum((nodes - c) ** 2, axis=1)))
    r = master - c
    m = np.zeros((6, 6))
    m[:3, :3] = np.eye(3)
    for k in range(3):
        w = np.eye(3)[k] / scale
        m[:3, 3 + k] = np.cross(w, r)
        m[3:, 3 + k] = w
    return m
