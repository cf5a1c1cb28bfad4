"""Bad arrays and options become ValueError with a clear message, never a crash."""

import numpy as np
import pytest

import symcorr
from conftest import SCAN


@pytest.fixture(scope="module")
def small(rest):
    """A few triangles of the body with its joints (enough to reach validation)."""
    v, f, j = rest
    return v, f, j


def bad_vertices(v):
    yield "dtype complex128", v.astype(complex)
    yield "dtype str", v.astype(str)
    yield "dtype object", np.array([[object()] * 3] * 4, dtype=object)
    yield "dtype bool", np.ones((4, 3), dtype=bool)
    yield r"shape \(n, 3\), got \(13380, 2\)", v[:, :2]
    yield r"shape \(n, 3\), got \(40140,\)", v.ravel()
    yield r"shape \(n, 3\), got \(1, 13380, 3\)", v[None]
    yield "non-finite", np.where(np.arange(len(v))[:, None] == 7, np.nan, v)
    yield "non-finite", np.where(np.arange(len(v))[:, None] == 9, np.inf, v)
    yield "expected a float array", [[0.0, 1.0], [1.0]]  # ragged


def bad_faces(f, n):
    yield "expected an integer array", f.astype(np.float64)
    yield "expected an integer array", f.astype(bool)
    yield "out of range", np.where(f == 5, -1, f)
    yield "out of range", np.where(f == 5, n, f)
    yield "out of range", np.where(f == 5, 2**40, f).astype(np.int64)
    yield "out of range", f.astype(np.uint64) + np.uint64(2**63)
    yield r"shape \(n, 3\), got \(26756, 4\)", np.hstack([f, f[:, :1]])
    yield "shape", f.ravel()


def test_bad_vertices(small):
    v, f, j = small
    for msg, bad in bad_vertices(v):
        with pytest.raises(ValueError, match=msg):
            symcorr.label(bad, f, j)
        with pytest.raises(ValueError, match="template vertices"):
            symcorr.match((bad, f, j), (v, f, j))


def test_bad_faces(small):
    v, f, j = small
    for msg, bad in bad_faces(f, len(v)):
        with pytest.raises(ValueError, match=msg):
            symcorr.Body(v, bad, j)
        with pytest.raises(ValueError, match="target faces"):
            symcorr.match((v, f, j), (v, bad, j))


def test_empty_mesh(small):
    _, _, j = small
    with pytest.raises(ValueError):
        symcorr.Body(np.zeros((0, 3)), np.zeros((0, 3), dtype=int), j)
    with pytest.raises(ValueError):
        symcorr.Body(np.zeros((3, 3)), np.zeros((0, 3), dtype=int), j)


def test_bad_joints(small):
    v, f, j = small
    arr = np.array([j[n] for n in symcorr.JOINT_NAMES])
    cases = [
        ("missing joint", {k: p for k, p in j.items() if k != "head"}),
        ("unknown joint", {**j, "tail": (0, 0, 0)}),
        ("keys must be joint names", {**j, 3: (0, 0, 0)}),
        (r"shape \(20, 3\)", arr[:15]),
        (r"shape \(n, 3\)", arr[:, :2]),
        ("non-finite", np.where(np.arange(20)[:, None] == 3, np.nan, arr)),
        ("non-finite", {**j, "head": (np.nan, 0, 0)}),
        ("three coordinates", {**j, "head": (1.0, 2.0)}),
        ("dtype", arr.astype(complex)),
        ("expected", "not joints"),
    ]
    for msg, bad in cases:
        with pytest.raises(ValueError, match=msg):
            symcorr.Body(v, f, bad)


def test_joints_of_another_pose_are_refused_with_the_fit_check(small, tpose):
    v, f, _ = small
    moved = tpose[2]
    with pytest.raises(ValueError, match="does not fit"):
        symcorr.label(v, f, moved)
    labels = symcorr.label(v, f, moved, accept_poor_fit=True)
    assert labels.corrections["accepted_poor_fit"] is True


def test_bad_options(small):
    body = small
    with pytest.raises(ValueError, match="method"):
        symcorr.match(body, body, method="magic")
    with pytest.raises(ValueError, match="at least one sample"):
        symcorr.match(body, body, dense=False, samples=0)
    with pytest.raises(ValueError, match="boundaries"):
        symcorr.label(*body, boundaries="elbows")
    with pytest.raises(ValueError, match="Body or a"):
        symcorr.match(body, "body")
    with pytest.raises(ValueError, match="Body or a"):
        symcorr.match(body, (1, 2))
    with pytest.raises(ValueError, match="samples -1"):
        symcorr.match(body, body, dense=False, samples=-1)


def test_bad_depth_and_intrinsics():
    depth = symcorr.read_depth(SCAN / "depth.png")
    j = symcorr.read_joints(SCAN / "joints.json")
    k = SCAN / "intrinsics.json"
    with pytest.raises(ValueError, match="uint16"):
        symcorr.scan(depth.astype(np.float32), k, j)
    with pytest.raises(ValueError, match=r"shape \(h, w\)"):
        symcorr.scan(depth[None], k, j)
    with pytest.raises(ValueError, match="depth image"):
        symcorr.scan(depth[:100], k, j)
    good = {"fx": 571.26, "fy": 571.26, "cx": 320.0, "cy": 240.0}
    with pytest.raises(ValueError, match="missing \"fy\""):
        symcorr.scan(depth, {"fx": 1.0, "cx": 1, "cy": 1}, j)
    with pytest.raises(ValueError, match="fx = 0.0"):
        symcorr.scan(depth, {**good, "fx": 0.0}, j)
    with pytest.raises(ValueError, match="fx = NaN"):
        symcorr.scan(depth, {**good, "fx": float("nan")}, j)
    with pytest.raises(ValueError, match="width = 320"):
        symcorr.scan(depth, {**good, "width": 320}, j)
    with pytest.raises(ValueError, match="discontinuity"):
        symcorr.scan(depth, good, j, discontinuity=float("inf"))
    with pytest.raises(OSError):
        symcorr.scan(depth, SCAN / "missing.json", j)
    with pytest.raises(OSError):
        symcorr.read_depth(SCAN / "missing.png")
