#!/usr/bin/env python3
"""Writes the bad-input corpus: tests/bad_inputs/cases/NAME/ (small input files) and
tests/bad_inputs/cases.json (what to run and what to expect). Run from anywhere:

    python3 tests/bad_inputs/make.py

The test tests/bad_inputs.rs runs the binary over every case (see its docs for the
placeholders). Each case says the exit status, the words its one stderr line must contain
(the file it blames and the cause), the files that must not appear and the inputs that must
stay byte-identical. Meaningful-but-wrong inputs (`dataset` cases) run `symcorr bench` on a
copy of fixtures/synth/bodies with one body changed and must give 0 flips, or be refused.
"""
import json
import math
import os
import shutil
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
CASES = os.path.join(HERE, "cases")

TET_V = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
TET_F = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]

cases = []


def case(name, args, exit, stderr=(), absent=(), unchanged=(), files=None, dataset=None):
    d = os.path.join(CASES, name)
    os.makedirs(d, exist_ok=True)
    for fname, data in (files or {}).items():
        path = os.path.join(d, fname)
        if isinstance(data, tuple) and data[0] == "symlink":
            os.symlink(data[1], path)
        else:
            with open(path, "wb") as f:
                f.write(data if isinstance(data, bytes) else data.encode())
    c = {"name": name, "args": args, "exit": exit, "stderr": list(stderr),
         "absent": list(absent), "unchanged": list(unchanged)}
    if dataset:
        c["dataset"] = dataset
    cases.append(c)


def ply_ascii(v=TET_V, f=TET_F, nv=None, vlines=None):
    out = ["ply", "format ascii 1.0", f"element vertex {nv if nv is not None else len(v)}",
           "property float x", "property float y", "property float z",
           f"element face {len(f)}", "property list uchar int vertex_indices", "end_header"]
    out += vlines if vlines is not None else [" ".join(map(str, p)) for p in v]
    out += [f"3 {a} {b} {c}" for a, b, c in f]
    return "\n".join(out) + "\n"


def ply_binary(v=TET_V, f=TET_F):
    head = ("ply\nformat binary_little_endian 1.0\n"
            f"element vertex {len(v)}\nproperty float x\nproperty float y\nproperty float z\n"
            f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n")
    body = b"".join(struct.pack("<3f", *p) for p in v)
    body += b"".join(struct.pack("<B3i", 3, *t) for t in f)
    return head.encode() + body


def gltf(mode=4, count=None, uri=None, byte_length=None):
    pos = b"".join(struct.pack("<3f", *p) for p in TET_V)
    idx = b"".join(struct.pack("<3H", *t) for t in TET_F)
    data = pos + idx
    buf = {"byteLength": byte_length if byte_length is not None else len(data)}
    buf["uri"] = uri if uri is not None else "data:application/octet-stream;base64," + \
        __import__("base64").b64encode(data).decode()
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [buf],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos)},
                        {"buffer": 0, "byteOffset": len(pos), "byteLength": len(idx)}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": count or 4, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 1]},
            {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": mode}]}],
        "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0,
    }
    return json.dumps(doc)


def joints_doc(fn):
    """The s1_walk-60 fixture joints with every position mapped by fn."""
    with open(os.path.join(ROOT, "fixtures/synth/bodies/joints/s1_walk-60.json")) as f:
        d = json.load(f)
    for fr in d["frames"]:
        for k, v in fr["joints"].items():
            if isinstance(v, list):
                fr["joints"][k] = fn(v)
            elif isinstance(v, dict) and "position" in v:
                v["position"] = fn(v["position"])
    return json.dumps(d)


def turned(deg):
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return lambda p: [c * p[0] + s * p[2], p[1], -s * p[0] + c * p[2]]


F = "{F}"
J = F + "/joints/s0_rest.json"


def label(mesh, joints=J, extra=()):
    return ["label", mesh, "--joints", joints, "--out", "{O}/labels.json",
            "--ply", "{O}/labels.ply", *extra]


