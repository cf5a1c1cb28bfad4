#!/usr/bin/env python3
"""Side-by-side timing: scipy eigsh vs the Rust eigensolver on the same mesh, in one run.

  tools/.venv/bin/python tools/reference/bench_eigsh.py [--mesh fixtures/body/body.off] [--k 100]
      [--repeats 3] [--runner example|symcorr] [--symcorr PATH] [--build] [--blas-threads 2]

Rust side (--runner): `example` (default) runs symcorr-spectral's own timing example
`target/release/examples/eigen_timing --mesh MESH --k K --repeats 1 --json` (build it with
`cargo build --release -p symcorr-spectral --example eigen_timing`, or pass --build), which only
needs the spectral crate; `symcorr` runs the CLI `symcorr spectrum MESH --k K --json` instead.
Both print the same `timings_s` keys, so the table below is the same ("symcorr" column).

scipy: builds the cotan stiffness L and lumped mass M with numpy (tools/reference/meshutil.py),
then times scipy.sparse.linalg.eigsh(L, k, M=M, sigma=-1e-8) exactly as the speed target states it (ARPACK's
default start vector; best of --repeats; the SuperLU factorisation of L - sigma M happens inside
eigsh and is included). The Laplacian build and a stand-alone splu factorisation are reported too.

symcorr: runs `symcorr spectrum MESH --k K --json` --repeats times (default binary
target/release/symcorr; --build runs `cargo build --release -p symcorr` first) and takes the best
factorization + lanczos from its `timings_s`. scipy and symcorr runs are interleaved so that load
from other processes hits both alike. If the binary is missing or fails, that column is skipped with
a message. Eigenvalues are compared: max relative difference over i >= 1 (lambda_0 ~ 0 shown apart).

BLAS threads default to 2 (the machine's cores). On a machine busy with other work OpenBLAS's two
spinning threads can make eigsh 5-10x slower; the script prints the load average and warns.
The Rust run gets RAYON_NUM_THREADS = the same number, so --blas-threads 1 compares one thread
against one thread.
"""

import os
import sys

# Match the 2-core machine; must happen before numpy/scipy load their BLAS, hence the early argv peek.
# (--blas-threads 1 is worth trying on a busy machine: OpenBLAS's 2 spinning threads then collapse.)
_threads = "2"
for _i, _a in enumerate(sys.argv):
    if _a == "--blas-threads" and _i + 1 < len(sys.argv):
        _threads = sys.argv[_i + 1]
    elif _a.startswith("--blas-threads="):
        _threads = _a.split("=", 1)[1]
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = _threads

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import scipy  # noqa: E402
import scipy.sparse as sp  # noqa: E402
import scipy.sparse.linalg as spla  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import meshutil as mu  # noqa: E402

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SIGMA = -1e-8


