"""Small, dependency-light mesh helpers shared by the reference scripts.

Everything here is written from the textbook formulas with numpy/scipy only,
independently of the Rust crates, so that the numbers it produces can serve
as an outside reference for symcorr-spectral.
"""

import numpy as np
import scipy.sparse as sp


def read_off(path):
    """Read an ASCII OFF file: optional '#' comments, header 'OFF', counts, vertices, faces.

    Polygons with more than three corners are fan-triangulated (v0, vi, vi+1),
    the same convention as DESIGN.md. Returns (V float64 n x 3, F int64 m x 3).
    """
    tokens = []
    with open(path, "r", encoding="ascii") as fh:
        for line in fh:
            line = line.split("#", 1)[0].strip()
            if line:
                tokens.extend(line.split())
    if not tokens or tokens[0] != "OFF":
        raise ValueError(f"{path}: missing OFF header")
    pos = 1
    nv, nf = int(tokens[pos]), int(tokens[pos + 1])
    pos += 3  # third count (edges) is ignored
    V = np.array(tokens[pos:pos + 3 * nv], dtype=np.float64).reshape(nv, 3)
    pos += 3 * nv
    tris = []
    for _ in range(nf):
        k = int(tokens[pos])
        idx = [int(t) for t in tokens[pos + 1:pos + 1 + k]]
        pos += 1 + k
        for i in range(1, k - 1):
            tris.append((idx[0], idx[i], idx[i + 1]))
    F = np.array(tris, dtype=np.int64)
    if F.min() < 0 or F.max() >= nv:
        raise ValueError(f"{path}: face index out of range")
    return V, F


def write_off(path, V, F, comments=()):
    """Write ASCII OFF with Python's shortest round-trip float repr (bit-exact on re-read)."""
    with open(path, "w", encoding="ascii", newline="\n") as fh:
        fh.write("OFF\n")
        for c in comments:
            fh.write(f"# {c}\n")
        fh.write(f"{len(V)} {len(F)} 0\n")
        for x, y, z in V:
            fh.write(f"{float(x)!r} {float(y)!r} {float(z)!r}\n")
        for a, b, c in F:
            fh.write(f"3 {int(a)} {int(b)} {int(c)}\n")


def triangle_areas(V, F):
    e1 = V[F[:, 1]] - V[F[:, 0]]
    e2 = V[F[:, 2]] - V[F[:, 0]]
    return 0.5 * np.linalg.norm(np.cross(e1, e2), axis=1)


def corner_cotangents(V, F):
    """cot of the interior angle at each corner: column k is the angle at F[:, k]."""
    cots = np.empty(F.shape, dtype=np.float64)
    for k in range(3):
        i, j, l = F[:, k], F[:, (k + 1) % 3], F[:, (k + 2) % 3]
        u = V[j] - V[i]
        w = V[l] - V[i]
        # cot = cos/sin = (u.w) / |u x w|
        cots[:, k] = np.einsum("ij,ij->i", u, w) / np.linalg.norm(np.cross(u, w), axis=1)
    return cots


def corner_angles(V, F):
    ang = np.empty(F.shape, dtype=np.float64)
    for k in range(3):
        i, j, l = F[:, k], F[:, (k + 1) % 3], F[:, (k + 2) % 3]
        u = V[j] - V[i]
        w = V[l] - V[i]
        ang[:, k] = np.arctan2(np.linalg.norm(np.cross(u, w), axis=1), np.einsum("ij,ij->i", u, w))
    return ang


def cotan_laplacian(V, F):
    """Positive semi-definite cotan stiffness L = D - W, W_ij = 1/2 (cot a_ij + cot b_ij).

    The angle at corner k is opposite the edge (F[:, k+1], F[:, k+2]); each triangle
    adds 1/2 cot(angle) to that edge's weight. No clamping.
    """
    n = len(V)
    cots = corner_cotangents(V, F)
    rows, cols, vals = [], [], []
    for k in range(3):
        a, b = F[:, (k + 1) % 3], F[:, (k + 2) % 3]
        w = 0.5 * cots[:, k]
        rows += [a, b]
        cols += [b, a]
        vals += [w, w]
    W = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)).tocsr()
    W.sum_duplicates()
    d = np.asarray(W.sum(axis=1)).ravel()
    L = (sp.diags(d) - W).tocsc()
    return L


def lumped_mass(V, F):
    """Barycentric lumped mass: each vertex gets one third of the area of every incident triangle."""
    n = len(V)
    A = triangle_areas(V, F)
    m = np.zeros(n)
    for k in range(3):
        np.add.at(m, F[:, k], A / 3.0)
    return m


def edges(F):
    """Unique undirected edges (i < j) as an int64 array, sorted."""
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    e = np.sort(e, axis=1)
    return np.unique(e, axis=0)
