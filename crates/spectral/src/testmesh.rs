//! Synthetic test meshes built from first principles, shared by this crate's tests, benches and
//! examples (not part of the public API: hidden from the docs, may change without notice).
//!
//! The generators only use the mesh crate (`TriMesh::new`, the icosahedron of its `testmesh`);
//! nothing here depends on the spectral code under test.

use nalgebra::{Point3, Vector3};
use std::collections::HashMap;
use symcorr_mesh::testmesh::{normalize, ICO_FACES, ICO_VERTICES};
use symcorr_mesh::TriMesh;

fn build(pos: Vec<[f64; 3]>, tris: Vec<[u32; 3]>) -> TriMesh {
    // Invariant: every generator here emits finite positions and in-range, non-repeated
    // triangle indices, which is all `TriMesh::new` checks.
    TriMesh::new(pos, tris).expect("generated meshes are valid by construction")
}

/// Unit icosphere: icosahedron subdivided `level` times (midpoint split), vertices projected to
/// the sphere. `10·4^level + 2` vertices; icosahedral symmetry, so eigenvalues repeat exactly.
pub fn icosphere(level: usize) -> TriMesh {
    let mut pos: Vec<[f64; 3]> = ICO_VERTICES.iter().map(|&p| normalize(p)).collect();
    let mut tris: Vec<[u32; 3]> = ICO_FACES.to_vec();
    for _ in 0..level {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut next = Vec::with_capacity(tris.len() * 4);
        for tri in &tris {
            let mut m = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                m[k] = *mid.entry(key).or_insert_with(|| {
                    let (pa, pb) = (pos[a as usize], pos[b as usize]);
                    pos.push(normalize((Vector3::from(pa) + Vector3::from(pb)).into()));
                    (pos.len() - 1) as u32
                });
            }
            next.push([tri[0], m[0], m[2]]);
            next.push([tri[1], m[1], m[0]]);
            next.push([tri[2], m[2], m[1]]);
            next.push([m[0], m[1], m[2]]);
        }
        tris = next;
    }
    build(pos, tris)
}

/// Class-I geodesic sphere of frequency `f` (each icosahedron face split f×f, projected):
/// `10 f² + 2` vertices, so any size, e.g. `f = 100` → 100,002 vertices.
pub fn geodesic_sphere(f: usize) -> TriMesh {
    let f = f.max(1);
    let mut pos: Vec<[f64; 3]> = Vec::new();
    // Shared edge vertices are found by their rounded position.
    let mut index: HashMap<[i64; 3], u32> = HashMap::new();
    let mut tris = Vec::with_capacity(20 * f * f);
    for fc in ICO_FACES {
        let [a, b, c] = fc.map(|i| Vector3::from(ICO_VERTICES[i as usize]));
        let mut id = |i: usize, j: usize| -> u32 {
            let w = [(f - i - j) as f64, i as f64, j as f64];
            let p = normalize(((a * w[0] + b * w[1] + c * w[2]) / f as f64).into());
            let key = p.map(|x| (x * 1e9).round() as i64);
            *index.entry(key).or_insert_with(|| {
                pos.push(p);
                (pos.len() - 1) as u32
            })
        };
        for i in 0..f {
            for j in 0..f - i {
                let (p0, p1, p2) = (id(i, j), id(i + 1, j), id(i, j + 1));
                tris.push([p0, p1, p2]);
                if i + j + 1 < f {
                    let p3 = id(i + 1, j + 1);
                    tris.push([p1, p3, p2]);
                }
            }
        }
    }
    build(pos, tris)
}

/// [`geodesic_sphere`] stretched to an ellipsoid and bumped, so the spectrum has no symmetric
/// multiplicities (a realistic, body-like eigenvalue distribution at any size).
pub fn deformed_sphere(f: usize) -> TriMesh {
    let mut mesh = geodesic_sphere(f);
    for p in &mut mesh.positions {
        let bump = 1.0 + 0.1 * (3.0 * p[0]).sin() * (2.0 * p[1]).cos();
        *p = [1.3 * p[0] * bump, 0.8 * p[1] * bump, p[2] * bump];
    }
    mesh
}

/// Flat unit disk in the z = 0 plane: `rings` concentric rings, ring r has 6r vertices.
pub fn disk(rings: usize) -> TriMesh {
    let mut pos = vec![[0.0, 0.0, 0.0]];
    let mut ring_start = vec![0usize];
    for r in 1..=rings {
        ring_start.push(pos.len());
        let n = 6 * r;
        for i in 0..n {
            let a = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
            let rad = r as f64 / rings as f64;
            pos.push([rad * a.cos(), rad * a.sin(), 0.0]);
        }
    }
    let mut tris = Vec::new();
    // Ring 1 fan.
    for i in 0..6u32 {
        tris.push([0, 1 + i, 1 + (i + 1) % 6]);
    }
    for r in 1..rings {
        let (inner, outer) = (ring_start[r] as u32, ring_start[r + 1] as u32);
        let (ni, no) = (6 * r as u32, 6 * (r as u32 + 1));
        // Walk both rings by angle, emitting triangles (standard ring-strip triangulation).
        let (mut i, mut o) = (0u32, 0u32);
        while i < ni || o < no {
            let ai = i as f64 / ni as f64;
            let ao = o as f64 / no as f64;
            if o < no && (i >= ni || ao <= ai) {
                tris.push([inner + i % ni, outer + o, outer + (o + 1) % no]);
                o += 1;
            } else {
                tris.push([inner + i, outer + o % no, inner + (i + 1) % ni]);
                i += 1;
            }
        }
    }
    build(pos, tris)
}

/// Translated copy of `b` appended to `a` (two components).
pub fn union(a: &TriMesh, b: &TriMesh, shift: [f64; 3]) -> TriMesh {
    let mut pos = a.positions.clone();
    let off = pos.len() as u32;
    pos.extend(
        b.positions
            .iter()
            .map(|&p| -> [f64; 3] { (Point3::from(p) + Vector3::from(shift)).into() }),
    );
    let mut tris = a.triangles.clone();
    tris.extend(
        b.triangles
            .iter()
            .map(|t| [t[0] + off, t[1] + off, t[2] + off]),
    );
    build(pos, tris)
}
