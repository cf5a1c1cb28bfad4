#!/usr/bin/env python3
"""Build the lens-distortion reference fixture for the depth-camera intrinsics.

Writes
  fixtures/kinect/distortion_reference.json   OpenCV's own projection / unprojection numbers for
                                               three pinhole + distortion cameras (OpenCV camera model)

Each case holds the intrinsics (fx, fy, cx, cy, image size), the OpenCV distCoeffs vector and
  project    200 x {"point": [x, y, z], "pixel": [u, v]}   pixel = cv2.projectPoints(point, rvec = tvec = 0)
  unproject  200 x {"pixel": [u, v], "ray": [x/z, y/z]}    ray = cv2.undistortPoints(pixel, K, dist, R=None, P=None,
                                                          criteria=(COUNT | EPS, 200, 1e-15)), i.e. normalised
                                                          coordinates; cv2.undistortPointsIter when the installed
                                                          OpenCV has it (OpenCV 5 dropped it: same thing)
The unproject pixels are the four image corners, the principal point, then 195 pixels drawn
uniformly over [0, W-1] x [0, H-1]. The project points are made by drawing a pixel uniformly in the
same rectangle, undistorting it as above, and scaling the ray (x/z, y/z, 1) by a depth z drawn
uniformly in [0.5, 4.5] m; the recorded pixel is cv2's projection of that point, not the drawn pixel.

Cases
  kinect_v2_radial          512 x 424, 5 coefficients (k1, k2, p1, p2, k3), p1 = p2 = 0
  azure_nfov_rational       640 x 576, 8 coefficients (rational model k1..k6 + tangential)
  brown_conrady_tangential  640 x 480, 4 coefficients (k1, k2, p1, p2)

Before sampling, every case is checked to be invertible over the whole image: the radial map
r -> r (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6) must have a positive
denominator and a positive derivative for undistorted radii 0 .. 1.5 x the undistorted radius of the
farthest image corner. The Azure-like coefficients [0.4989, -0.0155, -0.0000532, 0.0000436, -0.0063,
0.8350, 0.1196, -0.0300] pass as given (the map is increasing up to its pole at r = 2.827, the
farthest corner sits at r = 1.422, min derivative on the checked range 0 .. 2.13 is 0.268), so nothing was
changed. Every unprojected ray is re-projected with cv2.projectPoints and must land within 1e-6 px of
its pixel (asserted; the worst residual per case is printed), and every project point's cv2 pixel
must be within 1e-6 px of the pixel it was drawn from.

Run from the repository root (or anywhere), in a venv with numpy and opencv-python-headless:
  python3 -m venv /tmp/cvref && /tmp/cvref/bin/pip install numpy==2.4.6 opencv-python-headless==5.1.0.95
  /tmp/cvref/bin/python tools/reference/make_distortion_reference.py

Deterministic: the samples come from seeded numpy generators (np.random.default_rng([SEED, case
index])), everything is float64, and floats are written with Python's repr (shortest round-trip),
so nothing is rounded away. Re-running with the same numpy / OpenCV versions reproduces the file
bit for bit.
"""

import json
import os
import platform
import time

import cv2
import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
JSON_PATH = os.path.join(ROOT, "fixtures", "kinect", "distortion_reference.json")
GENERATOR = "tools/reference/make_distortion_reference.py"

SEED = 20240917
N_PROJECT = 200
N_UNPROJECT = 200
DEPTH_RANGE = (0.5, 4.5)  # metres
CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-15)
TOL_PX = 1e-6
MONOTONE_MARGIN = 1.5  # check the radial map up to this multiple of the corner's undistorted radius

CONVENTION = (
    "OpenCV camera frame x right, y down, z forward; pixel (u,v) with u = column, v = row, "
    "pixel centres at integers; distortion = OpenCV distCoeffs order (k1,k2,p1,p2[,k3[,k4,k5,k6]])"
)

CASES = [
    dict(name="kinect_v2_radial", width=512, height=424,
         fx=365.5, fy=365.5, cx=254.9, cy=205.4,
         distortion=[0.0905, -0.2701, 0.0, 0.0, 0.0922]),
    dict(name="azure_nfov_rational", width=640, height=576,
         fx=504.3, fy=504.4, cx=321.9, cy=333.6,
         distortion=[0.4989, -0.0155, -0.0000532, 0.0000436, -0.0063, 0.8350, 0.1196, -0.0300]),
    dict(name="brown_conrady_tangential", width=640, height=480,
         fx=580.0, fy=578.0, cx=318.2, cy=241.7,
         distortion=[-0.12, 0.05, 0.001, -0.0015]),
]


def camera_matrix(c):
    return np.array([[c["fx"], 0.0, c["cx"]], [0.0, c["fy"], c["cy"]], [0.0, 0.0, 1.0]], dtype=np.float64)


