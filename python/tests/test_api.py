"""Every function of the package on the bundled fixtures, round trips with trimesh, pickling,
and agreement with the command line's outputs on the same inputs."""

import json
import pickle
import subprocess

import numpy as np
import pytest
import trimesh

import symcorr
from conftest import BODIES, RECORDING, SCAN, body, joints_path, mesh_path


def test_module_constants():
    assert len(symcorr.JOINT_NAMES) == 20 and symcorr.JOINT_NAMES[0] == "hip_center"
    assert len(symcorr.SEGMENT_NAMES) == 17
    assert set(symcorr.__all__) >= {"read_mesh", "read_joints", "label", "match", "scan", "track",
                                    "Prepared", "Body"}


def test_read_mesh_keeps_the_file_order_like_trimesh(rest):
    v, f, _ = rest
    assert v.dtype == np.float64 and v.shape == (13380, 3)
    assert f.dtype == np.int64 and f.shape[1] == 3 and f.min() >= 0 and f.max() < len(v)
    t = trimesh.load(mesh_path("s0_rest"), process=False)
    np.testing.assert_array_equal(t.faces, f)
    np.testing.assert_allclose(t.vertices, v, rtol=0, atol=1e-6)


@pytest.mark.parametrize("ext", ["ply", "obj", "off"])
def test_trimesh_round_trip(rest, tmp_path, ext):
    v, f, _ = rest
    path = tmp_path / f"body.{ext}"
    trimesh.Trimesh(v, f, process=False).export(path)
    v2, f2 = symcorr.read_mesh(path)
    np.testing.assert_array_equal(f2, f)
    np.testing.assert_allclose(v2, v, rtol=0, atol=1e-6)
    # and back: symcorr's arrays build the same trimesh
    t = trimesh.Trimesh(v2, f2, process=False)
    assert len(t.vertices) == len(v) and len(t.faces) == len(f)


def test_read_mesh_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothing.ply"):
        symcorr.read_mesh(tmp_path / "nothing.ply")
    bad = tmp_path / "bad.off"
    bad.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n")
    with pytest.raises(ValueError, match="bad.off"):
        symcorr.read_mesh(bad)


def test_read_joints():
    j = symcorr.read_joints(joints_path("s0_rest"))
    assert list(j) == list(symcorr.JOINT_NAMES)
    assert all(len(p) == 3 for p in j.values())
    assert j["head"][1] > j["hip_center"][1]  # y is up
    assert symcorr.read_joints(joints_path("s0_rest"), frame=0) == j
    with pytest.raises(ValueError, match="frame 5 requested"):
        symcorr.read_joints(joints_path("s0_rest"), frame=5)
    with pytest.raises(OSError):
        symcorr.read_joints(BODIES / "joints" / "missing.json")


def test_label_matches_the_command_line(rest, cli, tmp_path):
    v, f, j = rest
    labels = symcorr.label(v, f, j)
    assert labels.segments.shape == (len(v),) and labels.segments.dtype == np.int64
    assert labels.names == list(symcorr.SEGMENT_NAMES)
    assert labels.segments.min() >= 0 and len(np.unique(labels.segments)) == 17
    assert labels.corrections["turned_triangles"] == 0
    assert labels.corrections["mirrored_fixed"] is False
    assert 0.5 <= labels.fit_score <= 1.0
    out = tmp_path / "labels.json"
    subprocess.run([cli, "label", mesh_path("s0_rest"), "--joints", joints_path("s0_rest"),
                    "--out", out], check=True, capture_output=True)
    doc = json.loads(out.read_text())
    assert doc["labels"] == labels.segments.tolist()
    assert doc["segments"] == labels.names
    again = pickle.loads(pickle.dumps(labels))
    np.testing.assert_array_equal(again.segments, labels.segments)
    assert again.corrections == labels.corrections and again.joints == labels.joints


def test_label_swaps_back_a_swapped_leg_pair(rest):
    v, f, j = rest
    assert symcorr.label(v, f, j).corrections["limbs_swapped"] is None
    legs = dict(j)
    for n in ("hip", "knee", "ankle", "foot"):
        legs[n + "_left"], legs[n + "_right"] = j[n + "_right"], j[n + "_left"]
    swapped = symcorr.label(v, f, legs)
    assert swapped.corrections["limbs_swapped"] == "legs"
    assert swapped.corrections["mirrored_fixed"] is False
    np.testing.assert_array_equal(swapped.segments, symcorr.label(v, f, j).segments)


