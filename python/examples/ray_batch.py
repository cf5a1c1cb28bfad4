#!/usr/bin/env python3
"""Map a list of pairs over a Ray cluster with one prepared template per worker.

Usage:
    python python/examples/ray_batch.py [DATASET] [--template NAME] [--workers N] [--local]

DATASET is a folder in symcorr's benchmark layout (default: fixtures/synth/bodies): meshes/NAME.ply
and joints/NAME.json. Every target of DATASET/pairs.txt whose template is NAME (default s0_rest)
is matched onto by NAME; each worker prepares the template once (a Ray actor, or one per
process of a `concurrent.futures.ProcessPoolExecutor`) and matches its share of the targets against it. With
`--local` the same code runs on a `ProcessPoolExecutor` instead of Ray (what the tests run).

The worker side is the class `Worker` (prepare in `__init__`, `match(target)`); `run_serial`,
`run_executor` and `run_ray` map it, and all three return the same `{target: (pairs, confidence)}`.
"""

import argparse
import multiprocessing
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

import symcorr

REPO = Path(__file__).resolve().parents[2]
DEFAULT_DATASET = REPO / "fixtures" / "synth" / "bodies"


def load_body(dataset, name):
    """A symcorr.Body from DATASET/meshes/NAME.ply and DATASET/joints/NAME.json."""
    dataset = Path(dataset)
    v, f = symcorr.read_mesh(dataset / "meshes" / f"{name}.ply")
    return symcorr.Body(v, f, symcorr.read_joints(dataset / "joints" / f"{name}.json"))


def targets_of(dataset, template):
    """The targets DATASET/pairs.txt pairs with `template`, in file order."""
    out = []
    for line in (Path(dataset) / "pairs.txt").read_text().splitlines():
        parts = line.split()
        if len(parts) == 2 and parts[0] == template:
            out.append(parts[1])
    return out


# --- worker side: one prepared template per worker --------------------------------------------


class Worker:
    """The template prepared once; matches targets against it."""

    def __init__(self, dataset, template):
        self.dataset = str(dataset)
        self.prepared = symcorr.Prepared(load_body(dataset, template))

    def match(self, target):
        """(target, pairs, confidence) of the prepared template matched onto `target`."""
        c = self.prepared.match(load_body(self.dataset, target))
        return target, c.pairs, c.confidence


_WORKER = None  # the process's Worker (ProcessPoolExecutor)


def _init_process(dataset, template):
    global _WORKER
    _WORKER = Worker(dataset, template)


def _match_in_process(target):
    return _WORKER.match(target)


# --- three ways to map it ---------------------------------------------------------------------


def run_serial(dataset, template, targets):
    w = Worker(dataset, template)
    return {t: (p, c) for t, p, c in map(w.match, targets)}


def run_executor(dataset, template, targets, workers=2):
    """The same with a ProcessPoolExecutor: each process holds one Worker. Worker processes
    are spawned, not forked: a fork of a process whose thread pool (symcorr's rayon workers)
    is running would inherit the pool without its threads."""
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_init_process,
                             initargs=(str(dataset), template)) as ex:
        return {t: (p, c) for t, p, c in ex.map(_match_in_process, targets)}


def run_ray(dataset, template, targets, workers=2):
    """The same on Ray: one actor per worker holds one Worker."""
    import ray

    Matcher = ray.remote(num_cpus=1)(Worker)
    actors = [Matcher.remote(str(dataset), template) for _ in range(workers)]
    pool = ray.util.ActorPool(actors)
    return {t: (p, c) for t, p, c in pool.map(lambda a, t: a.match.remote(t), targets)}


def same(a, b):
    return a.keys() == b.keys() and all(
        np.array_equal(a[k][0], b[k][0]) and np.array_equal(a[k][1], b[k][1]) for k in a)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dataset", nargs="?", type=Path, default=DEFAULT_DATASET)
    ap.add_argument("--template", default="s0_rest")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--local", action="store_true",
                    help="a ProcessPoolExecutor instead of Ray")
    ap.add_argument("--address", help="a running Ray cluster (default: start a local one)")
    args = ap.parse_args()
    targets = targets_of(args.dataset, args.template)
    if not targets:
        sys.exit(f"{args.dataset}/pairs.txt: no pair with template {args.template}")
    print(f"{len(targets)} targets for {args.template}, {args.workers} workers, "
          f"{os.cpu_count()} cores", flush=True)
    t = time.perf_counter()
    serial = run_serial(args.dataset, args.template, targets)
    t_serial = time.perf_counter() - t
    print(f"serial: {t_serial:.2f} s ({t_serial / len(targets):.2f} s per pair, template "
          f"prepared once)", flush=True)
    if args.local:
        t = time.perf_counter()
        mapped = run_executor(args.dataset, args.template, targets, args.workers)
        name = "ProcessPoolExecutor"
    else:
        import ray

        t0 = time.perf_counter()
        ray.init(address=args.address, num_cpus=None if args.address else args.workers,
                 include_dashboard=False)
        print(f"ray.init: {time.perf_counter() - t0:.2f} s", flush=True)
        t = time.perf_counter()
        mapped = run_ray(args.dataset, args.template, targets, args.workers)
        name = "Ray"
    t_mapped = time.perf_counter() - t
    ok = same(serial, mapped)
    print(f"{name}: {t_mapped:.2f} s with {args.workers} workers (each prepares the template "
          f"once); results equal the serial run: {ok}")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
