#!/usr/bin/env python3
"""symcorr (the Python package) against pyFM ZoomOut (PyPI `pyfmaps`) on two bundled bodies.

Usage:
    python python/examples/compare_pyfm.py [TEMPLATE TARGET] [--dataset DIR] [--eval-samples N]

Both tools map every template vertex of the pair (default s0_rest → s1_t-pose of
fixtures/synth/bodies) and are scored by the metric of `tools/peer/compare.py` (imported, not
copied: edge-path geodesic error on the target over √area, flips against the dataset's mirror
map), on the same seeded sample of template vertices. pyFM runs with compare.py's parameters
(WKS, 30×30 functional map with the orientation term, ZoomOut 30→110). Needs
`pip install pyfmaps scipy` beside symcorr (tools/peer/requirements.txt pins them).
"""

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import symcorr

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tools" / "peer"))
import compare  # noqa: E402  (tools/peer/compare.py: metric, dataset reading, the pyFM run)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("template", nargs="?", default="s0_rest")
    ap.add_argument("target", nargs="?", default="s1_t-pose")
    ap.add_argument("--dataset", type=Path, default=REPO / "fixtures" / "synth" / "bodies")
    ap.add_argument("--eval-samples", type=int, default=1000,
                    help="template vertices scored (seeded sample; 0 = all)")
    ap.add_argument("--seed", type=int, default=0)
    compare.add_peer_arguments(ap)
    args = ap.parse_args()
    d = args.dataset.resolve()

    def body(name):
        v, f = symcorr.read_mesh(compare.find_mesh(d, name))
        return v, f, symcorr.read_joints(d / "joints" / f"{name}.json")

    tpl, tgt = body(args.template), body(args.target)
    n = len(tpl[0])
    mirror = compare.read_mirror(d, n)
    rng = np.random.default_rng(args.seed)
    sample = (np.arange(n) if args.eval_samples <= 0 or args.eval_samples >= n
              else np.sort(rng.choice(n, size=args.eval_samples, replace=False)))

    t = time.perf_counter()
    corr = symcorr.match(tpl, tgt)  # articulated, dense
    t_sym = time.perf_counter() - t
    sym_map = np.full(n, -1, dtype=np.int64)
    sym_map[corr.pairs[:, 0]] = corr.pairs[:, 1]

    peer = compare.run_peer((tpl[0], tpl[1]), (tgt[0], tgt[1]), args)
    geo = compare.TargetGeodesics(tgt[0], tgt[1])
    rows = [("symcorr (Python, articulated)", sym_map, t_sym)]
    rows += [(name, p2p, secs) for name, (p2p, secs, _) in peer.items()]
    print(f"{args.template} → {args.target} ({n} → {len(tgt[0])} vertices), "
          f"{len(sample)} template vertices scored")
    print(f"{'tool':34} {'mean error':>10} {'flips':>8} {'≤ 0.05':>8} {'seconds':>8}")
    for name, m, secs in rows:
        ids = sample[m[sample] >= 0]
        err, flips = compare.score(geo, ids, m[ids], mirror)
        s = compare.summarise([err], [flips])
        print(f"{name:34} {s['mean_error']:10.4f} {100 * s['flip_rate']:7.2f}% "
              f"{100 * s['within_0.05']:7.1f}% {secs:8.2f}")


if __name__ == "__main__":
    main()
