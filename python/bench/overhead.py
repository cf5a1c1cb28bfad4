#!/usr/bin/env python3
"""The Python call's overhead against the command line on one pair.

Usage:
    python python/bench/overhead.py SYMCORR_BINARY [--repeats N] [--pair TEMPLATE TARGET]

Runs, interleaved, N times each on the pair (default s0_rest → s1_t-pose of
fixtures/synth/bodies, 13,380 vertices each, articulated, dense):
  cli       `SYMCORR_BINARY match A B --template-joints … --target-joints … --out OUT --dense --json`
            as a subprocess (wall clock: start-up, reading, both meshes prepared, matching, the
            JSON written);
  python    `symcorr.read_mesh` ×2, `symcorr.read_joints` ×2 and `symcorr.match(a, b)` in this
            process (the same work, without the process start and the file written);
  match     `symcorr.match(a, b)` on arrays already in memory;
  boundary  `symcorr.Body(V, F, J)` ×2: the array checks and copies `match` does on its inputs.
Prints medians and min; the wheel and the binary should come from the same build profile.
"""

import argparse
import json
import os
import platform
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

import symcorr

REPO = Path(__file__).resolve().parents[2]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("binary")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--pair", nargs=2, default=["s0_rest", "s1_t-pose"])
    ap.add_argument("--dataset", type=Path, default=REPO / "fixtures" / "synth" / "bodies")
    args = ap.parse_args()
    d = args.dataset
    m = [d / "meshes" / f"{n}.ply" for n in args.pair]
    j = [d / "joints" / f"{n}.json" for n in args.pair]
    out = Path(tempfile.mkdtemp()) / "corr.json"
    cmd = [args.binary, "match", m[0], m[1], "--template-joints", j[0], "--target-joints", j[1],
           "--out", out, "--dense", "--json"]

    def body(i):
        v, f = symcorr.read_mesh(m[i])
        return v, f, symcorr.read_joints(j[i])

    a, b = body(0), body(1)
    symcorr.match(a, b)  # warm up (page cache, thread pool)
    subprocess.run(cmd, check=True, capture_output=True)
    t = {"cli": [], "cli_internal": [], "python": [], "match": [], "boundary": []}
    for _ in range(args.repeats):
        s = time.perf_counter()
        r = subprocess.run(cmd, check=True, capture_output=True, text=True)
        t["cli"].append(time.perf_counter() - s)
        t["cli_internal"].append(json.loads(r.stdout)["seconds"])
        s = time.perf_counter()
        c = symcorr.match(body(0), body(1))
        t["python"].append(time.perf_counter() - s)
        s = time.perf_counter()
        c2 = symcorr.match(a, b)
        t["match"].append(time.perf_counter() - s)
        s = time.perf_counter()
        symcorr.Body(*a), symcorr.Body(*b)
        t["boundary"].append(time.perf_counter() - s)
        assert np.array_equal(c.pairs, c2.pairs)
    ref = np.array(json.loads(out.read_text())["pairs"])[:, :2]
    assert np.array_equal(ref, c.pairs), "the CLI and the package disagree"
    med = {k: statistics.median(v) for k, v in t.items()}
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load {os.getloadavg()[0]:.1f}, {args.repeats} repeats, pair {args.pair[0]} → "
          f"{args.pair[1]} ({len(a[0])} → {len(b[0])} vertices); identical pairs")
    for k, v in t.items():
        print(f"{k:13} median {med[k]:.3f} s  min {min(v):.3f} s")
    cli = med["cli"]
    print(f"python − cli: {med['python'] - cli:+.3f} s ({100 * (med['python'] - cli) / cli:+.1f} % "
          f"of the CLI); boundary checks and copies: {med['boundary'] * 1000:.1f} ms "
          f"({100 * med['boundary'] / cli:.1f} % of the CLI)")


if __name__ == "__main__":
    main()