def main():
    shutil.rmtree(CASES, ignore_errors=True)
    os.makedirs(CASES)
    # Malformed meshes: exit 1, one line naming the mesh and the cause, no output.
    out = ["{O}/labels.json", "{O}/labels.ply"]
    mesh_cases = {
        "ply_truncated_binary": (ply_binary()[:-7], ["m.ply"]),
        "ply_header_lies_vertex_count": (ply_ascii(nv=9), ["m.ply"]),
        "ply_nan_vertex": (ply_ascii(vlines=["nan 0 0", "1 0 0", "0 1 0", "0 0 1"]), ["m.ply", "finite"]),
        "ply_face_index_out_of_range": (ply_ascii(f=TET_F[:3] + [(1, 2, 9)]), ["m.ply", "9"]),
        "ply_ascii_extra_tokens": (ply_ascii(vlines=["0 0 0 7", "1 0 0", "0 1 0", "0 0 1"]), ["m.ply", "vertex"]),
        "ply_empty_file": (b"", ["m.ply"]),
    }
    for name, (data, words) in mesh_cases.items():
        case(name, label("{C}/m.ply"), 1, words, out, files={"m.ply": data})
    case("off_truncated", label("{C}/m.off"), 1, ["m.off"], out,
         files={"m.off": "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n"})
    case("obj_bad_index", label("{C}/m.obj"), 1, ["m.obj"], out,
         files={"m.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n"})
    case("gltf_accessor_count_lies", label("{C}/m.gltf"), 1, ["m.gltf"], out,
         files={"m.gltf": gltf(count=400)})
    case("gltf_lines_only", label("{C}/m.gltf"), 1, ["m.gltf", "LINES"], out,
         files={"m.gltf": gltf(mode=1)})
    case("gltf_buffer_outside_folder", label("{C}/m.gltf"), 1, ["m.gltf", "folder"], out,
         files={"m.gltf": gltf(uri="../../etc/passwd", byte_length=48 + 24)})
    case("gltf_buffer_absolute", label("{C}/m.gltf"), 1, ["m.gltf", "absolute"], out,
         files={"m.gltf": gltf(uri="/dev/zero", byte_length=72)})
    case("gltf_buffer_short", label("{C}/m.gltf"), 1, ["m.gltf", "byteLength"], out,
         files={"m.gltf": gltf(uri="b.bin", byte_length=72), "b.bin": b"\0" * 10})
    case("mesh_is_dev_zero", ["--max-input-size", "1M"] + label("{C}/zero.ply"), 1,
         ["zero.ply", "input limit"], out, files={"zero.ply": ("symlink", "/dev/zero")})
    # Malformed or meaningless joints: the joints file is blamed.
    good = "{F}/meshes/s0_rest.ply"
    case("joints_unrecognised_text", label(good, "{C}/j.txt"), 1, ["j.txt", "unrecognised"], out,
         files={"j.txt": "hello world\nthis is not a skeleton\n"})
    one_point = json.dumps({"format": "symcorr.joints/1", "skeleton": "kinect_v1", "units": "m",
                            "frames": [{"time_s": 0.0, "joints": {
                                n: [0.1, 0.2, 0.3] for n in
                                ["hip_center", "spine", "shoulder_center", "head", "shoulder_left",
                                 "elbow_left", "wrist_left", "hand_left", "shoulder_right",
                                 "elbow_right", "wrist_right", "hand_right", "hip_left", "knee_left",
                                 "ankle_left", "foot_left", "hip_right", "knee_right",
                                 "ankle_right", "foot_right"]}}]})
    case("joints_all_at_one_point", label(good, "{C}/j.json"), 1, ["j.json", "skeleton"], out,
         files={"j.json": one_point})
    case("joints_nan_json", label(good, "{C}/j.json"), 1, ["j.json"], out,
         files={"j.json": '{"format":"symcorr.joints/1","frames":[{"time_s":0,"joints":{"head":[NaN,0,0]}}]}'})
    case("joints_frame_out_of_range", label(good, J, ["--frame", "5"]), 1, ["s0_rest.json", "frame"], out)
    # Joints of another body and camera, and of another pose: refused, naming the check.
    case("joints_other_body", label(good, "{K}/standing_v1.json"), 1,
         ["standing_v1.json", "does not fit"], out)
    case("joints_other_body_text", label(good, "{K}/standing_v1.txt"), 1,
         ["standing_v1.txt", "does not fit"], out)
    case("joints_other_pose", label(good, "{F}/joints/s0_t-pose.json"), 1,
         ["s0_t-pose.json", "does not fit"], out)
    # Outputs: never over an input, never half-written.
    case("out_is_the_input_mesh", ["label", "{C}/m.ply", "--joints", J, "--out", "{C}/m.ply"], 1,
         ["m.ply", "input"], unchanged=["{C}/m.ply"], files={"m.ply": ply_ascii()})
    case("out_into_missing_folder", label(good, extra=["--glb", "{O}/missing/x.glb"]), 1,
         ["missing"], out + ["{O}/missing/x.glb"])
    case("out_is_a_folder", ["label", good, "--joints", J, "--out", "{C}"], 1, ["director"],
         files={"keep": "x"}, unchanged=["{C}/keep"])
    case("match_ply_out_is_a_file",
         ["match", good, "{F}/meshes/s0_walk-60.ply", "--template-joints", J, "--target-joints",
          "{F}/joints/s0_walk-60.json", "--out", "{O}/c.json", "--ply-out", "{C}/file"], 1,
         ["file"], ["{O}/c.json"], unchanged=["{C}/file"], files={"file": "not a folder"})
    # Bounds instead of panics.
    case("spectrum_k_too_large", ["spectrum", good, "--k", "13379"], 1, ["eigenpairs"])
    case("paper_eigenpairs_too_large",
         ["match", good, "{F}/meshes/s0_walk-60.ply", "--template-joints", J, "--target-joints",
          "{F}/joints/s0_walk-60.json", "--out", "{O}/c.json", "--method", "paper",
          "--eigenpairs", "13000"], 1, ["eigenpairs"], ["{O}/c.json"])
    case("scan_discontinuity_nan",
         ["scan", "--depth", "{F}/../scan/depth.png", "--intrinsics", "{F}/../scan/intrinsics.json",
          "--joints", "{F}/../scan/joints.json", "--out", "{O}/s.ply", "--discontinuity", "NaN"],
         1, ["discontinuity"], ["{O}/s.ply"])
    with open(os.path.join(ROOT, "fixtures/synth/scan/joints.json")) as f:
        shifted = json.load(f)
    for fr in shifted["frames"]:
        for k, v in fr["joints"].items():
            p = v if isinstance(v, list) else v["position"]
            p[0] += 0.8
    case("scan_joints_of_another_frame",
         ["scan", "--depth", "{F}/../scan/depth.png", "--intrinsics", "{F}/../scan/intrinsics.json",
          "--joints", "{C}/j.json", "--out", "{O}/s.ply"],
         1, ["do not lie on the body"], ["{O}/s.ply"], files={"j.json": json.dumps(shifted)})
    case("scan_intrinsics_fx_1e308",
         ["scan", "--depth", "{F}/../scan/depth.png", "--intrinsics", "{C}/k.json",
          "--joints", "{F}/../scan/joints.json", "--out", "{O}/s.ply"],
         1, ["k.json", "fx"], ["{O}/s.ply"],
         files={"k.json": json.dumps({"format": "symcorr.intrinsics/1", "width": 640, "height": 480,
                                      "fx": 1e308, "fy": 580.0, "cx": 319.5, "cy": 239.5})})
    # Meaningful but wrong: 0 flips (bench on a copy of the bodies with one body changed).
    for deg in (30, 90, 180):
        case(f"joints_turned_{deg}", ["bench", "{D}", "--mode", "dense", "--json", "{O}/b.json"], 0,
             files={"joints.json": joints_doc(turned(deg))},
             dataset={"body": "s1_walk-60", "joints": "joints.json"})
    case("mesh_in_mm_joints_in_m", ["bench", "{D}", "--mode", "dense", "--json", "{O}/b.json"], 0,
         dataset={"body": "s1_walk-60", "scale_mesh": 1000.0})
    case("mesh_and_joints_in_mm", ["bench", "{D}", "--mode", "dense", "--json", "{O}/b.json"], 0,
         files={"joints.json": joints_doc(lambda p: [1000.0 * x for x in p])},
         dataset={"body": "s1_walk-60", "scale_mesh": 1000.0, "joints": "joints.json"})
    case("faces_half_flipped", ["bench", "{D}", "--mode", "dense", "--json", "{O}/b.json"], 0,
         dataset={"body": "s1_walk-60", "flip_faces": "right_half"})
    with open(os.path.join(HERE, "cases.json"), "w") as f:
        json.dump(cases, f, indent=1)
        f.write("\n")
    print(f"{len(cases)} cases in {CASES}")


if __name__ == "__main__":
    main()
