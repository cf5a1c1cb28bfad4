#!/usr/bin/env python3
"""Build the spectral reference fixture for symcorr-spectral.

Writes
  fixtures/spectral/ref_mesh.off    a deterministic, non-symmetric, closed genus-0 mesh (1002 vertices)
  fixtures/spectral/reference.json  independent numpy/scipy/potpourri3d/pygeodesic numbers on it
                                    (+ the 50 smallest eigenvalues of fixtures/body/body.off)

Run from the repository root (or anywhere):
  tools/.venv/bin/python tools/reference/make_reference.py

Nothing is random; re-running reproduces the mesh bit for bit and the numbers up to the
last few ulps of the iterative solvers (ARPACK start vector is fixed with a seeded v0).
"""

import json
import math
import os
import platform
import sys
import time

import numpy as np
import scipy
import scipy.sparse as sp
import scipy.sparse.csgraph as csgraph
import scipy.sparse.linalg as spla

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import meshutil as mu  # noqa: E402

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
OUT_DIR = os.path.join(ROOT, "fixtures", "spectral")
MESH_PATH = os.path.join(OUT_DIR, "ref_mesh.off")
JSON_PATH = os.path.join(OUT_DIR, "reference.json")
BODY_PATH = os.path.join(ROOT, "fixtures", "body", "body.off")

FREQUENCY = 10  # geodesic-sphere subdivision frequency: 10 f^2 + 2 = 1002 vertices
K_REF = 30
K_BODY = 50
N_HKS_TIMES = 5
SIGMA = -1e-8
DIJKSTRA_SOURCE = 0

