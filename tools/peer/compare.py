#!/usr/bin/env python3
"""Side-by-side comparison of symcorr with a functional-map peer (pyFM, PyPI `pyfmaps`).

Usage:
    tools/peer/.venv/bin/python tools/peer/compare.py DATASET [--pairs FILE]
        [--symcorr PATH_TO_BINARY] [--mode dense|sparse] [--eval-samples N] [--json OUT]

DATASET is a folder in DESIGN.md's benchmark layout: meshes/NAME.{off,ply,obj} with one vertex
order across the folder (ground truth is the identity), joints/NAME.json (used by symcorr only),
optional mirror.txt (line i: the vertex mirror-symmetric to vertex i), pairs.txt
(`template target` per line), and optionally truth/NAME.txt for targets in another vertex order
(single-view scans, finer triangulations; symcorr's dataset extension): per target vertex its
common-order id or -1. Such pairs are scored on the template points the target sees, with errors
divided by sqrt(template area), exactly as `symcorr bench` does.

For every pair the peer computes a dense template → target map with pyFM's standard pipeline
(WKS descriptors → functional map by descriptor preservation + Laplacian commutativity +
descriptor commutativity [+ orientation term] → ZoomOut → point-to-point map). The same run calls
`symcorr bench DATASET --mode MODE --json … --out-dir …`, and BOTH tools' maps are scored by the
metric implemented here, independently of the Rust code (DESIGN.md, Metrics):

    e = g_target(q, q*) / sqrt(area(target))

with g the shortest path along mesh edges (scipy.sparse.csgraph.dijkstra over the target's edge
graph, Euclidean edge lengths), and the flip rate = fraction of matches strictly closer (in g) to
mirror(q*) than to q*, counted only where g(q*, mirror(q*)) > 0.1·sqrt(area(target)).

See README.md next to this file for what is timed and the parameters.
"""

import os

# Two threads for every BLAS/OpenMP pool (and for symcorr's rayon pool): the machine has 2 cores
# and both tools must be measured under the same budget. Must happen before numpy is imported.
for _var in (
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "NUMEXPR_NUM_THREADS",
    "VECLIB_MAXIMUM_THREADS",
    "RAYON_NUM_THREADS",
):
    os.environ.setdefault(_var, "2")

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import shutil  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import scipy.sparse as sp  # noqa: E402
from scipy.sparse.csgraph import dijkstra  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
MESH_EXTS = (".ply", ".off", ".obj")


# --------------------------------------------------------------------------------------------
# Dataset reading (vertex order of the file is kept: it is the ground truth)
# --------------------------------------------------------------------------------------------


def _fan(poly):
    return [(poly[0], poly[i], poly[i + 1]) for i in range(1, len(poly) - 1)]


def read_off(path):
    toks = []
    with open(path) as f:
        for line in f:
            line = line.split("#", 1)[0].strip()
            if line:
                toks.extend(line.split())
    if not toks or not toks[0].endswith("OFF"):
        raise ValueError(f"{path}: not an OFF file")
    i = 1
    if toks[0] != "OFF":  # e.g. "COFF", "NOFF": extra per-vertex values we do not read
        raise ValueError(f"{path}: only plain OFF is supported, got {toks[0]}")
    nv, nf = int(toks[i]), int(toks[i + 1])
    i += 3
    verts = np.array(toks[i : i + 3 * nv], dtype=float).reshape(nv, 3)
    i += 3 * nv
    faces = []
    for _ in range(nf):
        n = int(toks[i])
        faces.extend(_fan([int(t) for t in toks[i + 1 : i + 1 + n]]))
        i += 1 + n
    return verts, np.array(faces, dtype=np.int64).reshape(-1, 3)


def read_obj(path):
    verts, faces = [], []
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                verts.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                idx = []
                for p in parts[1:]:
                    k = int(p.split("/")[0])
                    idx.append(k - 1 if k > 0 else len(verts) + k)
                faces.extend(_fan(idx))
    return np.array(verts, dtype=float), np.array(faces, dtype=np.int64).reshape(-1, 3)


