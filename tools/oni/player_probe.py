#!/usr/bin/env python3
"""What OpenNI2's own file player (libOpenNI2.so.0, OniFile driver) makes of an .oni file and of
variants of it with one record changed: how many depth frames it plays, and whether they are the
file's frames (pixels and timestamps). Reproduces docs/decisions/2026-12-03-oni-writer.md:

    cargo run -p symcorr-synth -- oni fixtures/synth/recording --out /tmp/fixture.oni
    python3 tools/oni/player_probe.py /tmp/fixture.oni

Needs only Python 3 and libopenni2 (ctypes); each variant is played in its own process, as
OpenNI2's context is process-global.
"""
import ctypes as C
import os
import struct
import subprocess
import sys
import tempfile

MAGIC = 0x0052494E
GENERAL_PROPERTY, NEW_DATA, END, NODE_ADDED, SEEK_TABLE = 0x06, 0x0A, 0x0B, 0x0D, 0x0E


def records(b):
    """(position, type, fields size, payload size) of every record."""
    pos, out = 24, []
    while pos + 28 <= len(b):
        magic, kind, _node, fields, payload = struct.unpack_from("<5I", b, pos)
        if magic != MAGIC:
            break
        out.append((pos, kind, fields, payload))
        pos += fields + payload
    return out


def prop_name(b, pos):
    n = struct.unpack_from("<I", b, pos + 28)[0]
    return b[pos + 32:pos + 32 + n - 1].decode()


def frames_in_file(b):
    return [(struct.unpack_from("<Q", b, p + 28)[0], b[p + f:p + f + n])
            for p, k, f, n in records(b) if k == NEW_DATA]


def without(b, keep):
    """The file without the records `keep` refuses; the node's seek table position zeroed."""
    out = bytearray(b[:24])
    for p, k, f, n in records(b):
        if keep(b, p, k):
            out += b[p:p + f + n]
    for p, k, f, n in records(bytes(out)):
        if k == NODE_ADDED:
            out[p + f - 8:p + f] = bytes(8)
    return bytes(out)


def short_cropping(b):
    """xnCropping's value cut to 10 bytes (the size with a one-byte XnBool)."""
    out = bytearray(b[:24])
    for p, k, f, n in records(b):
        r = bytearray(b[p:p + f + n])
        if k == GENERAL_PROPERTY and prop_name(b, p) == "xnCropping":
            name_len = struct.unpack_from("<I", r, 28)[0]
            at = 32 + name_len
            r = r[:at] + struct.pack("<I", 10) + r[at + 4:at + 14]
            struct.pack_into("<I", r, 12, len(r))
        out += r
    return bytes(out)


def play(path):
    """Plays `path` in manual mode: (frames as (timestamp, bytes), or an error string)."""
    ni = C.CDLL("libOpenNI2.so.0")

    class VideoMode(C.Structure):
        _fields_ = [("pf", C.c_int), ("x", C.c_int), ("y", C.c_int), ("fps", C.c_int)]

    class Frame(C.Structure):
        _fields_ = [("dataSize", C.c_int), ("data", C.c_void_p), ("sensorType", C.c_int),
                    ("timestamp", C.c_uint64), ("frameIndex", C.c_int), ("width", C.c_int),
                    ("height", C.c_int), ("vm", VideoMode), ("crop", C.c_int), ("cx", C.c_int),
                    ("cy", C.c_int), ("stride", C.c_int)]
    assert ni.oniInitialize(2002) == 0
    dev, st = C.c_void_p(), C.c_void_p()
    if ni.oniDeviceOpen(path.encode(), C.byref(dev)) != 0:
        return "the file does not open"
    speed, repeat = C.c_float(-1.0), C.c_int(0)
    ni.oniDeviceSetProperty(dev, 100, C.byref(speed), 4)
    ni.oniDeviceSetProperty(dev, 101, C.byref(repeat), 4)
    if ni.oniDeviceCreateStream(dev, 3, C.byref(st)) != 0 or ni.oniStreamStart(st) != 0:
        return "no depth stream"
    got = []
    while True:
        h, idx = C.c_void_p(st.value), C.c_int()
        if ni.oniWaitForAnyStream(C.byref(h), 1, C.byref(idx), 1500) != 0:
            return got
        f = C.POINTER(Frame)()
        ni.oniStreamReadFrame(st, C.byref(f))
        got.append((f.contents.timestamp, C.string_at(f.contents.data, f.contents.dataSize)))
        ni.oniFrameRelease(f)


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--play":
        got = play(sys.argv[2])
        b = open(sys.argv[2], "rb").read()
        if isinstance(got, str):
            print(got)
        else:
            n = len(frames_in_file(b))
            if not got:
                print(f"0 of {n} frames played")
            elif got == frames_in_file(b)[:len(got)]:
                print(f"{len(got)} of {n} frames played, with the file's pixels and timestamps")
            else:
                print(f"{len(got)} of {n} frames played, with OTHER pixels or timestamps")
        sys.stdout.flush()
        os._exit(0)  # oniShutdown crashes on OpenNI 2.2; leave without it
    b = open(sys.argv[1], "rb").read()
    variants = [
        ("as written", b),
        ("without xnCropping", without(b, lambda b, p, k: not (
            k == GENERAL_PROPERTY and prop_name(b, p) == "xnCropping"))),
        ("xnCropping of 10 bytes", short_cropping(b)),
        ("without xnFOV", without(b, lambda b, p, k: not (
            k == GENERAL_PROPERTY and prop_name(b, p) == "xnFOV"))),
        ("without the seek table", without(b, lambda b, p, k: k != SEEK_TABLE)),
        ("without END", without(b, lambda b, p, k: k != END)),
    ]
    with tempfile.TemporaryDirectory() as d:
        for name, data in variants:
            path = os.path.join(d, "v.oni")
            open(path, "wb").write(data)
            r = subprocess.run([sys.executable, __file__, "--play", path],
                               capture_output=True, text=True, timeout=300)
            print(f"{name}: {r.stdout.strip() or r.stderr.strip()}")


if __name__ == "__main__":
    main()
