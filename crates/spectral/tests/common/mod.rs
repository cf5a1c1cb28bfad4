//! Test meshes built from first principles (independent of the code under test).
#![allow(dead_code)]

use std::collections::HashMap;
use symcorr_mesh::TriMesh;

/// Unit icosphere: icosahedron subdivided `level` times, vertices projected to the sphere.
pub fn icosphere(level: usize) -> TriMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut pos: Vec<[f64; 3]> = vec![
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let normalize = |p: [f64; 3]| {
        let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        [p[0] / l, p[1] / l, p[2] / l]
    };
    for p in &mut pos {
        *p = normalize(*p);
    }
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
                    pos.push(normalize([pa[0] + pb[0], pa[1] + pb[1], pa[2] + pb[2]]));
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
    TriMesh::new(pos, tris).unwrap()
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
    TriMesh::new(pos, tris).unwrap()
}

/// Translated copy of `b` appended to `a` (two components).
pub fn union(a: &TriMesh, b: &TriMesh, shift: [f64; 3]) -> TriMesh {
    let mut pos = a.positions.clone();
    let off = pos.len() as u32;
    pos.extend(
        b.positions
            .iter()
            .map(|p| [p[0] + shift[0], p[1] + shift[1], p[2] + shift[2]]),
    );
    let mut tris = a.triangles.clone();
    tris.extend(
        b.triangles
            .iter()
            .map(|t| [t[0] + off, t[1] + off, t[2] + off]),
    );
    TriMesh::new(pos, tris).unwrap()
}

/// The realistic body fixture.
pub fn body() -> TriMesh {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/body/body.off");
    symcorr_mesh::io::read(path).unwrap().mesh
}