def test_label_with_the_makehuman_convention(rest):
    a = symcorr.label(*rest)
    b = symcorr.label(*rest, boundaries="makehuman")
    assert 0 < (a.segments != b.segments).sum() < len(a.segments) // 4


def test_match_equals_the_command_line(rest, tpose, cli, tmp_path):
    """Same pair, same options: the pairs of `symcorr match --dense` exactly."""
    corr = symcorr.match(rest, tpose)
    out = tmp_path / "corr.json"
    subprocess.run([cli, "match", mesh_path("s0_rest"), mesh_path("s1_t-pose"),
                    "--template-joints", joints_path("s0_rest"),
                    "--target-joints", joints_path("s1_t-pose"), "--out", out, "--dense"],
                   check=True, capture_output=True)
    doc = json.loads(out.read_text())
    ref = np.array(doc["pairs"])
    assert corr.pairs.shape == (13380, 2) and corr.pairs.dtype == np.int64
    np.testing.assert_array_equal(corr.pairs, ref[:, :2].astype(np.int64))
    np.testing.assert_allclose(corr.confidence, ref[:, 2], rtol=0, atol=5e-7)
    assert corr.no_counterpart is None and "no_counterpart" not in doc
    assert corr.method == "articulated" and 0 < corr.coverage <= 1
    assert {"attachment", "articulated_icp", "map", "total"} <= set(corr.timings)
    # The articulated method on exact joints: nearly every vertex onto itself (same order).
    assert (corr.pairs[:, 0] == np.arange(13380)).all()
    # The matches as surface points: the file's, on a triangle around each matched vertex.
    corners = np.array([c for c, _ in doc["surface_points"]])
    weights = np.array([w for _, w in doc["surface_points"]])
    np.testing.assert_array_equal(corr.surface_corners, corners)
    np.testing.assert_allclose(corr.surface_weights, weights, rtol=0, atol=5e-7)
    assert (corr.surface_corners == corr.pairs[:, 1:2]).any(axis=1).all()
    assert (corr.surface_weights >= 0).all()
    np.testing.assert_allclose(corr.surface_weights.sum(axis=1), 1.0, atol=1e-12)


def test_match_inputs_and_pickle(rest, tpose):
    corr = symcorr.match(rest, tpose, dense=False, samples=300)
    assert corr.pairs.shape == (300, 2) and len(corr) == 300
    # A Body, a (20, 3) joints array and Fortran-ordered arrays give the same result.
    v, f, j = rest
    arr = np.array([j[n] for n in symcorr.JOINT_NAMES])
    b = symcorr.Body(np.asfortranarray(v), f.astype(np.int32), arr)
    np.testing.assert_array_equal(b.joints, arr)
    again = symcorr.match(b, tpose, dense=False, samples=300)
    np.testing.assert_array_equal(again.pairs, corr.pairs)
    body_copy = pickle.loads(pickle.dumps(b))
    np.testing.assert_array_equal(body_copy.vertices, v)
    np.testing.assert_array_equal(body_copy.faces, f)
    c2 = pickle.loads(pickle.dumps(corr))
    np.testing.assert_array_equal(c2.pairs, corr.pairs)
    np.testing.assert_array_equal(c2.confidence, corr.confidence)
    assert c2.timings == corr.timings and c2.method == corr.method
    np.testing.assert_array_equal(c2.surface_corners, corr.surface_corners)
    np.testing.assert_array_equal(c2.surface_weights, corr.surface_weights)
    assert corr.surface_corners.shape == (300, 3)


def test_prepared_equals_match(rest, tpose):
    p = symcorr.Prepared(rest)
    assert p.method == "articulated" and p.segments.shape == (13380,)
    a = p.match(tpose)
    b = symcorr.match(rest, tpose)
    np.testing.assert_array_equal(a.pairs, b.pairs)
    np.testing.assert_array_equal(a.confidence, b.confidence)
    c = p.match(body("s1_walk-60"))
    assert c.pairs.shape == (13380, 2)


def test_other_methods_sparse(rest):
    target = body("s0_walk-10")
    for method in ["paper", "refined"]:
        c = symcorr.match(rest, target, method=method, dense=False, samples=100)
        assert c.method == method and c.pairs.shape == (100, 2)
        assert np.isfinite(c.confidence).all()


