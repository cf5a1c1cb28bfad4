//! A procedural test body: a union of capsules around a known skeleton, meshed by surface nets,
//! with reference labels (the segment whose capsule surface is nearest). Used by the tests,
//! benches and documentation examples; not part of the stable API.

use crate::{bone_segment, Joint, Segment, Skeleton, BONES};
use nalgebra::{Point3, Vector3};
use std::collections::HashMap;
use symcorr_mesh::geometry::closest_on_segment;
use symcorr_mesh::TriMesh;

/// Capsule radius per bone of [`BONES`] (metres at scale 1).
pub const RADII: [f64; 19] = [
    0.13, 0.14, 0.08, 0.06, 0.05, 0.04, 0.04, 0.06, 0.05, 0.04, 0.04, 0.10, 0.075, 0.055, 0.045,
    0.10, 0.075, 0.055, 0.045,
];

/// An A-pose skeleton in metres × `s`: y up, facing +z, the subject's left at +x.
pub fn t_pose(s: f64) -> Skeleton {
    use Joint as J;
    let mut p = [Point3::origin(); 20];
    let mut set = |j: Joint, x: [f64; 3]| p[j.index()] = Point3::from(x) * s;
    set(J::HipCenter, [0.0, 1.0, 0.0]);
    set(J::Spine, [0.0, 1.2, 0.0]);
    set(J::ShoulderCenter, [0.0, 1.45, 0.0]);
    set(J::Head, [0.0, 1.65, 0.0]);
    for side in [1.0, -1.0] {
        let (sh, el, wr, ha, hi, kn, an, fo) = if side > 0.0 {
            (
                J::ShoulderLeft,
                J::ElbowLeft,
                J::WristLeft,
                J::HandLeft,
                J::HipLeft,
                J::KneeLeft,
                J::AnkleLeft,
                J::FootLeft,
            )
        } else {
            (
                J::ShoulderRight,
                J::ElbowRight,
                J::WristRight,
                J::HandRight,
                J::HipRight,
                J::KneeRight,
                J::AnkleRight,
                J::FootRight,
            )
        };
        set(sh, [0.18 * side, 1.42, 0.0]);
        set(el, [0.40 * side, 1.25, 0.0]);
        set(wr, [0.58 * side, 1.08, 0.0]);
        set(ha, [0.64 * side, 1.02, 0.0]);
        set(hi, [0.10 * side, 0.95, 0.0]);
        set(kn, [0.14 * side, 0.52, 0.0]);
        set(an, [0.16 * side, 0.10, 0.0]);
        set(fo, [0.17 * side, 0.04, 0.14]);
    }
    Skeleton::from_positions(p)
}

/// Signed distance to the capsule union and the nearest capsule's bone.
fn sdf(x: &Point3<f64>, sk: &Skeleton, s: f64) -> (f64, usize) {
    let mut best = (f64::INFINITY, 0);
    for (b, bone) in BONES.iter().enumerate() {
        let d = closest_on_segment(x, &sk.position(bone.parent), &sk.position(bone.child)).1
            - RADII[b] * s;
        if d < best.0 {
            best = (d, b);
        }
    }
    best
}