def read_ply(path):
    from plyfile import PlyData

    ply = PlyData.read(str(path))
    v = ply["vertex"]
    verts = np.stack([np.asarray(v["x"], float), np.asarray(v["y"], float), np.asarray(v["z"], float)], 1)
    fe = ply["face"]
    name = "vertex_indices" if "vertex_indices" in fe.data.dtype.names else "vertex_index"
    polys = fe[name]
    try:
        faces = np.vstack(polys).astype(np.int64)
        if faces.shape[1] != 3:
            raise ValueError
    except ValueError:
        faces = np.array([t for p in polys for t in _fan(list(p))], dtype=np.int64)
    return verts, faces


def read_mesh(path):
    ext = path.suffix.lower()
    if ext == ".ply":
        return read_ply(path)
    if ext == ".off":
        return read_off(path)
    if ext == ".obj":
        return read_obj(path)
    raise ValueError(f"{path}: unsupported mesh format")


def find_mesh(dataset, name):
    for ext in MESH_EXTS:
        p = dataset / "meshes" / f"{name}{ext}"
        if p.exists():
            return p
    raise FileNotFoundError(f"{dataset}/meshes/{name}.{{off,ply,obj}} not found")


def read_pairs(path):
    pairs = []
    with open(path) as f:
        for lineno, line in enumerate(f, 1):
            line = line.split("#", 1)[0].strip()
            if not line:
                continue
            parts = line.split()
            if len(parts) != 2:
                raise ValueError(f"{path}:{lineno}: expected `template target`, got {line!r}")
            pairs.append((parts[0], parts[1]))
    return pairs


def read_mirror(dataset, n):
    p = dataset / "mirror.txt"
    if not p.exists():
        return None
    m = np.loadtxt(p, dtype=np.int64).reshape(-1)
    if len(m) != n or m.min() < 0 or m.max() >= n:
        raise ValueError(f"{p}: expected {n} vertex ids in [0, {n}), got {len(m)}")
    return m


# --------------------------------------------------------------------------------------------
# Independent metric (DESIGN.md, Metrics)
# --------------------------------------------------------------------------------------------