def test_scan_equals_the_command_line_and_matches_as_a_partial_target(rest, cli, tmp_path):
    depth = symcorr.read_depth(SCAN / "depth.png")
    assert depth.dtype == np.uint16 and depth.shape == (480, 640)
    joints = symcorr.read_joints(SCAN / "joints.json")
    v, f, px = symcorr.scan(depth, SCAN / "intrinsics.json", joints)
    k = json.loads((SCAN / "intrinsics.json").read_text())
    v2, f2, px2 = symcorr.scan(depth, {n: k[n] for n in ["fx", "fy", "cx", "cy"]}, joints)
    np.testing.assert_array_equal(v, v2)
    out, pm = tmp_path / "scan.ply", tmp_path / "px.json"
    subprocess.run([cli, "scan", "--depth", SCAN / "depth.png", "--intrinsics",
                    SCAN / "intrinsics.json", "--joints", SCAN / "joints.json",
                    "--joints-frame", "0", "--out", out, "--pixel-map", pm],
                   check=True, capture_output=True)
    cv, cf = symcorr.read_mesh(out)
    np.testing.assert_array_equal(f, cf)
    np.testing.assert_allclose(v, cv, rtol=0, atol=1e-6)
    np.testing.assert_array_equal(px, json.loads(pm.read_text())["pixel_ids"])
    corr = symcorr.match(rest, (v, f, joints))
    assert corr.no_counterpart is not None
    assert len(corr.pairs) + len(corr.no_counterpart) == 13380
    assert 0 < len(corr.no_counterpart) < 13380
    assert corr.view_held >= 0.75 and not corr.turned_about_spine
    # The joints turned half a turn about their spine (facing away from the camera) are turned
    # back, as `symcorr match` does.
    h = np.array(joints["hip_center"])
    a = np.array(joints["shoulder_center"]) - h
    a /= np.linalg.norm(a)
    turned = {n: h + 2 * np.dot(a, np.array(p) - h) * a - (np.array(p) - h)
              for n, p in joints.items()}
    back = symcorr.match(rest, (v, f, turned), dense=False, samples=300)
    assert back.turned_about_spine and back.view_held >= 0.75
    again = pickle.loads(pickle.dumps(back))
    assert again.turned_about_spine and again.view_held == back.view_held