def dist_vector(c):
    return np.array(c["distortion"], dtype=np.float64)


def radial_coeffs(dist):
    """(k1, k2, k3, k4, k5, k6) from an OpenCV distCoeffs vector of length 4, 5 or 8 (missing = 0)."""
    d = list(dist) + [0.0] * (8 - len(dist))
    return d[0], d[1], d[4], d[5], d[6], d[7]


def radial_map(r, dist):
    """r_d(r), its derivative and the rational denominator, for undistorted radius r (array)."""
    k1, k2, k3, k4, k5, k6 = radial_coeffs(dist)
    t = r * r
    num = 1.0 + t * (k1 + t * (k2 + t * k3))
    den = 1.0 + t * (k4 + t * (k5 + t * k6))
    num_t = k1 + t * (2.0 * k2 + t * 3.0 * k3)
    den_t = k4 + t * (2.0 * k5 + t * 3.0 * k6)
    f = r * num / den
    df = (num * den + 2.0 * t * (num_t * den - num * den_t)) / (den * den)
    return f, df, den


def check_invertible(c):
    """Assert the radial map is strictly increasing (and its denominator positive) for undistorted
    radii up to MONOTONE_MARGIN x the undistorted radius of the farthest image corner.
    Returns (corner distorted radius, corner undistorted radius, min derivative)."""
    dist = dist_vector(c)
    W, H = c["width"], c["height"]
    corners = [((u - c["cx"]) / c["fx"], (v - c["cy"]) / c["fy"]) for u in (0, W - 1) for v in (0, H - 1)]
    rd_corner = max(float(np.hypot(x, y)) for x, y in corners)
    # Walk outwards on a fine grid until the map passes the corner radius, checking as we go.
    step = 1e-5
    r_hi = 0.5
    while True:
        r = np.arange(0.0, r_hi + step / 2, step)
        f, df, den = radial_map(r, dist)
        bad = (den <= 0.0) | (df <= 0.0)
        above = np.nonzero(f >= rd_corner)[0]
        if above.size and not bad[: above[0] + 1].any():
            break
        assert not bad.any(), f"{c['name']}: radial map not increasing before r_d reaches the corner ({rd_corner})"
        assert r_hi < 100.0, f"{c['name']}: corner radius never reached"
        r_hi *= 2.0
    # Refine the undistorted corner radius by bisection on the monotone branch.
    lo, hi = float(r[above[0] - 1]), float(r[above[0]])
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if radial_map(np.array([mid]), dist)[0][0] < rd_corner:
            lo = mid
        else:
            hi = mid
    r_corner = hi
    r = np.linspace(0.0, MONOTONE_MARGIN * r_corner, 1_000_001)
    f, df, den = radial_map(r, dist)
    assert (den > 0.0).all(), f"{c['name']}: rational denominator vanishes below {MONOTONE_MARGIN} x corner radius"
    assert (df > 0.0).all(), f"{c['name']}: radial map not strictly increasing below {MONOTONE_MARGIN} x corner radius"
    assert (np.diff(f) > 0.0).all(), f"{c['name']}: sampled radial map not strictly increasing"
    return rd_corner, r_corner, float(df.min())


def undistort(pixels, K, dist):
    """Normalised rays (x/z, y/z) of distorted pixels (N x 2), OpenCV's iterative undistortion."""
    src = np.ascontiguousarray(pixels, dtype=np.float64).reshape(-1, 1, 2)
    fn = getattr(cv2, "undistortPointsIter", None)
    if fn is not None:
        out = fn(src, K, dist, None, None, CRITERIA)
    else:
        out = cv2.undistortPoints(src, K, dist, R=None, P=None, criteria=CRITERIA)
    assert out.dtype == np.float64
    return out.reshape(-1, 2)


def project(points, K, dist):
    """cv2.projectPoints of camera-frame points (N x 3), rvec = tvec = 0."""
    obj = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 1, 3)
    zero = np.zeros(3, dtype=np.float64)
    img, _ = cv2.projectPoints(obj, zero, zero, K, dist)
    assert img.dtype == np.float64
    return img.reshape(-1, 2)


def draw_pixels(rng, c, n):
    u = rng.uniform(0.0, c["width"] - 1.0, n)
    v = rng.uniform(0.0, c["height"] - 1.0, n)
    return np.stack([u, v], axis=1)