class TargetGeodesics:
    """Edge-graph shortest paths on one target mesh, with a per-source row cache."""

    def __init__(self, verts, faces):
        e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
        e = np.sort(e, axis=1)
        e = np.unique(e, axis=0)
        w = np.linalg.norm(verts[e[:, 0]] - verts[e[:, 1]], axis=1)
        n = len(verts)
        self.graph = sp.coo_matrix((w, (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
        cr = np.cross(verts[faces[:, 1]] - verts[faces[:, 0]], verts[faces[:, 2]] - verts[faces[:, 0]])
        self.sqrt_area = float(np.sqrt(0.5 * np.linalg.norm(cr, axis=1).sum()))
        self.rows = {}

    def ensure(self, sources):
        need = sorted(set(int(s) for s in sources) - self.rows.keys())
        for start in range(0, len(need), 256):
            chunk = need[start : start + 256]
            d = dijkstra(self.graph, directed=False, indices=chunk).astype(np.float32)
            for s, row in zip(chunk, d):
                self.rows[s] = row

    def dist(self, a, b):
        """g(a_i, b_i) for sources a (rows must be cached)."""
        return np.array([self.rows[int(x)][int(y)] for x, y in zip(a, b)], dtype=float)


def read_truth(dataset, name):
    """truth/NAME.txt (a target not in the common vertex order: a scan or a finer mesh): the
    common-order id per vertex, -1 for none; None when the file does not exist."""
    p = dataset / "truth" / f"{name}.txt"
    if not p.exists():
        return None
    return np.loadtxt(p, dtype=np.int64).reshape(-1)


def common_to_target(truth, n_common):
    """First target vertex per common id (-1 where none), as symcorr's bench does."""
    out = np.full(n_common, -1, dtype=np.int64)
    for v in range(len(truth) - 1, -1, -1):  # reversed, so the first vertex wins
        c = truth[v]
        if 0 <= c < n_common:
            out[c] = v
    return out


def score(geo, template_ids, target_ids, mirror, to_target=None, sqrt_area=None):
    """Per-match normalised errors and flip flags (NaN where the flip is not counted).

    Without `to_target` the ground truth is the identity. With it (a target with a truth file),
    the truth of template vertex p is target vertex to_target[p]; matches of template points
    the target does not see are dropped, flips are counted only where the mirror image is seen,
    and errors are divided by `sqrt_area` (the template's), as symcorr's bench does."""
    p = np.asarray(template_ids)
    q = np.asarray(target_ids)
    norm = geo.sqrt_area if sqrt_area is None else sqrt_area
    if to_target is None:
        qstar = p
        mq = mirror[p] if mirror is not None else None
    else:
        seen = to_target[p] >= 0
        p, q = p[seen], q[seen]
        qstar = to_target[p]
        mq = to_target[mirror[p]] if mirror is not None else None
    sources = set(qstar.tolist())
    if mq is not None:
        sources |= set(int(x) for x in mq if x >= 0)
    geo.ensure(sources)
    err = geo.dist(qstar, q) / norm
    flips = None
    if mq is not None:
        ok = mq >= 0
        mq_safe = np.where(ok, mq, qstar)
        d_sym = geo.dist(qstar, mq_safe) / norm
        d_mirror = geo.dist(mq_safe, q) / norm
        counted = ok & (d_sym > 0.1)
        flips = np.where(counted, (d_mirror < err).astype(float), np.nan)
    return err, flips


def summarise(errs, flips):
    e = np.concatenate(errs) if errs else np.zeros(0)
    out = {
        "matches_scored": int(len(e)),
        "mean_error": float(e.mean()) if len(e) else float("nan"),
        "within_0.05": float((e <= 0.05).mean()) if len(e) else float("nan"),
        "within_0.10": float((e <= 0.10).mean()) if len(e) else float("nan"),
        "flip_rate": float("nan"),
        "flips_counted": 0,
    }
    fl = [f for f in flips if f is not None]
    if fl:
        f = np.concatenate(fl)
        f = f[~np.isnan(f)]
        out["flips_counted"] = int(len(f))
        if len(f):
            out["flip_rate"] = float(f.mean())
    return out


# --------------------------------------------------------------------------------------------
# The peer: pyFM (PyPI package `pyfmaps`)
# --------------------------------------------------------------------------------------------


def peer_variants(args):
    v = [("pyFM WKS+orient", args.w_orient)]
    if args.peer_plain:
        v.append(("pyFM WKS, no orient", 0.0))
    return v


def run_peer(tpl, tgt, args):
    """Dense template → target maps for each variant, with wall-clock seconds per variant.

    Timed: building both TriMesh objects (area normalisation), cotan Laplacian + lumped mass,
    k_process eigenpairs of each mesh (scipy eigsh, shift-invert), WKS descriptors, functional-map
    fit, ZoomOut, final point-to-point map. Not timed: reading the mesh files. Spectra are not
    cached across pairs. The preprocessing (Laplacians, eigenpairs, descriptors) is shared by the
    variants and its time is added to each variant's own fit + ZoomOut + p2p time.
    """
    from pyFM.functional import FunctionalMapping
    from pyFM.mesh import TriMesh

    t0 = time.perf_counter()
    # mesh1 = target, mesh2 = template: pyFM's p2p_21 then gives, for every template vertex,
    # a target vertex — the template → target map the metric asks for.
    m_tgt = TriMesh(tgt[0].copy(), tgt[1].copy(), area_normalize=True, center=True)
    m_tpl = TriMesh(tpl[0].copy(), tpl[1].copy(), area_normalize=True, center=True)
    model = FunctionalMapping(m_tgt, m_tpl)
    model.preprocess(
        n_descr=args.n_descr,
        descr_type=args.descr,
        subsample_step=args.subsample_step,
        k_process=args.k_process,
        k_descr=args.k_descr,
    )
    t_pre = time.perf_counter() - t0
    out = {}
    for name, w_orient in peer_variants(args):
        t1 = time.perf_counter()
        model.fit(K=args.k_fit, w_descr=1.0, w_lap=1e-1, w_dcomm=1.0, w_orient=w_orient)
        t2 = time.perf_counter()
        fm_zo = model.zoomout_refine(nit=args.zo_nit, step=args.zo_step)
        p2p = model.get_p2p(fm_zo)  # (n_template,) target vertex per template vertex
        t3 = time.perf_counter()
        out[name] = (np.asarray(p2p, dtype=np.int64), t_pre + t3 - t1,
                     {"preprocess": t_pre, "fit": t2 - t1, "zoomout_p2p": t3 - t2})
    return out


def peer_cache_key(tpl, tgt, args):
    """Content hash of both meshes and every peer parameter."""
    import hashlib

    h = hashlib.sha256()
    for v, f in (tpl, tgt):
        h.update(np.ascontiguousarray(v).tobytes())
        h.update(np.ascontiguousarray(f).tobytes())
    params = [args.descr, args.n_descr, args.subsample_step, args.k_descr, args.k_process,
              args.k_fit, args.zo_nit, args.zo_step, peer_variants(args)]
    h.update(repr(params).encode())
    return h.hexdigest()[:24]


# --------------------------------------------------------------------------------------------
# symcorr
# --------------------------------------------------------------------------------------------


def run_symcorr(binary, dataset, pairs_file, mode, out_dir, method="articulated"):
    """Run `symcorr bench`; returns (summary dict or None, message)."""
    if binary is None or not Path(binary).is_file():
        return None, f"symcorr binary not found at {binary} (build: cargo build --release -p symcorr)"
    js = out_dir / "bench.json"
    cmd = [str(binary), "bench", str(dataset), "--pairs", str(pairs_file), "--mode", mode,
           "--method", method, "--json", str(js), "--out-dir", str(out_dir)]
    print("running:", " ".join(cmd), flush=True)
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True)
    except OSError as e:
        return None, f"symcorr could not be started: {e}"
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        tail = (proc.stderr or proc.stdout).strip().splitlines()[-5:]
        return None, f"symcorr bench failed (exit {proc.returncode}): " + " | ".join(tail)
    try:
        summary = json.loads(js.read_text())
    except (OSError, ValueError) as e:
        return None, f"symcorr bench wrote no readable JSON summary: {e}"
    summary["_wall_s"] = wall
    return summary, "ok"


def load_symcorr_pairs(out_dir, tpl, tgt):
    p = out_dir / f"{tpl}__{tgt}.json"
    if not p.exists():
        return None
    d = json.loads(p.read_text())
    arr = np.asarray([[int(a), int(b)] for a, b, *_ in d["pairs"]], dtype=np.int64).reshape(-1, 2)
    return arr


# --------------------------------------------------------------------------------------------
# Report
# --------------------------------------------------------------------------------------------


def machine_info():
    cpu = platform.processor() or "?"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"nproc": os.cpu_count(), "cpu": cpu, "threads_per_tool": int(os.environ["OMP_NUM_THREADS"])}


def fmt(x, pct=False):
    if x is None or (isinstance(x, float) and np.isnan(x)):
        return "—"
    return f"{100 * x:.2f} %" if pct else f"{x:.4f}"


def print_table(rows, info, header):
    cols = ["tool", "mean error", "flip rate", "within 0.05", "within 0.10", "s / pair", "scored"]
    lines = []
    for r in rows:
        lines.append([
            r["tool"],
            fmt(r.get("mean_error")),
            fmt(r.get("flip_rate"), pct=True),
            fmt(r.get("within_0.05"), pct=True),
            fmt(r.get("within_0.10"), pct=True),
            "—" if r.get("seconds_per_pair") is None else f"{r['seconds_per_pair']:.2f}",
            str(r.get("scored", "—")),
        ])
    w = [max(len(c), *(len(l[i]) for l in lines)) for i, c in enumerate(cols)]
    print()
    print(header)
    print(f"machine: {info['nproc']} cores ({info['cpu']}), {info['threads_per_tool']} threads per tool")
    print("  ".join(c.ljust(w[i]) for i, c in enumerate(cols)))
    print("  ".join("-" * w[i] for i in range(len(cols))))
    for l in lines:
        print("  ".join(v.ljust(w[i]) for i, v in enumerate(l)))


def add_peer_arguments(ap):
    """The peer's parameters (pyFM README's quickstart: K=30, WKS, subsample_step=2, ZoomOut
    nit=16 step=5) on an argparse parser; `python/examples/compare_pyfm.py` uses them too."""
    ap.add_argument("--descr", choices=["WKS", "HKS"], default="WKS")
    ap.add_argument("--n-descr", type=int, default=100)
    ap.add_argument("--subsample-step", type=int, default=2)
    ap.add_argument("--k-descr", type=int, default=128, help="eigenpairs behind the descriptors")
    ap.add_argument("--k-process", type=int, default=128, help="eigenpairs computed per mesh")
    ap.add_argument("--k-fit", type=int, default=30, help="functional map size before ZoomOut")
    ap.add_argument("--zo-nit", type=int, default=16)
    ap.add_argument("--zo-step", type=int, default=5)
    ap.add_argument("--w-orient", type=float, default=1.0)
    ap.add_argument("--peer-plain", action="store_true",
                    help="also run the peer without the orientation term (classic pipeline)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dataset", type=Path)
    ap.add_argument("--pairs", type=Path, help="pairs file (default: DATASET/pairs.txt)")
    ap.add_argument("--symcorr", type=Path, default=REPO / "target" / "release" / "symcorr",
                    help="symcorr binary (default: target/release/symcorr of this repository)")
    ap.add_argument("--mode", choices=["dense", "sparse"], default="dense",
                    help="symcorr bench mode (the peer is always dense)")
    ap.add_argument("--eval-samples", type=int, default=1000,
                    help="template vertices scored per pair: a seeded random sample, the same for "
                         "every pair and tool; 0 = every vertex (slow)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--limit", type=int, default=0, help="only the first N pairs (0 = all)")
    ap.add_argument("--json", type=Path, help="also write the table and per-pair rows here")
    ap.add_argument("--keep", type=Path, help="keep symcorr's bench output in this folder")
    ap.add_argument("--symcorr-method", choices=["articulated", "refined", "paper"], default="articulated",
                    help="symcorr bench --method (default: articulated, symcorr's default)")
    ap.add_argument("--no-symcorr", action="store_true", help="run the peer only")
    ap.add_argument("--peer-cache", type=Path,
                    help="reuse peer maps (and their measured seconds) for identical meshes and "
                         "parameters, e.g. a dataset that differs from another only in its joints")
    add_peer_arguments(ap)
    args = ap.parse_args()

    dataset = args.dataset.resolve()
    pairs_file = (args.pairs or dataset / "pairs.txt").resolve()
    pairs = read_pairs(pairs_file)
    if args.limit:
        pairs = pairs[: args.limit]
    kmax = args.k_fit + args.zo_nit * args.zo_step
    if kmax > max(args.k_process, args.k_descr):
        sys.exit(f"ZoomOut ends at {kmax} eigenfunctions but only {args.k_process} are computed")

    names = sorted({n for p in pairs for n in p})
    meshes = {n: read_mesh(find_mesh(dataset, n)) for n in names}
    truths = {n: t for n in names if (t := read_truth(dataset, n)) is not None}
    nverts = {len(meshes[n][0]) for n in names if n not in truths}
    if len(nverts) != 1:
        sys.exit(f"{dataset}: meshes have different vertex counts {sorted(nverts)}; ground truth "
                 "is the identity, so they must share one vertex order (or have truth/NAME.txt)")
    n = nverts.pop()
    for name, t in truths.items():
        if len(t) != len(meshes[name][0]):
            sys.exit(f"{dataset}/truth/{name}.txt: {len(t)} lines for {len(meshes[name][0])} vertices")
    mirror = read_mirror(dataset, n)
    rng = np.random.default_rng(args.seed)
    sample = np.arange(n) if args.eval_samples <= 0 or args.eval_samples >= n else \
        np.sort(rng.choice(n, size=args.eval_samples, replace=False))
    info = machine_info()

    # symcorr first (one subprocess for all pairs), so a failing build is reported early.
    sym_summary, sym_dir, tmp, sym_load = None, None, None, None
    if args.no_symcorr:
        sym_msg = "symcorr skipped (--no-symcorr)"
    else:
        if args.keep:
            sym_dir = args.keep.resolve()
            sym_dir.mkdir(parents=True, exist_ok=True)
        else:
            tmp = tempfile.mkdtemp(prefix="symcorr-peer-")
            sym_dir = Path(tmp)
        tmp_pairs = sym_dir / "pairs.txt"
        tmp_pairs.write_text("".join(f"{a} {b}\n" for a, b in pairs))
        sym_load = os.getloadavg()[0]
        sym_summary, sym_msg = run_symcorr(args.symcorr, dataset, tmp_pairs, args.mode, sym_dir,
                                           args.symcorr_method)
    if sym_summary is None:
        print(f"NOTE: {sym_msg} — the table has the peer only.", flush=True)
    else:
        print(f"symcorr bench done in {sym_summary['_wall_s']:.1f} s", flush=True)

    # The peer, pair by pair.
    peer_maps, peer_secs, peer_breakdown = {}, {}, {}
    peer_pair_secs, peer_from_cache = {}, {}  # per (tool, template, target); per (template, target)
    warnings.filterwarnings("ignore", category=DeprecationWarning)
    cached_pairs = 0
    load_before = os.getloadavg()
    for i, (a, b) in enumerate(pairs):
        res, key = None, None
        if args.peer_cache:
            key = peer_cache_key(meshes[a], meshes[b], args)
            cf = args.peer_cache / f"{key}.npz"
            if cf.exists():
                z = np.load(cf, allow_pickle=False)
                meta = json.loads(str(z["meta"]))
                res = {nm: (z[f"p2p{j}"], meta[nm]["seconds"], meta[nm]["breakdown"])
                       for j, nm in enumerate(meta["order"])}
                cached_pairs += 1
        peer_from_cache[(a, b)] = res is not None
        if res is None:
            res = run_peer(meshes[a], meshes[b], args)
            if args.peer_cache:
                args.peer_cache.mkdir(parents=True, exist_ok=True)
                meta = {"order": list(res), **{nm: {"seconds": r[1], "breakdown": r[2]}
                                               for nm, r in res.items()}}
                np.savez(args.peer_cache / f"{key}.npz", meta=json.dumps(meta),
                         **{f"p2p{j}": r[0] for j, r in enumerate(res.values())})
        for name, (p2p, secs, brk) in res.items():
            peer_maps[(name, a, b)] = p2p
            peer_secs.setdefault(name, []).append(secs)
            peer_pair_secs[(name, a, b)] = secs
            peer_breakdown.setdefault(name, []).append(brk)
        print(f"[{i + 1}/{len(pairs)}] peer {a} -> {b}: "
              + ", ".join(f"{k} {v[1]:.1f} s ("
                          + ", ".join(f"{s} {x:.1f}" for s, x in v[2].items()) + ")"
                          for k, v in res.items())
              + (" (from --peer-cache)" if peer_from_cache[(a, b)] else ""), flush=True)
    load_after = os.getloadavg()

    # Scoring, grouped by target so one target's geodesic rows are cached at a time.
    tools = [name for name, _ in peer_variants(args)]
    if sym_summary is not None:
        tools.append("symcorr")
    errs = {t: [] for t in tools}
    flips = {t: [] for t in tools}
    per_pair = []
    missing_sym = []
    by_target = {}
    for a, b in pairs:
        by_target.setdefault(b, []).append(a)
    for b, templates in by_target.items():
        geo = TargetGeodesics(*meshes[b])
        to_target = common_to_target(truths[b], n) if b in truths else None
        for a in templates:
            tpl_sqrt_area = TargetGeodesics(*meshes[a]).sqrt_area if to_target is not None else None
            sym = load_symcorr_pairs(sym_dir, a, b) if sym_summary is not None else None
            if sym_summary is not None and sym is None:
                missing_sym.append(f"{a}__{b}")
            if args.mode == "sparse" and sym is not None:
                ids = np.unique(sym[:, 0])  # score both tools on symcorr's sparse sample
            else:
                ids = sample
            row = {"template": a, "target": b}
            for t in tools:
                if t == "symcorr":
                    if sym is None:
                        continue
                    lookup = dict(zip(sym[:, 0].tolist(), sym[:, 1].tolist()))
                    keep = np.array([i for i in ids if int(i) in lookup], dtype=np.int64)
                    tgt_ids = np.array([lookup[int(i)] for i in keep], dtype=np.int64)
                else:
                    keep = ids
                    tgt_ids = peer_maps[(t, a, b)][ids]
                e, f = score(geo, keep, tgt_ids, mirror, to_target, tpl_sqrt_area)
                errs[t].append(e)
                flips[t].append(f)
                row[t] = {"mean_error": float(e.mean()) if len(e) else None,
                          "flip_rate": None if f is None or np.all(np.isnan(f)) else float(np.nanmean(f))}
                if t != "symcorr":
                    # Seconds of this pair's peer run, and whether it came from --peer-cache
                    # (then the seconds are those measured when it was computed).
                    row[t]["seconds"] = peer_pair_secs[(t, a, b)]
                    row[t]["from_cache"] = peer_from_cache[(a, b)]
            per_pair.append(row)
        del geo

    rows = []
    for t in tools:
        s = summarise(errs[t], flips[t])
        if t == "symcorr":
            secs = sym_summary.get("seconds_per_pair")
            label = f"symcorr {args.symcorr_method} ({args.mode}, scored here)"
        else:
            secs = float(np.mean(peer_secs[t]))
            label = t
        rows.append({"tool": label, **s, "seconds_per_pair": secs, "scored": s["matches_scored"]})
    if sym_summary is not None:
        rows.append({
            "tool": "symcorr (bench's own metric)",
            "mean_error": sym_summary.get("mean_error"),
            "flip_rate": sym_summary.get("flip_rate"),
            "within_0.05": sym_summary.get("within_0.05"),
            "within_0.10": sym_summary.get("within_0.10"),
            "seconds_per_pair": sym_summary.get("seconds_per_pair"),
            "scored": "all",
        })

    header = (f"dataset {dataset} — {len(pairs)} pairs, {n} vertices per mesh; scored on "
              + (f"{len(sample)} seeded-random template vertices per pair"
                 if args.mode == "dense" or sym_summary is None else "symcorr's sparse sample")
              + "; error = edge-graph Dijkstra distance / sqrt(target area)"
              + ("" if mirror is not None else "; no mirror.txt, so no flip rate"))
    print_table(rows, info, header)
    if sym_summary is None:
        print(f"\nsymcorr: not in the table — {sym_msg}")
    else:
        wall = sym_summary.get("wall_seconds", sym_summary["_wall_s"])
        print(f"\nsymcorr: s / pair is bench's `seconds_per_pair` (its own definition: "
              f"prepare(template) + prepare(target) + match, pairs run concurrently on the "
              f"{os.environ['RAYON_NUM_THREADS']}-thread pool); bench wall clock "
              f"{wall:.1f} s / {len(pairs)} pairs = {wall / max(len(pairs), 1):.2f} s per pair "
              "including its evaluation.")
    if missing_sym:
        print(f"\nsymcorr wrote no correspondence file for {len(missing_sym)} pair(s): "
              + ", ".join(missing_sym[:5]))
    print("\npeer: pyFM (pyfmaps) "
          f"{args.descr} n_descr={args.n_descr} subsample_step={args.subsample_step} "
          f"k_descr={args.k_descr} k_process={args.k_process}; FM {args.k_fit}x{args.k_fit} "
          "(w_descr=1, w_lap=0.1, w_dcomm=1"
          f", w_orient={args.w_orient}); ZoomOut {args.k_fit}->{kmax} (nit={args.zo_nit}, "
          f"step={args.zo_step}). Peer seconds: whole pipeline per pair except file reading "
          "(both meshes' eigenpairs and descriptors recomputed for every pair).")
    for name, brks in peer_breakdown.items():
        print(f"  {name}: mean seconds " + ", ".join(
            f"{s} {np.mean([b[s] for b in brks]):.2f}" for s in brks[0]))
    if cached_pairs:
        print(f"  peer maps of {cached_pairs} pair(s) came from --peer-cache {args.peer_cache}; "
              "their seconds are those measured when they were computed.")
    print(f"load average (1 min) before/after the peer: {load_before[0]:.1f} / {load_after[0]:.1f}"
          + (f"; at symcorr's start: {sym_load:.1f}" if sym_load is not None else ""))

    if args.json:
        args.json.write_text(json.dumps({"dataset": str(dataset), "machine": info, "rows": rows,
                                         "pairs": per_pair, "symcorr_status": sym_msg,
                                         # per tool, in pairs.txt order (each pair row of
                                         # "pairs" also has its own "seconds")
                                         "peer_seconds": peer_secs,
                                         "peer_breakdown_s": peer_breakdown}, indent=2))
    if tmp and not args.keep:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
