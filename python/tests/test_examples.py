"""The examples: ray_batch.py's worker code on a ProcessPoolExecutor equals the serial run;
compare_pyfm.py compiles (it needs pyfmaps, not a test dependency)."""

import importlib
import py_compile
import sys
from pathlib import Path

import numpy as np

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def load(name):
    """An example as a module, importable by name (spawned worker processes import it)."""
    if str(EXAMPLES) not in sys.path:
        sys.path.insert(0, str(EXAMPLES))
    return importlib.import_module(name)


def test_ray_batch_code_path_on_a_process_pool_equals_the_serial_run():
    rb = load("ray_batch")
    targets = rb.targets_of(rb.DEFAULT_DATASET, "s0_rest")[:3]
    assert targets == ["s0_t-pose", "s0_arms-down", "s0_walk-10"]
    serial = rb.run_serial(rb.DEFAULT_DATASET, "s0_rest", targets)
    pooled = rb.run_executor(rb.DEFAULT_DATASET, "s0_rest", targets, workers=2)
    assert list(pooled) == targets
    assert rb.same(serial, pooled)
    for t in targets:
        assert serial[t][0].shape == (13380, 2)
        np.testing.assert_array_equal(serial[t][0], pooled[t][0])


def test_compare_pyfm_compiles():
    py_compile.compile(str(EXAMPLES / "compare_pyfm.py"), doraise=True)
