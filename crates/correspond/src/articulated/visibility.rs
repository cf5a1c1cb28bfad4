//! Which posed template vertices a single-view target can show: a z-buffer of the posed
//! template seen from the target's viewpoint (the camera centre of a depth scan).
//!
//! A single-view scan shows only the surface nearest the camera. A posed template vertex
//! hidden behind the template's own surface — the far cheek behind the nose in a profile
//! view, the far arm behind the torso — has no counterpart in the scan, but its nearest scan
//! vertex can still lie within the gate and face the same way, pairing it with the wrong side
//! of a symmetric part. Self-occlusion is what the normal test cannot see; the z-buffer does.

use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Grid cells per median template edge (seen from the viewpoint): a triangle overlaps a few
/// cells, a cell holds a few triangles.
const CELLS_PER_EDGE: f64 = 1.0;
/// The grid has at most this many cells per side (a template far from the camera or with a
/// few huge triangles would otherwise ask for an enormous one).
const MAX_CELLS_PER_SIDE: usize = 1024;

/// Per posed template vertex: is it (within `tolerance`) the surface nearest the viewpoint
/// `eye` along its line of sight? `positions` are the posed template's, `triangles` its faces.
///
/// Ray casting through a grid: the template is projected through a pinhole at `eye` looking
/// at the template's centroid, each triangle listed in the grid cells its image overlaps; a
/// vertex is hidden when a triangle not incident to it covers its image point at a depth
/// (perspective-correct) more than `tolerance` nearer. Vertices behind the eye are not
/// visible; a degenerate view (the eye at the centroid) sees all.
pub(super) fn visible_from(
    eye: &Point3<f64>,
    positions: &[Point3<f64>],
    triangles: &[[u32; 3]],
    tolerance: f64,
) -> Vec<bool> {
    let n = positions.len();
    if n == 0 {
        return Vec::new();
    }
    let centroid = positions.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / n as f64;
    let Some(forward) = (centroid - eye.coords).try_normalize(1e-12) else {
        return vec![true; n];
    };
    let helper = if forward.y.abs() < 0.9 {
        Vector3::y()
    } else {
        Vector3::x()
    };
    let right = forward.cross(&helper).normalize();
    let up = right.cross(&forward);
    // Per vertex: image coordinates (tangent plane at unit distance) and depth along forward.
    let projected: Vec<Option<(f64, f64, f64)>> = positions
        .par_iter()
        .map(|p| {
            let d = p - eye;
            let z = d.dot(&forward);
            (z > 1e-9).then(|| (d.dot(&right) / z, d.dot(&up) / z, z))
        })
        .collect();
    let corners = |t: &[u32; 3]| -> Option<[(f64, f64, f64); 3]> {
        Some([
            projected[t[0] as usize]?,
            projected[t[1] as usize]?,
            projected[t[2] as usize]?,
        ])
    };
    let mut edges: Vec<f64> = triangles
        .par_iter()
        .filter_map(|t| {
            let [a, b, _] = corners(t)?;
            Some(((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt())
        })
        .filter(|l| *l > 0.0 && l.is_finite())
        .collect();
    if edges.is_empty() {
        return projected.iter().map(|p| p.is_some()).collect();
    }
    let mid = edges.len() / 2;
    let median = *edges.select_nth_unstable_by(mid, f64::total_cmp).1;
    let (mut u0, mut u1, mut v0, mut v1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(u, v, _) in projected.iter().flatten() {
        u0 = u0.min(u);
        u1 = u1.max(u);
        v0 = v0.min(v);
        v1 = v1.max(v);
    }
    let cell = (median / CELLS_PER_EDGE)
        .max((u1 - u0) / MAX_CELLS_PER_SIDE as f64)
        .max((v1 - v0) / MAX_CELLS_PER_SIDE as f64);
    let width = (((u1 - u0) / cell).floor() as usize + 1).min(MAX_CELLS_PER_SIDE + 1);
    let height = (((v1 - v0) / cell).floor() as usize + 1).min(MAX_CELLS_PER_SIDE + 1);
    let to_cell = |u: f64, v: f64| -> (usize, usize) {
        (
            (((u - u0) / cell) as usize).min(width - 1),
            (((v - v0) / cell) as usize).min(height - 1),
        )
    };
    // The cells a triangle's image bounding box overlaps.
    let cells_of = |c: &[(f64, f64, f64); 3]| {
        let (i0, j0) = to_cell(
            c[0].0.min(c[1].0).min(c[2].0),
            c[0].1.min(c[1].1).min(c[2].1),
        );
        let (i1, j1) = to_cell(
            c[0].0.max(c[1].0).max(c[2].0),
            c[0].1.max(c[1].1).max(c[2].1),
        );
        (j0..=j1).flat_map(move |j| (i0..=i1).map(move |i| j * width + i))
    };
    // The triangles that can hide a vertex, with what the test reads of them in one compact
    // table, listed per cell by their index in it (compressed rows: counts, offsets, then
    // indices): the test runs five times per recorded frame over every template vertex, and
    // chasing each triangle's corners through the vertex table was much of its cost. A
    // triangle with a corner behind the eye or a zero image area hides nothing and is left
    // out.
    let image: Vec<ImageTriangle> = triangles
        .par_iter()
        .filter_map(|tri| {
            let [a, b, c] = corners(tri)?;
            let area = (b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1);
            (area.abs() >= 1e-18).then_some(ImageTriangle {
                corners: [a, b, c],
                area,
                // Its interpolated depth is at least this (the weights are ≥ 0 and sum to 1,
                // up to rounding, which the factor covers many times over).
                nearest: a.2.min(b.2).min(c.2) * (1.0 - 1e-9),
                vertices: *tri,
            })
        })
        .collect();
    let mut start = vec![0usize; width * height + 1];
    for t in &image {
        for k in cells_of(&t.corners) {
            start[k + 1] += 1;
        }
    }
    for k in 0..width * height {
        start[k + 1] += start[k];
    }
    let mut fill = start.clone();
    let mut members = vec![0u32; start[width * height]];
    for (i, t) in image.iter().enumerate() {
        for k in cells_of(&t.corners) {
            members[fill[k]] = i as u32;
            fill[k] += 1;
        }
    }
    (0..n)
        .into_par_iter()
        .map(|v| {
            let Some((x, y, z)) = projected[v] else {
                return false;
            };
            let (i, j) = to_cell(x, y);
            let k = j * width + i;
            let limit = z - tolerance;
            !members[start[k]..start[k + 1]].iter().any(|&t| {
                let t = &image[t as usize];
                // Nothing of the triangle is nearer than the vertex by the tolerance.
                if t.nearest >= limit || t.vertices.contains(&(v as u32)) {
                    return false;
                }
                let [a, b, c] = t.corners;
                let area = t.area;
                // Barycentric coordinates of the vertex's image point.
                let wa = ((b.0 - x) * (c.1 - y) - (c.0 - x) * (b.1 - y)) / area;
                let wb = ((c.0 - x) * (a.1 - y) - (a.0 - x) * (c.1 - y)) / area;
                let wc = 1.0 - wa - wb;
                if wa < 0.0 || wb < 0.0 || wc < 0.0 {
                    return false;
                }
                // Perspective-correct: 1/depth, not depth, is affine in image coordinates.
                let depth = 1.0 / (wa / a.2 + wb / b.2 + wc / c.2);
                depth < limit
            })
        })
        .collect()
}

/// A template triangle in the image of [`visible_from`]: its corners (image coordinates and
/// depth), twice its signed image area, a lower bound of its depth, and its vertices.
#[derive(Debug, Clone, Copy)]
struct ImageTriangle {
    corners: [(f64, f64, f64); 3],
    area: f64,
    nearest: f64,
    vertices: [u32; 3],
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two parallel unit squares facing the eye, one 1 m behind the other.
    fn two_squares(offset_x: f64) -> (Vec<Point3<f64>>, Vec<[u32; 3]>) {
        let mut p = Vec::new();
        let mut t = Vec::new();
        for (k, (z, dx)) in [(2.0, 0.0), (3.0, offset_x)].into_iter().enumerate() {
            let s = 5usize; // 5 × 5 vertices per square
            let base = (k * s * s) as u32;
            for j in 0..s {
                for i in 0..s {
                    p.push(Point3::new(
                        i as f64 / 4.0 - 0.5 + dx,
                        j as f64 / 4.0 - 0.5,
                        z,
                    ));
                }
            }
            for j in 0..s - 1 {
                for i in 0..s - 1 {
                    let a = base + (j * s + i) as u32;
                    t.push([a, a + 1, a + s as u32]);
                    t.push([a + 1, a + s as u32 + 1, a + s as u32]);
                }
            }
        }
        (p, t)
    }

    #[test]
    fn a_square_behind_another_is_hidden_and_shows_where_it_sticks_out() {
        let eye = Point3::origin();
        let (p, t) = two_squares(0.0);
        let vis = visible_from(&eye, &p, &t, 0.01);
        assert!(vis[..25].iter().all(|&v| v), "the front square is seen");
        // The back square (z = 3) projects inside the front one (z = 2): all hidden.
        assert!(vis[25..].iter().all(|&v| !v), "{:?}", &vis[25..]);
        // Moved 2 m to the side, the back square is beside the front one: all seen.
        let (p, t) = two_squares(2.0);
        let vis = visible_from(&eye, &p, &t, 0.01);
        assert!(vis.iter().all(|&v| v), "{vis:?}");
    }

    #[test]
    fn seen_from_the_other_side_the_order_reverses() {
        let (p, t) = two_squares(0.0);
        let vis = visible_from(&Point3::new(0.0, 0.0, 5.0), &p, &t, 0.01);
        assert!(vis[..25].iter().all(|&v| !v));
        assert!(vis[25..].iter().all(|&v| v));
    }

    #[test]
    fn vertices_behind_the_eye_are_not_seen_and_an_empty_template_is_fine() {
        let (p, t) = two_squares(0.0);
        let vis = visible_from(&Point3::new(0.0, 0.0, 2.2), &p, &t, 0.01);
        assert!(vis[..25].iter().all(|&v| !v), "behind the eye");
        assert!(vis[25..].iter().all(|&v| v));
        assert!(visible_from(&Point3::origin(), &[], &[], 0.01).is_empty());
    }
}