PHI = (1.0 + 5.0 ** 0.5) / 2.0
ICO_VERTS = np.array([
    [-1, PHI, 0], [1, PHI, 0], [-1, -PHI, 0], [1, -PHI, 0],
    [0, -1, PHI], [0, 1, PHI], [0, -1, -PHI], [0, 1, -PHI],
    [PHI, 0, -1], [PHI, 0, 1], [-PHI, 0, -1], [-PHI, 0, 1],
], dtype=np.float64)
ICO_FACES = [
    [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
    [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
    [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
    [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
]


def rotation(axis, angle):
    """Rodrigues rotation matrix."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * (K @ K)


def radial_displacement(p):
    """Smooth, non-symmetric radius factor (min > 0.7, so the surface stays star-shaped)."""
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    return 1.0 + 0.2 * np.sin(2 * x + 0.3) * np.cos(3 * y + 0.5) + 0.1 * z ** 2 + 0.05 * x * y


def build_ref_mesh():
    """Class-I geodesic sphere (frequency FREQUENCY) on a rotated icosahedron, radially displaced.

    Vertices are deduplicated by their exact barycentric key on the icosahedron
    (which icosahedron vertices, which integer weights), numbered in order of first
    appearance while walking faces in ICO_FACES order and (i, j) lexicographically.
    """
    n = FREQUENCY
    base = ICO_VERTS / np.linalg.norm(ICO_VERTS, axis=1, keepdims=True)
    faces = []
    for f in ICO_FACES:
        a, b, c = base[f]
        # outward orientation: normal . centroid > 0
        if np.dot(np.cross(b - a, c - a), a + b + c) < 0:
            f = [f[0], f[2], f[1]]
        faces.append(f)

    key_to_id = {}
    keys = []

    def vid(f, i, j):
        w = {f[0]: n - i - j, f[1]: i, f[2]: j}
        key = tuple(sorted((v, wt) for v, wt in w.items() if wt > 0))
        if key not in key_to_id:
            key_to_id[key] = len(keys)
            keys.append(key)
        return key_to_id[key]

    tris = []
    for f in faces:
        idx = {}
        for i in range(n + 1):
            for j in range(n + 1 - i):
                idx[(i, j)] = vid(f, i, j)
        for i in range(n):
            for j in range(n - i):
                tris.append((idx[(i, j)], idx[(i + 1, j)], idx[(i, j + 1)]))
                if i + j < n - 1:
                    tris.append((idx[(i + 1, j)], idx[(i + 1, j + 1)], idx[(i, j + 1)]))

    P = np.zeros((len(keys), 3))
    for k, key in enumerate(keys):
        p = sum(wt * base[v] for v, wt in key) / n
        P[k] = p / np.linalg.norm(p)
    R = rotation([0.3, -0.7, 0.5], 0.9)
    P = P @ R.T
    P = P * radial_displacement(P)[:, None]
    F = np.array(tris, dtype=np.int64)
    return P, F


def check_closed_manifold(V, F, name):
    """Every directed edge exactly once and its reverse exactly once (closed, oriented, manifold)."""
    d = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    u = np.unique(d, axis=0)
    assert len(u) == len(d), f"{name}: repeated directed edge (orientation / non-manifold)"
    rev = set(map(tuple, d[:, ::-1]))
    assert all(tuple(e) in rev for e in d), f"{name}: boundary edge present"
    ne = len(d) // 2
    chi = len(V) - ne + len(F)
    assert chi == 2, f"{name}: Euler characteristic {chi}, expected 2"
    ncomp, _ = csgraph.connected_components(adjacency(V, F), directed=False)
    assert ncomp == 1, f"{name}: {ncomp} components"
    return ne


def adjacency(V, F):
    e = mu.edges(F)
    w = np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1)
    n = len(V)
    G = sp.coo_matrix((np.concatenate([w, w]), (np.concatenate([e[:, 0], e[:, 1]]), np.concatenate([e[:, 1], e[:, 0]]))), shape=(n, n))
    return G.tocsr()


def eigs(L, m, k):
    """k smallest of L phi = lambda M phi, shift-invert about SIGMA; sorted ascending; M-normalised."""
    n = L.shape[0]
    M = sp.diags(m).tocsc()
    # Fixed ARPACK start vector => deterministic. Not the constant vector: that is an exact eigenvector
    # (an invariant Krylov space), which makes ARPACK restart from its own internal random vector.
    v0 = np.random.default_rng(12345).standard_normal(n)
    lam, phi = spla.eigsh(L, k=k, M=M, sigma=SIGMA, which="LM", v0=v0)
    order = np.argsort(lam)
    lam, phi = lam[order], phi[:, order]
    # ARPACK already returns M-orthonormal vectors; renormalise anyway and report the defect.
    G = phi.T @ (m[:, None] * phi)
    ortho_defect = float(np.max(np.abs(G - np.eye(k))))
    phi = phi / np.sqrt(np.einsum("ij,i,ij->j", phi, m, phi))
    resid = np.linalg.norm(L @ phi - (m[:, None] * phi) * lam, axis=0) / np.maximum(np.linalg.norm(m[:, None] * phi, axis=0), 1e-300)
    return lam, phi, ortho_defect, resid


def gaussian_curvature(V, F):
    """Paper eq. 4: gc(p) = 3 (2 pi - sum of corner angles at p) / sum of incident triangle areas."""
    n = len(V)
    ang = mu.corner_angles(V, F)
    A = mu.triangle_areas(V, F)
    angle_sum = np.zeros(n)
    area_sum = np.zeros(n)
    for k in range(3):
        np.add.at(angle_sum, F[:, k], ang[:, k])
        np.add.at(area_sum, F[:, k], A)
    return 3.0 * (2.0 * math.pi - angle_sum) / area_sum, angle_sum, area_sum


def heat_geodesic_numpy(L, m, V, F, src, t, poisson_shift=None):
    """Plain heat method (Crane et al. 2013), our own implementation for cross-checking potpourri3d.

    (M + t L) u = delta_src ; X = -grad u / |grad u| per face ; L phi = div X ; phi shifted so phi(src) = 0.
    L is the PSD stiffness, so -div in Crane's sign convention becomes +: we solve L phi = -div_crane X.
    """
    n = len(V)
    M = sp.diags(m).tocsc()
    rhs = np.zeros(n)
    rhs[src] = 1.0
    u = spla.spsolve((M + t * L).tocsc(), rhs)
    A = mu.triangle_areas(V, F)
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    Nn = N / np.linalg.norm(N, axis=1, keepdims=True)
    grad = np.zeros((len(F), 3))
    for k in range(3):
        i, j, l = F[:, k], F[:, (k + 1) % 3], F[:, (k + 2) % 3]
        e_opp = V[l] - V[j]
        grad += u[i][:, None] * np.cross(Nn, e_opp)
    grad /= (2 * A)[:, None]
    X = -grad / np.linalg.norm(grad, axis=1, keepdims=True)
    cots = mu.corner_cotangents(V, F)
    div = np.zeros(n)
    for k in range(3):
        i, j, l = F[:, k], F[:, (k + 1) % 3], F[:, (k + 2) % 3]
        e1 = V[j] - V[i]  # edge to next corner, opposite angle at l
        e2 = V[l] - V[i]  # edge to previous corner, opposite angle at j
        div_i = 0.5 * (cots[:, (k + 2) % 3] * np.einsum("ij,ij->i", e1, X) + cots[:, (k + 1) % 3] * np.einsum("ij,ij->i", e2, X))
        np.add.at(div, i, div_i)
    # Crane: Delta_crane phi = div X with Delta_crane = -L (NSD); so L phi = -div X.
    if poisson_shift is not None:
        # geometry-central's variant: (L + shift I) phi = -div, then shift phi so phi(src) = 0.
        phi = spla.spsolve((L + poisson_shift * sp.identity(n)).tocsc(), -div)
        return phi - phi[src]
    # Pin the null space: solve on the complement of src, phi(src) = 0.
    keep = np.arange(n) != src
    Lk = L[keep][:, keep].tocsc()
    phi = np.zeros(n)
    phi[keep] = spla.spsolve(Lk, -div[keep])
    return phi


def main():
    t_start = time.time()
    os.makedirs(OUT_DIR, exist_ok=True)

    # --- mesh -------------------------------------------------------------------------------------
    P, F = build_ref_mesh()
    mu.write_off(MESH_PATH, P, F, comments=[
        "symcorr spectral reference mesh: class-I geodesic sphere, frequency 10, on a rotated icosahedron,",
        "radially displaced by r = 1 + 0.2 sin(2x+0.3) cos(3y+0.5) + 0.1 z^2 + 0.05 x y (non-symmetric).",
        "Generated by tools/reference/make_reference.py. Coordinates are shortest round-trip reprs (bit exact).",
    ])
    V, F2 = mu.read_off(MESH_PATH)
    assert np.array_equal(V, P) and np.array_equal(F2, F), "OFF round trip not bit-exact"
    n = len(V)
    n_edges = check_closed_manifold(V, F, "ref_mesh")
    ang = mu.corner_angles(V, F)
    min_angle_deg = float(np.degrees(ang.min()))
    max_angle_deg = float(np.degrees(ang.max()))

    # --- operators --------------------------------------------------------------------------------
    L = mu.cotan_laplacian(V, F)
    m = mu.lumped_mass(V, F)
    total_area = float(mu.triangle_areas(V, F).sum())
    row_sums = np.asarray(L.sum(axis=1)).ravel()
    sym_defect = float(abs(L - L.T).max())
    stiffness_diagonal = L.diagonal().copy()
    stiffness_frobenius = float(sp.linalg.norm(L, "fro"))
    n_negative_weights = int(((L - sp.diags(L.diagonal())) > 0).nnz // 2)  # off-diagonal > 0 means W_ij < 0

    # --- eigenpairs --------------------------------------------------------------------------------
    lam, phi, ortho_defect, resid = eigs(L, m, K_REF)
    lam31, _, _, _ = eigs(L, m, K_REF + 1)
    gaps = np.diff(lam31[1:]) / lam31[2:]
    min_rel_gap = float(gaps.min())
    min_gap_pair = int(np.argmin(gaps)) + 1
    gap_after_30 = float((lam31[K_REF] - lam31[K_REF - 1]) / lam31[K_REF])
    agree_k30_k31 = float(np.max(np.abs(lam31[:K_REF] - lam)[1:] / lam[1:]))

    # --- HKS --------------------------------------------------------------------------------------
    t_min = 4.0 * math.log(10.0) / lam[K_REF - 1]
    t_max = 4.0 * math.log(10.0) / lam[1]
    hks_times = np.exp(np.linspace(math.log(t_min), math.log(t_max), N_HKS_TIMES))
    hks = (phi ** 2) @ np.exp(-np.outer(lam, hks_times))  # n x times

    # --- curvature --------------------------------------------------------------------------------
    gc, angle_sum, area_sum = gaussian_curvature(V, F)
    gauss_bonnet = float(np.sum(gc * area_sum / 3.0))

    # --- geodesics --------------------------------------------------------------------------------
    G = adjacency(V, F)
    dij = csgraph.dijkstra(G, directed=False, indices=DIJKSTRA_SOURCE)

    import potpourri3d as pp3d
    solver = pp3d.MeshHeatMethodDistanceSolver(V, F)  # defaults: t_coef=1, use_robust=True
    heat = solver.compute_distance(DIJKSTRA_SOURCE)
    solver_plain = pp3d.MeshHeatMethodDistanceSolver(V, F, t_coef=1.0, use_robust=False)
    heat_plain = solver_plain.compute_distance(DIJKSTRA_SOURCE)
    e = mu.edges(F)
    mean_edge = float(np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1).mean())
    t_heat = mean_edge ** 2
    heat_np = heat_geodesic_numpy(L, m, V, F, DIJKSTRA_SOURCE, t_heat)
    heat_np_shifted = heat_geodesic_numpy(L, m, V, F, DIJKSTRA_SOURCE, t_heat, poisson_shift=1e-6)

    exact = None
    try:
        import pygeodesic.geodesic as pgeo
        alg = pgeo.PyGeodesicAlgorithmExact(V, F.astype(np.int32))
        exact, _ = alg.geodesicDistances(np.array([DIJKSTRA_SOURCE], dtype=np.int32), None)
        exact = np.asarray(exact, dtype=np.float64)
    except ImportError:
        print("pygeodesic not installed: skipping exact_geodesic")

    # --- body eigenvalues -------------------------------------------------------------------------
    t0 = time.time()
    VB, FB = mu.read_off(BODY_PATH)
    check_closed_manifold(VB, FB, "body")
    LB = mu.cotan_laplacian(VB, FB)
    mB = mu.lumped_mass(VB, FB)
    lamB, phiB, orthoB, residB = eigs(LB, mB, K_BODY)
    t_body = time.time() - t0
    body_area = float(mu.triangle_areas(VB, FB).sum())

    # --- sanity -----------------------------------------------------------------------------------
    far = np.arange(n) != DIJKSTRA_SOURCE
    checks = {
        "lambda0_abs": abs(float(lam[0])),
        "hks_min": float(hks.min()),
        "gauss_bonnet_minus_4pi": gauss_bonnet - 4 * math.pi,
        "dijkstra_minus_exact_min": None if exact is None else float((dij - exact).min()),
        "heat_minus_exact_rel_mean": None if exact is None else float(np.mean(np.abs(heat - exact)[far] / exact[far])),
        "heat_minus_exact_rel_max": None if exact is None else float(np.max(np.abs(heat - exact)[far] / exact[far])),
        "heat_plain_minus_exact_rel_mean": None if exact is None else float(np.mean(np.abs(heat_plain - exact)[far] / exact[far])),
        "dijkstra_minus_exact_rel_mean": None if exact is None else float(np.mean((dij - exact)[far] / exact[far])),
        "heat_numpy_vs_potpourri_plain_max_abs": float(np.max(np.abs(heat_np - heat_plain))),
        "heat_numpy_with_1e-6_shift_vs_potpourri_plain_max_abs": float(np.max(np.abs(heat_np_shifted - heat_plain))),
        "heat_default_vs_plain_max_abs": float(np.max(np.abs(heat - heat_plain))),
        "heat_numpy_minus_exact_rel_mean": None if exact is None else float(np.mean(np.abs(heat_np - exact)[far] / exact[far])),
        "eigen_residual_max": float(resid.max()),
        "eigen_m_orthonormality_defect": ortho_defect,
        "body_eigen_residual_max": float(residB.max()),
        "body_eigen_m_orthonormality_defect": orthoB,
    }
    assert checks["lambda0_abs"] < 1e-9, checks
    assert checks["hks_min"] > 0, checks
    assert abs(checks["gauss_bonnet_minus_4pi"]) < 1e-9, checks
    assert abs(float(lamB[0])) < 1e-9, lamB[:3]
    if exact is not None:
        assert checks["dijkstra_minus_exact_min"] > -1e-9, checks

    description = {
        "_about": "Independent reference numbers for symcorr-spectral, made by tools/reference/make_reference.py "
                  "with numpy/scipy (own cotan code), potpourri3d and pygeodesic. All arrays are indexed by the "
                  "vertex order of fixtures/spectral/ref_mesh.off (file order, 0-based). Floats are written with "
                  "Python's shortest round-trip repr; nothing is rounded. Units: the mesh is unitless (radius ~1); "
                  "areas in length^2, eigenvalues and curvature in 1/length^2, HKS in 1/length^2, times in length^2.",
        "mesh": "Path of the mesh the numbers refer to, relative to the repository root.",
        "vertices": "Number of vertices n of ref_mesh.off.",
        "triangles": "Number of triangles of ref_mesh.off.",
        "edges": "Number of undirected edges of ref_mesh.off (closed genus 0: V - E + F = 2).",
        "mesh_construction": "How ref_mesh.off was built (for humans; the OFF file is the source of truth).",
        "min_angle_deg": "Smallest interior triangle angle in degrees (no clamping of cotangents is needed).",
        "max_angle_deg": "Largest interior triangle angle in degrees (> 90 means some cotan weights may be negative).",
        "negative_cotan_weights": "Number of undirected edges whose cotan weight W_ij is negative (obtuse opposite angles).",
        "total_area": "Sum of triangle areas (= sum of mass).",
        "mass": "Lumped barycentric mass, length n: M_ii = (1/3) * sum of the areas of the triangles incident to i. M is diagonal.",
        "stiffness_convention": "L is the POSITIVE semi-definite cotan stiffness L = D - W, with W_ij = 1/2 (cot alpha_ij + cot beta_ij) "
                                "summed over the (one or two) triangles containing edge ij (alpha, beta = angles opposite the edge), "
                                "D_ii = sum_j W_ij. cot computed as (u.v)/|u x v| with no clamping. L is NOT divided by the mass.",
        "stiffness_diagonal": "Diagonal of L (= D_ii = sum_j W_ij), length n.",
        "stiffness_frobenius_norm": "Frobenius norm of L, sqrt(sum_ij L_ij^2).",
        "stiffness_row_sums_max_abs": "max_i |sum_j L_ij| (should be ~1e-15: L 1 = 0).",
        "stiffness_symmetry_max_abs": "max |L - L^T| (0 by construction).",
        "eigenvalues": f"The {K_REF} smallest eigenvalues of the generalised problem L phi = lambda M phi, ascending, "
                       f"from scipy.sparse.linalg.eigsh(L, k={K_REF}, M=M, sigma={SIGMA}, which='LM', v0=numpy.random.default_rng(12345).standard_normal(n)) "
                       "(ARPACK shift-invert, default tol=0 i.e. machine precision). eigenvalues[0] ~ 0 (constant mode). "
                       "For a unit sphere these would be l(l+1); this mesh is deformed so all are simple.",
        "eigenvalue_min_relative_gap": "min over i>=1 of (lambda_{i+1} - lambda_i)/lambda_{i+1} among the 31 smallest: all 30 "
                                       "eigenvalues (and the 30/31 boundary) are simple, so eigenvectors and HKS are well defined.",
        "eigenvalue_gap_after_30": "(lambda_30 - lambda_29)/lambda_30 (0-based): the truncation of the HKS sum is not inside a cluster.",
        "eigen_residual_max": "max_i ||L phi_i - lambda_i M phi_i|| / ||M phi_i|| of the scipy pairs (quality of the reference).",
        "eigen_m_orthonormality_defect": "max |Phi^T M Phi - I| of the eigenvectors scipy returned.",
        "hks_times": f"{N_HKS_TIMES} diffusion times, log-spaced (np.exp(np.linspace(log t_min, log t_max, {N_HKS_TIMES}))) "
                     "between t_min = 4 ln(10) / eigenvalues[29] and t_max = 4 ln(10) / eigenvalues[1] (Sun et al. 2009 range).",
        "hks": f"Heat kernel signature, n rows x {N_HKS_TIMES} columns (hks[v][j] is vertex v at hks_times[j]): "
               f"k_t(v,v) = sum_{{i=0}}^{{{K_REF - 1}}} exp(-eigenvalues[i] t) phi_i(v)^2, phi_i M-orthonormal "
               "(phi_i^T M phi_i = 1), all 30 pairs INCLUDING the constant one (phi_0 = 1/sqrt(total_area)). Not scale-normalised.",
        "gaussian_curvature": "Per vertex, paper eq. 4: gc(v) = 3 (2 pi - sum of the corner angles at v) / (sum of the areas of the "
                              "triangles incident to v). Angles by atan2(|u x w|, u.w).",
        "gauss_bonnet_sum": "sum_v gc(v) * (sum of incident areas(v) / 3) = sum_v (2 pi - angle sum) = 4 pi for a closed genus-0 mesh.",
        "dijkstra_source": "Source vertex index (0) for dijkstra, heat_geodesic, heat_geodesic_plain, heat_geodesic_numpy, exact_geodesic.",
        "dijkstra": "Shortest path length from dijkstra_source to every vertex over mesh edges weighted by Euclidean edge length "
                    "(scipy.sparse.csgraph.dijkstra, undirected). Paper eq. 5-6.",
        "heat_geodesic": "potpourri3d.MeshHeatMethodDistanceSolver(V, F) with DEFAULTS (t_coef=1.0, use_robust=True) from dijkstra_source. "
                         "use_robust=True means geometry-central builds operators on an intrinsic mollification (relative 1e-5) "
                         "+ intrinsic Delaunay flip of the mesh, t = t_coef * (mean intrinsic edge length)^2, heat system M + t L, "
                         "Poisson system L + 1e-6 I, result shifted so the source is 0. Expect only a few % agreement with exact.",
        "heat_geodesic_plain": "Same solver with use_robust=False: plain cotan L and lumped mass of the input mesh, "
                               "t = (mean edge length of the input mesh)^2 = heat_t, Poisson system L + 1e-6 I, shifted to 0 at the source.",
        "heat_geodesic_numpy": "Our own numpy heat method (Crane, Weischedel, Wardetzky 2013) with exactly the operators above: "
                               "solve (M + heat_t L) u = e_src; per face X = -grad u/|grad u|; integrated divergence "
                               "div(i) = 1/2 sum over incident faces (cot theta_1 (e_1 . X) + cot theta_2 (e_2 . X)); "
                               "solve L phi = -div with phi(src) = 0 pinned (exact null-space handling, no 1e-6 shift). "
                               "This is the variant a Rust plain heat method should match to ~1e-9 relative (it differs from "
                               "heat_geodesic_plain only by potpourri3d's 1e-6 I regularisation).",
        "heat_t": "The heat-method time used for heat_geodesic_plain and heat_geodesic_numpy: (mean Euclidean edge length)^2.",
        "mean_edge_length": "Mean Euclidean length of the undirected edges of ref_mesh.off.",
        "exact_geodesic": "Exact polyhedral geodesic distance (MMP, Surazhsky et al. 2005 / Kirsanov implementation, pygeodesic "
                          "PyGeodesicAlgorithmExact) from dijkstra_source to every vertex. null if pygeodesic was unavailable.",
        "checks": "Sanity numbers computed by the script (lambda_0, HKS minimum, Gauss-Bonnet defect, geodesic comparisons; "
                  "rel = relative to exact_geodesic, excluding the source).",
        "body_mesh": "Path of the body mesh, relative to the repository root (MakeHuman body, decimetres).",
        "body_vertices": "Number of vertices of body.off.",
        "body_triangles": "Number of triangles of body.off (after fan triangulation; it is already triangles).",
        "body_total_area": "Total area of body.off in dm^2.",
        "body_eigenvalues": f"The {K_BODY} smallest eigenvalues of L phi = lambda M phi on fixtures/body/body.off, same operators "
                            f"and same eigsh call (k={K_BODY}, sigma={SIGMA}, same v0 recipe), ascending, in 1/dm^2.",
        "body_eigen_residual_max": "max_i ||L phi_i - lambda_i M phi_i|| / ||M phi_i|| for the body pairs.",
        "generator": "Versions and platform that produced the file.",
    }

    out = {
        "description": description,
        "mesh": "fixtures/spectral/ref_mesh.off",
        "mesh_construction": "class-I geodesic sphere, frequency 10 (10*10^2+2 vertices), icosahedron rotated by Rodrigues(axis "
                             "(0.3,-0.7,0.5) normalised, angle 0.9 rad), projected to the unit sphere, then each point p scaled by "
                             "1 + 0.2 sin(2x+0.3) cos(3y+0.5) + 0.1 z^2 + 0.05 x y.",
        "vertices": n,
        "triangles": int(len(F)),
        "edges": int(n_edges),
        "min_angle_deg": min_angle_deg,
        "max_angle_deg": max_angle_deg,
        "negative_cotan_weights": n_negative_weights,
        "total_area": total_area,
        "mass": m.tolist(),
        "stiffness_convention": "L = D - W, positive semi-definite, W_ij = 1/2 (cot alpha_ij + cot beta_ij)",
        "stiffness_diagonal": stiffness_diagonal.tolist(),
        "stiffness_frobenius_norm": stiffness_frobenius,
        "stiffness_row_sums_max_abs": float(np.abs(row_sums).max()),
        "stiffness_symmetry_max_abs": sym_defect,
        "eigenvalues": lam.tolist(),
        "eigenvalue_min_relative_gap": min_rel_gap,
        "eigenvalue_gap_after_30": gap_after_30,
        "eigen_residual_max": float(resid.max()),
        "eigen_m_orthonormality_defect": ortho_defect,
        "hks_times": hks_times.tolist(),
        "hks": hks.tolist(),
        "gaussian_curvature": gc.tolist(),
        "gauss_bonnet_sum": gauss_bonnet,
        "dijkstra_source": DIJKSTRA_SOURCE,
        "dijkstra": dij.tolist(),
        "heat_geodesic": np.asarray(heat, dtype=np.float64).tolist(),
        "heat_geodesic_plain": np.asarray(heat_plain, dtype=np.float64).tolist(),
        "heat_geodesic_numpy": heat_np.tolist(),
        "heat_t": t_heat,
        "mean_edge_length": mean_edge,
        "exact_geodesic": None if exact is None else exact.tolist(),
        "checks": checks,
        "body_mesh": "fixtures/body/body.off",
        "body_vertices": int(len(VB)),
        "body_triangles": int(len(FB)),
        "body_total_area": body_area,
        "body_eigenvalues": lamB.tolist(),
        "body_eigen_residual_max": float(residB.max()),
        "generator": {
            "script": "tools/reference/make_reference.py",
            "python": platform.python_version(),
            "numpy": np.__version__,
            "scipy": scipy.__version__,
            "potpourri3d": _version("potpourri3d"),
            "pygeodesic": _version("pygeodesic"),
            "platform": platform.platform(),
        },
    }
    assert set(out) <= set(description) | {"description"}, set(out) - set(description)
    assert set(description) - {"_about"} <= set(out), set(description) - set(out)
    tmp = JSON_PATH + ".tmp"
    with open(tmp, "w", encoding="ascii") as fh:
        json.dump(out, fh, indent=1, allow_nan=False)
        fh.write("\n")
    os.replace(tmp, JSON_PATH)

    # --- summary ----------------------------------------------------------------------------------
    print(f"ref mesh: {n} vertices, {len(F)} triangles, {n_edges} edges, area {total_area:.6f}, "
          f"angles {min_angle_deg:.2f}..{max_angle_deg:.2f} deg, {n_negative_weights} negative cotan weights")
    print(f"L: row sums max |.| {np.abs(row_sums).max():.2e}, symmetry {sym_defect:.1e}")
    print(f"eigenvalues (k={K_REF}): {lam[0]:.3e}, {lam[1]:.10f}, {lam[2]:.10f}, ..., {lam[-1]:.10f}")
    print(f"  min relative gap {min_rel_gap:.3e} (lambda_{min_gap_pair}, lambda_{min_gap_pair + 1}), gap after 30 {gap_after_30:.3e}, k30 vs k31 agree {agree_k30_k31:.1e}, "
          f"residual max {resid.max():.1e}, M-orthonormality defect {ortho_defect:.1e}")
    print(f"HKS times {', '.join(f'{t:.4g}' for t in hks_times)}; HKS min {hks.min():.4e} max {hks.max():.4e}")
    print(f"Gauss-Bonnet: sum gc*area/3 = {gauss_bonnet:.15f} (4 pi = {4 * math.pi:.15f})")
    print(f"geodesics from {DIJKSTRA_SOURCE}: dijkstra max {dij.max():.6f}, heat(default) max {heat.max():.6f}, "
          f"heat(plain) max {heat_plain.max():.6f}" + ("" if exact is None else f", exact max {exact.max():.6f}"))
    for k, v in checks.items():
        print(f"  {k}: {v}")
    print(f"body: {len(VB)} vertices, area {body_area:.4f} dm^2, lambda[0..3] {lamB[:4]}, lambda[49] {lamB[-1]:.8f}, "
          f"residual max {residB.max():.1e}, {t_body:.2f} s")
    print(f"wrote {os.path.relpath(MESH_PATH, ROOT)} and {os.path.relpath(JSON_PATH, ROOT)} "
          f"({os.path.getsize(JSON_PATH) / 1024:.0f} KiB) in {time.time() - t_start:.1f} s")


def _version(pkg):
    try:
        from importlib.metadata import version
        return version(pkg)
    except Exception:  # pragma: no cover - informational only
        return None


if __name__ == "__main__":
    main()