def machine_info():
    cpu = "unknown"
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {
        "nproc": os.cpu_count(),
        "cpu": cpu,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "threads": {v: os.environ.get(v) for v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")},
    }


def best_of(fn, repeats):
    best, out = float("inf"), None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def scipy_setup(mesh, repeats):
    t0 = time.perf_counter()
    V, F = mu.read_off(mesh)
    t_load = time.perf_counter() - t0
    t_lap, (L, m) = best_of(lambda: (mu.cotan_laplacian(V, F), mu.lumped_mass(V, F)), repeats)
    M = sp.diags(m).tocsc()
    t_splu, _ = best_of(lambda: spla.splu((L - SIGMA * M).tocsc()), repeats)
    return {"n": len(V), "load": t_load, "laplacian": t_lap, "splu": t_splu, "L": L, "M": M}


def scipy_eigsh_once(s, k):
    """Exactly the call of the speed target: eigsh(L, k, M=M, sigma=-1e-8) (default which='LM', ARPACK's own start vector)."""
    t0, c0 = time.perf_counter(), time.process_time()
    lam, _ = spla.eigsh(s["L"], k, M=s["M"], sigma=SIGMA)
    return time.perf_counter() - t0, time.process_time() - c0, np.sort(lam)


RUNNERS = {
    # runner: (cargo build arguments, default binary, command line after the binary)
    "example": (["-p", "symcorr-spectral", "--example", "eigen_timing"],
                os.path.join("target", "release", "examples", "eigen_timing"),
                lambda mesh, k: ["--mesh", mesh, "--k", str(k), "--repeats", "1", "--json"]),
    "symcorr": (["-p", "symcorr"], os.path.join("target", "release", "symcorr"),
                lambda mesh, k: ["spectrum", mesh, "--k", str(k), "--json"]),
}


def find_symcorr(path, build, runner):
    cargo_args, default_exe, _ = RUNNERS[runner]
    if build:
        cmd = ["cargo", "build", "--release"] + cargo_args
        print("building: " + " ".join(cmd) + " ...", flush=True)
        r = subprocess.run(cmd, cwd=ROOT)
        if r.returncode != 0:
            print(f"rust: cargo build failed (exit {r.returncode}); skipping the symcorr column")
            return None
    exe = path or os.path.join(ROOT, default_exe)
    if not (os.path.isfile(exe) and os.access(exe, os.X_OK)):
        print(f"rust: no binary at {exe} (build it with `cargo build --release {' '.join(cargo_args)}` or pass "
              "--build); skipping the symcorr column")
        return None
    return exe


def symcorr_once(exe, mesh, k, runner):
    """One Rust run (see RUNNERS) -> dict, or an error string."""
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    # Same thread count as scipy's BLAS (fair comparison; rayon, hence faer, reads this).
    env = dict(os.environ, RAYON_NUM_THREADS=os.environ.get("OPENBLAS_NUM_THREADS", "2"))
    r = subprocess.run([exe] + RUNNERS[runner][2](mesh, k), capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    if r.returncode != 0:
        return f"exited {r.returncode}: {r.stderr.strip()[:500]}"
    try:
        out = json.loads(r.stdout)
        lam = np.sort(np.asarray(out["eigenvalues"], dtype=np.float64))
        ts = {key: float(v) for key, v in out.get("timings_s", {}).items() if isinstance(v, (int, float))}
    except (ValueError, KeyError, TypeError) as exc:
        return f"unreadable JSON ({exc}); first 300 chars: {r.stdout[:300]!r}"
    if "factorization" in ts and "lanczos" in ts:
        solve, how = ts["factorization"] + ts["lanczos"], "factorization + lanczos"
    else:
        solve = wall - ts.get("load", 0.0) - ts.get("laplacian", 0.0)
        how = f"process wall - load - laplacian (timings_s has only {sorted(ts)})"
    return {"wall": wall, "cpu": cpu, "solve": solve, "how": how, "timings": ts, "eigenvalues": lam}


def loadavg():
    try:
        return os.getloadavg()[0]
    except OSError:
        return float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mesh", default=os.path.join(ROOT, "fixtures", "body", "body.off"))
    ap.add_argument("--k", type=int, default=100)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--runner", choices=sorted(RUNNERS), default="example",
                    help="Rust side: spectral's eigen_timing example (default) or the symcorr CLI")
    ap.add_argument("--symcorr", default=None, help="path to the Rust binary (default: the runner's release binary)")
    ap.add_argument("--build", action="store_true", help="cargo build --release the runner's binary first")
    ap.add_argument("--blas-threads", default="2", help="OMP/OPENBLAS/MKL_NUM_THREADS for scipy (default 2 = nproc)")
    args = ap.parse_args()
    if not args.mesh.lower().endswith(".off"):
        ap.error("this script reads OFF meshes only")

    info = machine_info()
    print(f"machine: {info['nproc']} cores, {info['cpu']}; python {info['python']}, numpy {info['numpy']}, "
          f"scipy {info['scipy']}; threads {info['threads']}")
    rel = os.path.relpath(args.mesh, ROOT)
    exe = find_symcorr(args.symcorr, args.build, args.runner)
    load_before = loadavg()

    s = scipy_setup(args.mesh, args.repeats)
    # Interleave scipy and symcorr runs so a busy machine (other builds) hurts both alike.
    scipy_times, scipy_cpu, scipy_lam, y_runs, y_error = [], [], None, [], None
    for _ in range(args.repeats):
        t, c, scipy_lam = scipy_eigsh_once(s, args.k)
        scipy_times.append(t)
        scipy_cpu.append(c)
        if exe and y_error is None:
            r = symcorr_once(exe, args.mesh, args.k, args.runner)
            if isinstance(r, str):
                y_error = r
            else:
                y_runs.append(r)
    load_after = loadavg()
    if y_error:
        print(f"symcorr: {y_error}; skipping the symcorr column")
    y = min(y_runs, key=lambda r: r["solve"]) if (y_runs and not y_error) else None
    t_eig = min(scipy_times)

    print(f"rust runner: {args.runner} ({exe}), RAYON_NUM_THREADS = {os.environ.get('OPENBLAS_NUM_THREADS')}")
    print(f"mesh: {rel}, {s['n']} vertices, k = {args.k}, best of {args.repeats}; "
          f"1-min load average {load_before:.2f} before, {load_after:.2f} after"
          + ("  (WARNING: machine busy, timings unreliable)" if max(load_before, load_after) > 2.5 else ""))
    print(f"scipy: Laplacian+mass build (numpy) {s['laplacian']:.4f} s; splu(L - sigma M) alone {s['splu']:.4f} s; "
          f"eigsh(L, {args.k}, M=M, sigma={SIGMA}) per run " + ", ".join(f"{t:.3f}" for t in scipy_times)
          + " s (factorisation included)")

    print()
    print(f"{'':28s} {'scipy':>10s} {'symcorr':>10s} {'scipy/symcorr':>14s}")
    y_lap = y["timings"].get("laplacian") if y else None
    print(f"{'Laplacian + mass (s)':28s} {s['laplacian']:10.4f} "
          + (f"{y_lap:10.4f} {s['laplacian'] / y_lap:14.2f}" if y_lap else f"{'-':>10s} {'-':>14s}"))
    print(f"{'eigenpairs, k=' + str(args.k) + ' (s)':28s} {t_eig:10.4f} "
          + (f"{y['solve']:10.4f} {t_eig / y['solve']:14.2f}" if y else f"{'-':>10s} {'-':>14s}"))
    # CPU seconds are far less sensitive to other load than wall time (but charge threads in full).
    y_cpu = min(r["cpu"] for r in y_runs) if y else None
    print(f"{'CPU s (symcorr: whole run)':28s} {min(scipy_cpu):10.4f} "
          + (f"{y_cpu:10.4f} {min(scipy_cpu) / y_cpu:14.2f}" if y else f"{'-':>10s} {'-':>14s}"))
    if y:
        a, b = scipy_lam, y["eigenvalues"]
        if len(a) != len(b):
            print(f"eigenvalue count differs: scipy {len(a)}, symcorr {len(b)}")
        else:
            rel_diff = np.abs(a[1:] - b[1:]) / np.abs(a[1:])
            print(f"{'max rel. eigenvalue diff':28s} {rel_diff.max():10.2e}  (i >= 1, worst at i = "
                  f"{int(np.argmax(rel_diff)) + 1}; |lambda_0| scipy {abs(a[0]):.1e}, symcorr {abs(b[0]):.1e})")
        print(f"symcorr eigenpair seconds per run ({y['how']}): " + ", ".join(f"{r['solve']:.4f}" for r in y_runs))
        print("symcorr timings_s of the best run: " + ", ".join(f"{key} {v:.4f}" for key, v in y["timings"].items())
              + f"; process wall {y['wall']:.4f} s")
        print(f"RATIO scipy eigsh / rust eigenpairs = {t_eig / y['solve']:.2f}x (best of {args.repeats} each, "
              f"load {load_before:.2f} -> {load_after:.2f})")
    else:
        print("(symcorr column skipped)")


if __name__ == "__main__":
    main()
