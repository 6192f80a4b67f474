"""scikit-fem peer run for benchmarks/bench_tet10.py: K and M of a mesh of 10-node tetrahedra.

Run it with the peers virtualenv (``pip install scikit-fem`` there, see benchmarks/setup_peers.sh),
never with flexshaft's:

    benchmarks/.venv-peers/bin/python benchmarks/peers/skfem_tet10.py MESH.npz [--matrices OUT.npz]

``MESH.npz`` holds the mesh's corners, ``p`` (3, nv) in m and ``t`` (4, m), and the material ``E``
(Pa), ``nu``, ``rho`` (kg/m³). The script builds scikit-fem's ``MeshTet`` with the quadratic vector
element ``ElementVector(ElementTetP2())`` - straight elements, mid-side DOFs on the edges - and
assembles, the way its documentation does:

- K with ``skfem.models.elasticity.linear_elasticity(λ, μ)`` on a basis of ``intorder=2`` (4
  points, exact for straight P2 elements, as flexshaft's rule);
- M with the form ρ u·v on a basis of the default order (4 for P2: exact for the degree-4
  integrand).

It times the bases and the two assemblies with ``time.perf_counter`` and prints one JSON line:

    {"seconds": total, "seconds_basis": .., "seconds_K": .., "seconds_M": .., "peak_mib": ..,
     "before_mib": .., "n_dofs": .., "nnz_K": .., "nnz_M": ..}

``--matrices OUT.npz`` also saves K and M (CSR arrays) and the DOF map (``nodal_dofs`` (3, nv),
``edge_dofs`` (3, ne), ``edges`` (2, ne) vertex pairs) for the agreement check.
"""

from __future__ import annotations

import argparse
import json
import resource
import time

import numpy as np
from skfem import Basis, BilinearForm, ElementTetP2, ElementVector, MeshTet, asm
from skfem.helpers import dot
from skfem.models.elasticity import lame_parameters, linear_elasticity


def peak_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("mesh")
    parser.add_argument("--matrices")
    args = parser.parse_args()
    data = np.load(args.mesh)
    p, t = data["p"], data["t"]
    E, nu, rho = float(data["E"]), float(data["nu"]), float(data["rho"])

    @BilinearForm
    def mass(u, v, w):
        return rho * dot(u, v)

    before = peak_mib()
    t0 = time.perf_counter()
    mesh = MeshTet(p, t)
    element = ElementVector(ElementTetP2())
    basis_k = Basis(mesh, element, intorder=2)
    basis_m = Basis(mesh, element)
    t1 = time.perf_counter()
    K = asm(linear_elasticity(*lame_parameters(E, nu)), basis_k)
    t2 = time.perf_counter()
    M = asm(mass, basis_m)
    t3 = time.perf_counter()
    record = {
        "seconds": t3 - t0,
        "seconds_basis": t1 - t0,
        "seconds_K": t2 - t1,
        "seconds_M": t3 - t2,
        "peak_mib": peak_mib(),
        "before_mib": before,
        "n_dofs": int(K.shape[0]),
        "nnz_K": int(K.nnz),
        "nnz_M": int(M.nnz),
    }
    if args.matrices:
        K, M = K.tocsr(), M.tocsr()
        np.savez(
            args.matrices,
            K_data=K.data,
            K_indices=K.indices,
            K_indptr=K.indptr,
            M_data=M.data,
            M_indices=M.indices,
            M_indptr=M.indptr,
            nodal_dofs=basis_k.nodal_dofs,
            edge_dofs=basis_k.edge_dofs,
            edges=mesh.edges,
        )
    print(json.dumps(record))


if __name__ == "__main__":
    main()