def build_case(index, c):
    rng = np.random.default_rng([SEED, index])
    K, dist = camera_matrix(c), dist_vector(c)
    W, H = c["width"], c["height"]

    # --- unproject: corners, principal point, then uniform pixels -----------------------------
    fixed = np.array([[0.0, 0.0], [W - 1.0, 0.0], [0.0, H - 1.0], [W - 1.0, H - 1.0], [c["cx"], c["cy"]]])
    un_pix = np.concatenate([fixed, draw_pixels(rng, c, N_UNPROJECT - len(fixed))])
    rays = undistort(un_pix, K, dist)
    back = project(np.concatenate([rays, np.ones((len(rays), 1))], axis=1), K, dist)
    un_resid = np.hypot(*(back - un_pix).T)
    assert np.isfinite(rays).all()
    assert un_resid.max() <= TOL_PX, f"{c['name']}: unproject round trip {un_resid.max():.3e} px"

    # --- project: drawn pixel -> ray -> random depth -> 3-D point -> cv2 pixel -----------------
    pr_pix = draw_pixels(rng, c, N_PROJECT)
    pr_rays = undistort(pr_pix, K, dist)
    z = rng.uniform(DEPTH_RANGE[0], DEPTH_RANGE[1], N_PROJECT)
    points = np.stack([pr_rays[:, 0] * z, pr_rays[:, 1] * z, z], axis=1)
    pixels = project(points, K, dist)
    pr_resid = np.hypot(*(pixels - pr_pix).T)
    assert np.isfinite(pixels).all()
    assert pr_resid.max() <= TOL_PX, f"{c['name']}: project vs drawn pixel {pr_resid.max():.3e} px"

    out = {k: c[k] for k in ("name", "width", "height", "fx", "fy", "cx", "cy", "distortion")}
    out["project"] = [{"point": [float(a) for a in p], "pixel": [float(a) for a in q]} for p, q in zip(points, pixels)]
    out["unproject"] = [{"pixel": [float(a) for a in p], "ray": [float(a) for a in r]} for p, r in zip(un_pix, rays)]
    stats = dict(unproject_max=float(un_resid.max()), unproject_argmax=un_pix[int(un_resid.argmax())].tolist(),
                 project_max=float(pr_resid.max()),
                 ray_extent=float(np.abs(rays).max()))
    return out, stats


def dumps(doc):
    """JSON with one project / unproject entry per line; floats via repr (json's default)."""
    lines = ["{"]
    for key in ("generator", "opencv", "numpy", "convention"):
        lines.append(f"  {json.dumps(key)}: {json.dumps(doc[key])},")
    lines.append('  "cases": [')
    for ci, case in enumerate(doc["cases"]):
        lines.append("    {")
        head = ", ".join(f"{json.dumps(k)}: {json.dumps(case[k])}" for k in ("name", "width", "height", "fx", "fy", "cx", "cy"))
        lines.append(f"      {head},")
        lines.append(f'      "distortion": {json.dumps(case["distortion"])},')
        for li, list_key in enumerate(("project", "unproject")):
            lines.append(f"      {json.dumps(list_key)}: [")
            entries = case[list_key]
            for ei, e in enumerate(entries):
                lines.append("        " + json.dumps(e) + ("," if ei + 1 < len(entries) else ""))
            lines.append("      ]" + ("," if li == 0 else ""))
        lines.append("    }" + ("," if ci + 1 < len(doc["cases"]) else ""))
    lines.append("  ]")
    lines.append("}")
    return "\n".join(lines) + "\n"


def main():
    t_start = time.time()
    print(f"python {platform.python_version()}, numpy {np.__version__}, opencv {cv2.__version__}, "
          f"undistort via {'cv2.undistortPointsIter' if hasattr(cv2, 'undistortPointsIter') else 'cv2.undistortPoints'}")
    doc = {"generator": GENERATOR, "opencv": cv2.__version__, "numpy": np.__version__,
           "convention": CONVENTION, "cases": []}
    for i, c in enumerate(CASES):
        rd_corner, r_corner, min_df = check_invertible(c)
        case, st = build_case(i, c)
        doc["cases"].append(case)
        print(f"{c['name']}: corner r_d {rd_corner:.6f} <- r {r_corner:.6f}, radial map increasing up to "
              f"{MONOTONE_MARGIN} x that (min dr_d/dr {min_df:.4f}); max |ray| {st['ray_extent']:.4f}")
        print(f"  unproject round trip max {st['unproject_max']:.3e} px (at {st['unproject_argmax']}), "
              f"project vs drawn pixel max {st['project_max']:.3e} px")

    text = dumps(doc)
    assert json.loads(text) == doc, "JSON does not round-trip"
    os.makedirs(os.path.dirname(JSON_PATH), exist_ok=True)
    with open(JSON_PATH, "w", encoding="utf-8") as fh:
        fh.write(text)
    print(f"wrote {os.path.relpath(JSON_PATH, ROOT)} ({os.path.getsize(JSON_PATH) / 1024:.0f} KiB) "
          f"in {time.time() - t_start:.1f} s")


if __name__ == "__main__":
    main()