def test_scan_reads_an_image_that_is_not_mirrored():
    # A camera that delivers depth as the lens forms it (Azure Kinect, RealSense): the same
    # view with the columns reversed and ``mirrored`` False gives the same surface.
    depth = symcorr.read_depth(SCAN / "depth.png")
    joints = symcorr.read_joints(SCAN / "joints.json")
    k = json.loads((SCAN / "intrinsics.json").read_text())
    v, f, px = symcorr.scan(depth, SCAN / "intrinsics.json", joints)
    w = depth.shape[1]
    direct = {"fx": k["fx"], "fy": k["fy"], "cx": w - 1 - k["cx"], "cy": k["cy"],
              "mirrored": False}
    vd, fd, pxd = symcorr.scan(np.ascontiguousarray(depth[:, ::-1]), direct, joints)
    assert len(vd) == len(v) and len(fd) == len(f)
    mirrored_px = (pxd // w) * w + (w - 1 - pxd % w)
    order = np.argsort(px)
    at = order[np.searchsorted(px, mirrored_px, sorter=order)]
    np.testing.assert_allclose(vd, v[at], rtol=0, atol=1e-9)
    with pytest.raises(ValueError, match="mirrored"):
        symcorr.scan(depth, {**direct, "mirrored": "no"}, joints)
    with pytest.raises(ValueError, match='unknown key "mirror"'):
        symcorr.scan(depth, {**{n: k[n] for n in ["fx", "fy", "cx", "cy"]}, "mirror": False},
                     joints)
    # The file's own keys, "format" included, are accepted as a dict.
    v2, _, _ = symcorr.scan(depth, k, joints)
    np.testing.assert_array_equal(v, v2)
    # The reversed image read as mirrored puts the pose on the other side: refused.
    with pytest.raises(ValueError, match='"mirrored": false'):
        symcorr.scan(np.ascontiguousarray(depth[:, ::-1]), k, joints)


def test_scan_undoes_a_lens_distortion():
    # OpenCV's model (k1, k2, p1, p2, k3): every vertex lies on the ray the lens bends onto its
    # pixel, checked with the forward formula here (the library inverts it by Newton's method).
    depth = symcorr.read_depth(SCAN / "depth.png")
    joints = symcorr.read_joints(SCAN / "joints.json")
    k = json.loads((SCAN / "intrinsics.json").read_text())
    k1, k2, p1, p2, k3 = 0.09, -0.27, 0.002, -0.001, 0.09
    lens = {n: k[n] for n in ["fx", "fy", "cx", "cy"]}
    v, _, px = symcorr.scan(depth, {**lens, "distortion": [k1, k2, p1, p2, k3]}, joints)
    w = depth.shape[1]
    # The stored image is mirrored: its a = (u - cx)/fx is +x/z, its b = (v - cy)/fy is -y/z.
    a, b = v[:, 0] / v[:, 2], -v[:, 1] / v[:, 2]
    r2 = a * a + b * b
    radial = 1 + k1 * r2 + k2 * r2**2 + k3 * r2**3
    ad = a * radial + 2 * p1 * a * b + p2 * (r2 + 2 * a * a)
    bd = b * radial + p1 * (r2 + 2 * b * b) + 2 * p2 * a * b
    # The scan keeps its rays in single precision: 1e-7 of a ray, 1e-5 px here.
    np.testing.assert_allclose(k["cx"] + k["fx"] * ad, px % w, rtol=0, atol=1e-5)
    np.testing.assert_allclose(k["cy"] + k["fy"] * bd, px // w, rtol=0, atol=1e-5)
    plain, _, _ = symcorr.scan(depth, lens, joints)
    assert len(plain) > 0 and not np.allclose(plain[:100], v[:100])
    with pytest.raises(ValueError, match="6 coefficients"):
        symcorr.scan(depth, {**lens, "distortion": [0.1] * 6}, joints)
    with pytest.raises(ValueError, match="folds"):
        symcorr.scan(depth, {**lens, "distortion": [-0.9, 0, 0, 0]}, joints)


def test_track_equals_the_command_line(cli, tmp_path):
    template = symcorr.Body(*body("s0_rest"))
    frames = list(symcorr.track(RECORDING, RECORDING / "joints.json", template,
                                frames=range(3)))
    assert [f.index for f in frames] == [0, 1, 2]
    assert all(f.status == "ok" for f in frames)
    f0 = frames[0]
    assert f0.target_of.shape == (13380,) and f0.target_of.dtype == np.int32
    assert f0.posed.shape == (13380, 3) and f0.scan[0].shape[1] == 3
    assert f0.target_of.max() < len(f0.scan[0]) and (f0.target_of >= 0).any()
    assert all(0.5 <= f.view_held <= 1 for f in frames)
    assert pickle.loads(pickle.dumps(f0)).index == 0
    out = tmp_path / "track"
    subprocess.run([cli, "track", RECORDING, "--joints", RECORDING / "joints.json", "--out", out,
                    "--frames", "0..3", "--template", mesh_path("s0_rest"),
                    "--template-joints", joints_path("s0_rest")],
                   check=True, capture_output=True)
    ref = np.load(out / "correspondence.npy")
    np.testing.assert_array_equal(np.stack([f.target_of for f in frames]), ref)
    # A Prepared template, and an iterator dropped early.
    it = symcorr.track(RECORDING, RECORDING / "joints.json", symcorr.Prepared(template),
                       frames=[2, 0])
    assert len(it) == 2
    assert next(it).index == 2
    del it
    with pytest.raises(ValueError, match="frame 60 is not in the recording"):
        symcorr.track(RECORDING, RECORDING / "joints.json", template, frames=[60])
    with pytest.raises(ValueError, match="dense"):
        symcorr.track(RECORDING, RECORDING / "joints.json",
                      symcorr.Prepared(template, dense=False), frames=[0])
    with pytest.raises(OSError):
        symcorr.track(RECORDING / "missing", RECORDING / "joints.json", template)


def test_track_refuses_a_mirrored_joint_log(tmp_path):
    log = json.loads((RECORDING / "joints.json").read_text())
    for f in log["frames"]:
        for p in f["joints"].values():
            p[0] = -p[0]
    mirrored = tmp_path / "mirrored.json"
    mirrored.write_text(json.dumps(log))
    template = symcorr.Body(*body("s0_rest"))
    with pytest.raises(ValueError, match="does not fit the depth frames"):
        symcorr.track(RECORDING, mirrored, template, joint_offset=0.04)
    it = symcorr.track(RECORDING, mirrored, template, frames=[20], joint_offset=0.04,
                       check_log=False)
    assert len(it) == 1


def test_track_reads_an_azure_kinect_log():
    # The recording's log as the Azure Kinect's tracker writes it (32 joints in its own camera
    # frame, millimetres, a face): read like any joint file, tracked like the Kinect v1 log.
    template = symcorr.Body(*body("s0_rest"))
    v1 = list(symcorr.track(RECORDING, RECORDING / "joints.json", template, frames=[20, 21],
                            joint_offset=0.04))
    azure = list(symcorr.track(RECORDING, RECORDING / "joints_k4abt.json", template,
                               frames=[20, 21], joint_offset=0.04))
    assert [f.status for f in azure] == ["ok", "ok"]
    shown = v1[0].target_of >= 0
    assert (azure[0].target_of >= 0).sum() > 0.9 * shown.sum()
    head = symcorr.read_joints(RECORDING / "joints.json", frame=20)["head"]
    head_azure = symcorr.read_joints(RECORDING / "joints_k4abt.json", frame=20)["head"]
    np.testing.assert_allclose(head_azure, head, atol=1e-9)


def test_track_takes_intrinsics_in_the_recordings_place():
    # The recording's own intrinsics given again: the same frames. Said to be unmirrored,
    # which its depth is not, they make the log stick out of the body: refused by the check.
    template = symcorr.Body(*body("s0_rest"))
    k = json.loads((RECORDING / "intrinsics.json").read_text())
    plain = list(symcorr.track(RECORDING, RECORDING / "joints.json", template, frames=[20],
                               joint_offset=0.04))
    given = list(symcorr.track(RECORDING, RECORDING / "joints.json", template, frames=[20],
                               joint_offset=0.04, intrinsics=k))
    np.testing.assert_array_equal(given[0].target_of, plain[0].target_of)
    with pytest.raises(ValueError, match="mirrored"):
        list(symcorr.track(RECORDING, RECORDING / "joints.json", template, joint_offset=0.04,
                           intrinsics={**k, "mirrored": False}))
    with pytest.raises(ValueError, match="width = 640"):
        symcorr.track(RECORDING, RECORDING / "joints.json", template,
                      intrinsics={**k, "width": 640})


def restamped(tmp_path, seconds):
    """The recording's joint log with every time `seconds` later, written in `tmp_path`."""
    log = json.loads((RECORDING / "joints.json").read_text())
    for f in log["frames"]:
        f["time_s"] += seconds
    path = tmp_path / f"log_{seconds}.json"
    path.write_text(json.dumps(log))
    return path


def test_track_refuses_a_log_on_another_clock(tmp_path):
    # Stamped from the epoch: no log frame near any depth frame's time.
    epoch = restamped(tmp_path, 1.7e9)
    template = symcorr.Body(*body("s0_rest"))
    with pytest.raises(ValueError, match="different clocks"):
        symcorr.track(RECORDING, epoch, template, joint_offset=0.04)
    # No frames: nothing to compare, nothing to track.
    assert len(symcorr.track(RECORDING, epoch, template, frames=[], joint_offset=0.04)) == 0


def test_track_estimates_the_joint_offset(tmp_path):
    # The log's clock a second later still: "auto" finds it, a fixed 0.04 is refused.
    late = restamped(tmp_path, 1.0)
    template = symcorr.Body(*body("s0_rest"))
    frames = list(symcorr.track(RECORDING, late, template, frames=[40], joint_offset="auto"))
    assert frames[0].status == "ok"
    with pytest.raises(ValueError, match="does not fit the depth frames"):
        symcorr.track(RECORDING, late, template, frames=range(30, 60), joint_offset=0.04)
    with pytest.raises(ValueError, match="auto"):
        symcorr.track(RECORDING, late, template, frames=[40], joint_offset="later")


def test_help_reads_well():
    doc = symcorr.match.__doc__
    assert "Example" in doc and "Correspondence" in doc
    assert symcorr.match.__text_signature__.startswith("(template, target, method=")
    for name in symcorr.__all__:
        obj = getattr(symcorr, name)
        if callable(obj):
            assert obj.__doc__, name