/// Meshes the capsule union around `sk` (whose scale relative to metres is inferred from the
/// hip→shoulder distance) with grid step `step`, returning the mesh and per-vertex reference
/// labels (segment of the nearest capsule).
pub fn capsule_body(sk: &Skeleton, step: f64) -> (TriMesh, Vec<Segment>) {
    let s = nalgebra::distance(
        &sk.position(Joint::HipCenter),
        &sk.position(Joint::ShoulderCenter),
    ) / 0.45;
    let margin = Vector3::repeat(0.2 * s);
    let mut lo = Point3::from([f64::INFINITY; 3]);
    let mut hi = Point3::from([f64::NEG_INFINITY; 3]);
    for p in &sk.positions {
        lo = lo.inf(&(p - margin));
        hi = hi.sup(&(p + margin));
    }
    let span = hi - lo;
    let dims: [usize; 3] = std::array::from_fn(|k| (span[k] / step).ceil() as usize + 1);
    let at = |i: usize, j: usize, k: usize| -> Point3<f64> {
        lo + Vector3::new(i as f64, j as f64, k as f64) * step
    };
    let idx = |i: usize, j: usize, k: usize| (k * dims[1] + j) * dims[0] + i;
    let mut f = vec![0.0; dims[0] * dims[1] * dims[2]];
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                f[idx(i, j, k)] = sdf(&at(i, j, k), sk, s).0;
            }
        }
    }
    // One vertex per cell with a sign change: the mean of its edges' zero crossings.
    let mut cell_vertex: HashMap<(usize, usize, usize), u32> = HashMap::new();
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let corner = |c: usize| [(c & 1), (c >> 1) & 1, (c >> 2) & 1];
    const EDGES: [(usize, usize); 12] = [
        (0, 1),
        (2, 3),
        (4, 5),
        (6, 7),
        (0, 2),
        (1, 3),
        (4, 6),
        (5, 7),
        (0, 4),
        (1, 5),
        (2, 6),
        (3, 7),
    ];
    for k in 0..dims[2] - 1 {
        for j in 0..dims[1] - 1 {
            for i in 0..dims[0] - 1 {
                let val: [f64; 8] = std::array::from_fn(|c| {
                    let o = corner(c);
                    f[idx(i + o[0], j + o[1], k + o[2])]
                });
                if val.iter().all(|&v| v < 0.0) || val.iter().all(|&v| v >= 0.0) {
                    continue;
                }
                let mut acc = Vector3::zeros();
                let mut n = 0.0;
                for (a, b) in EDGES {
                    if (val[a] < 0.0) != (val[b] < 0.0) {
                        let t = val[a] / (val[a] - val[b]);
                        let (oa, ob) = (corner(a), corner(b));
                        let pa = at(i + oa[0], j + oa[1], k + oa[2]);
                        let pb = at(i + ob[0], j + ob[1], k + ob[2]);
                        acc += (pa + (pb - pa) * t).coords;
                        n += 1.0;
                    }
                }
                cell_vertex.insert((i, j, k), positions.len() as u32);
                positions.push((acc * (1.0 / n)).into());
            }
        }
    }
    // One quad per grid edge with a sign change, between the four cells around it.
    let mut triangles = Vec::new();
    for k in 1..dims[2] - 1 {
        for j in 1..dims[1] - 1 {
            for i in 1..dims[0] - 1 {
                let v0 = f[idx(i, j, k)];
                for axis in 0..3 {
                    let (ni, nj, nk) = match axis {
                        0 => (i + 1, j, k),
                        1 => (i, j + 1, k),
                        _ => (i, j, k + 1),
                    };
                    if ni >= dims[0] || nj >= dims[1] || nk >= dims[2] {
                        continue;
                    }
                    let v1 = f[idx(ni, nj, nk)];
                    if (v0 < 0.0) == (v1 < 0.0) {
                        continue;
                    }
                    // Cells around the edge, counter-clockwise seen from the edge's + end.
                    let cells = match axis {
                        0 => [(i, j - 1, k - 1), (i, j, k - 1), (i, j, k), (i, j - 1, k)],
                        1 => [(i - 1, j, k - 1), (i - 1, j, k), (i, j, k), (i, j, k - 1)],
                        _ => [(i - 1, j - 1, k), (i, j - 1, k), (i, j, k), (i - 1, j, k)],
                    };
                    let q: Vec<u32> = cells
                        .iter()
                        .filter_map(|c| cell_vertex.get(c).copied())
                        .collect();
                    if q.len() != 4 {
                        continue;
                    }
                    let q = if v0 < 0.0 {
                        [q[0], q[1], q[2], q[3]]
                    } else {
                        [q[3], q[2], q[1], q[0]]
                    };
                    triangles.push([q[0], q[1], q[2]]);
                    triangles.push([q[0], q[2], q[3]]);
                }
            }
        }
    }
    let labels = positions
        .iter()
        .map(|&x| bone_segment(sdf(&x.into(), sk, s).1))
        .collect();
    (
        TriMesh {
            positions,
            triangles,
        },
        labels,
    )
}
