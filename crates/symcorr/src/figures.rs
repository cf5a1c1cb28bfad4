//! The paper's figures as files: the two bodies side by side in one mesh, with the base vertex
//! set marked (the paper's Fig. 4) or with a sample of matches joined by lines (Figs. 1 and 6).
//! Every figure is a plain coloured [`TriMesh`] (lines are thin prisms), so any mesh writer
//! (PLY, GLB, OBJ, OFF) stores it and any viewer shows it without an edge mode.

use crate::{Correspondence, PipelineError, PreparedMesh};
use nalgebra::{Point3, Vector3};
use symcorr_attach::palette;
use symcorr_mesh::TriMesh;

/// Two meshes in one: the template as it is, the target shifted along +x so that the two
/// bounding boxes stand side by side with a gap of a quarter of the template's width.
#[derive(Debug, Clone)]
pub struct SideBySide {
    /// Template vertices first (same ids), then the target's (id + `target_offset`).
    pub mesh: TriMesh,
    /// Index of the target's vertex 0 in [`SideBySide::mesh`].
    pub target_offset: u32,
}

impl SideBySide {
    /// Places `template` and `target` side by side (see the type's docs). The target keeps its
    /// own height and depth; only x is shifted, and its bounding-box centre is brought to the
    /// template's in y and z so that two bodies in different frames still stand next to each
    /// other.
    pub fn new(template: &TriMesh, target: &TriMesh) -> Result<SideBySide, PipelineError> {
        let (tlo, thi) = template.bounding_box();
        let (ulo, uhi) = target.bounding_box();
        let (tlo, thi, ulo, uhi) = (
            Point3::from(tlo),
            Point3::from(thi),
            Point3::from(ulo),
            Point3::from(uhi),
        );
        let gap = 0.25 * (thi.x - tlo.x);
        let t_centre = nalgebra::center(&tlo, &thi);
        let u_centre = nalgebra::center(&ulo, &uhi);
        let shift = Vector3::new(
            thi.x + gap - ulo.x,
            t_centre.y - u_centre.y,
            t_centre.z - u_centre.z,
        );
        let offset = template.num_vertices() as u32;
        let positions = template
            .positions
            .iter()
            .copied()
            .chain(
                target
                    .positions
                    .iter()
                    .map(|&p| (Point3::from(p) + shift).into()),
            )
            .collect();
        let triangles = template
            .triangles
            .iter()
            .copied()
            .chain(target.triangles.iter().map(|t| t.map(|i| i + offset)))
            .collect();
        Ok(SideBySide {
            mesh: TriMesh::new(positions, triangles)?,
            target_offset: offset,
        })
    }

    /// Appends a thin triangular prism from `a` to `b` (scene coordinates) of radius `radius`
    /// to the mesh and `colour` to `colours`; a zero-length segment adds nothing.
    fn add_line(
        &mut self,
        colours: &mut Vec<[u8; 3]>,
        (a, b): (Point3<f64>, Point3<f64>),
        radius: f64,
        colour: [u8; 3],
    ) -> Result<(), PipelineError> {
        let Some(d) = (b - a).try_normalize(1e-12) else {
            return Ok(());
        };
        // Any unit vector perpendicular to the line, then its partner.
        let helper = if d.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let u = d.cross(&helper).normalize();
        let w = d.cross(&u);
        let base = self.mesh.num_vertices() as u32;
        let mut positions = std::mem::take(&mut self.mesh.positions);
        for end in [a, b] {
            for k in 0..3 {
                let angle = std::f64::consts::TAU * k as f64 / 3.0;
                let p = end + radius * (angle.cos() * u + angle.sin() * w);
                positions.push(p.into());
                colours.push(colour);
            }
        }
        let mut triangles = std::mem::take(&mut self.mesh.triangles);
        for k in 0..3u32 {
            let (i, j) = (base + k, base + (k + 1) % 3);
            triangles.push([i, j, j + 3]);
            triangles.push([i, j + 3, i + 3]);
        }
        self.mesh = TriMesh::new(positions, triangles)?;
        Ok(())
    }
}

/// A segment colour mixed half-way to white: the bodies stay readable as segments while the
/// marks and lines drawn on them keep full colour.
fn pale(c: [u8; 3]) -> [u8; 3] {
    c.map(|x| ((u16::from(x) + 255) / 2) as u8)
}

/// Pale segment colours of both meshes, in [`SideBySide::mesh`] order.
fn body_colours(template: &PreparedMesh, target: &PreparedMesh) -> Vec<[u8; 3]> {
    template
        .labels()
        .iter()
        .chain(target.labels())
        .map(|&s| pale(palette::colour(s)))
        .collect()
}

/// Radius of the marks and lines: a fraction of the template's √area (0.004·√area is about
/// 5 mm on a 1.8 m body).
fn mark_radius(template: &PreparedMesh) -> f64 {
    0.004 * template.area.sqrt()
}

/// The paper's Fig. 4: template and target side by side in pale segment colours, every vertex
/// within 2.5 mark radii of a base vertex (§3.3, the curvature-sampled base vertex set) in
/// black. Errors unless both meshes were prepared for the paper's method.
pub fn base_set_figure(
    template: &PreparedMesh,
    target: &PreparedMesh,
) -> Result<(TriMesh, Vec<[u8; 3]>), PipelineError> {
    let (tp, up) = (template.paper_data()?, target.paper_data()?);
    let scene = SideBySide::new(&template.mesh, &target.mesh)?;
    let mut colours = body_colours(template, target);
    let r = 2.5 * mark_radius(template);
    for (mesh, base, offset) in [
        (&template.mesh, &tp.base_set, 0),
        (&target.mesh, &up.base_set, scene.target_offset),
    ] {
        let centres: Vec<Point3<f64>> = base
            .iter()
            .map(|&b| Point3::from(mesh.positions[b as usize]))
            .collect();
        for (v, &p) in mesh.positions.iter().enumerate() {
            let p = Point3::from(p);
            if centres.iter().any(|c| (c - p).norm() <= r) {
                colours[v + offset as usize] = [20, 20, 20];
            }
        }
    }
    Ok((scene.mesh, colours))
}

/// The paper's Fig. 2 for one template point (a [`symcorr_correspond::PointExplanation`] in
/// the prepared meshes' ids): template and target side by side in pale segment colours, the
/// point marked in blue on the template, and on the target the candidates the filter removed
/// in red, those it kept in green and the selected one in black (marks of 2.5 mark radii).
pub fn explain_figure(
    template: &PreparedMesh,
    target: &PreparedMesh,
    explanation: &symcorr_correspond::PointExplanation,
) -> Result<(TriMesh, Vec<[u8; 3]>), PipelineError> {
    let scene = SideBySide::new(&template.mesh, &target.mesh)?;
    let mut colours = body_colours(template, target);
    let r = 2.5 * mark_radius(template);
    let mut mark = |mesh: &TriMesh, offset: u32, centre: u32, colour: [u8; 3]| {
        let c = Point3::from(mesh.positions[centre as usize]);
        for (v, &p) in mesh.positions.iter().enumerate() {
            if (Point3::from(p) - c).norm() <= r {
                colours[v + offset as usize] = colour;
            }
        }
    };
    mark(&template.mesh, 0, explanation.point, [30, 60, 230]);
    let kept = |q: u32| explanation.filtered.iter().any(|c| c.vertex == q);
    for c in &explanation.candidates {
        let colour = if kept(c.vertex) {
            [20, 170, 40]
        } else {
            [230, 20, 20]
        };
        mark(&target.mesh, scene.target_offset, c.vertex, colour);
    }
    for c in explanation
        .filtered
        .iter()
        .filter(|c| !explanation.candidates.contains(c))
    {
        mark(&target.mesh, scene.target_offset, c.vertex, [20, 170, 40]);
    }
    if let Some((c, _)) = &explanation.selected {
        mark(&target.mesh, scene.target_offset, c.vertex, [20, 20, 20]);
    }
    Ok((scene.mesh, colours))
}

/// The paper's Figs. 1 and 6: template and target side by side in pale segment colours, and
/// up to `count` matches (a farthest-point sample of the matched template points) drawn as
/// lines in the template point's segment colour, or in red when a match joins the subject's
/// left to its right (by the two meshes' labels). Points the target does not show
/// (`no_counterpart`) get no line.
pub fn lines_figure(
    template: &PreparedMesh,
    target: &PreparedMesh,
    corr: &Correspondence,
    count: usize,
) -> Result<(TriMesh, Vec<[u8; 3]>), PipelineError> {
    let mut scene = SideBySide::new(&template.mesh, &target.mesh)?;
    let mut colours = body_colours(template, target);
    let shown = corr.has_counterpart();
    let matched: Vec<&symcorr_correspond::Pair> = corr
        .pairs
        .iter()
        .enumerate()
        .filter(|(i, _)| shown.is_none_or(|h| h[*i]))
        .map(|(_, p)| p)
        .collect();
    // Farthest-point order over the matched template points: the first `count` cover the body.
    let sample = spread_out(&template.mesh, &matched, count);
    let radius = mark_radius(template);
    let (tl, ul) = (template.labels(), target.labels());
    for pair in sample {
        let (s, t) = (tl[pair.template as usize], ul[pair.target as usize]);
        let colour = if s.side().opposes(t.side()) {
            [230, 20, 20]
        } else {
            palette::colour(s)
        };
        let a = Point3::from(scene.mesh.positions[pair.template as usize]);
        let b = Point3::from(scene.mesh.positions[(pair.target + scene.target_offset) as usize]);
        scene.add_line(&mut colours, (a, b), radius, colour)?;
    }
    Ok((scene.mesh, colours))
}

/// Up to `count` of `pairs`, chosen by farthest-point sampling of their template positions
/// (Euclidean), starting from the first pair.
fn spread_out<'a>(
    mesh: &TriMesh,
    pairs: &[&'a symcorr_correspond::Pair],
    count: usize,
) -> Vec<&'a symcorr_correspond::Pair> {
    let pos = |i: usize| Point3::from(mesh.positions[pairs[i].template as usize]);
    let mut out = Vec::new();
    let mut nearest = vec![f64::INFINITY; pairs.len()];
    let mut next = (!pairs.is_empty()).then_some(0);
    while let Some(i) = next {
        if out.len() >= count {
            break;
        }
        out.push(pairs[i]);
        let p = pos(i);
        for (j, d) in nearest.iter_mut().enumerate() {
            *d = d.min((pos(j) - p).norm());
        }
        next = nearest
            .iter()
            .enumerate()
            .filter(|(_, &d)| d > 0.0)
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(j, _)| j);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(x: f64) -> TriMesh {
        TriMesh::new(
            vec![[x, 0.0, 0.0], [x + 1.0, 0.0, 0.0], [x, 1.0, 0.0]],
            vec![[0, 1, 2]],
        )
        .unwrap()
    }

    #[test]
    fn side_by_side_puts_the_target_right_of_the_template_with_a_gap() {
        let s = SideBySide::new(&tri(0.0), &tri(-5.0)).unwrap();
        assert_eq!(s.target_offset, 3);
        assert_eq!(s.mesh.num_vertices(), 6);
        assert_eq!(s.mesh.triangles[1], [3, 4, 5]);
        // Template width 1, gap 0.25: the target's leftmost x is 1.25.
        approx::assert_relative_eq!(s.mesh.positions[3][0], 1.25);
        approx::assert_relative_eq!(s.mesh.positions[4][0], 2.25);
    }

    #[test]
    fn a_line_is_a_closed_prism_around_its_segment() {
        let mut s = SideBySide::new(&tri(0.0), &tri(0.0)).unwrap();
        let mut colours = vec![[0u8; 3]; 6];
        let (a, b) = (Point3::new(0.0, 0.0, 0.0), Point3::new(0.0, 0.0, 2.0));
        s.add_line(&mut colours, (a, b), 0.1, [1, 2, 3]).unwrap();
        assert_eq!(s.mesh.num_vertices(), 12);
        assert_eq!(s.mesh.num_triangles(), 2 + 6);
        assert_eq!(colours.len(), 12);
        for (k, p) in s.mesh.positions[6..].iter().enumerate() {
            let p = Point3::from(*p);
            // Every prism vertex is `radius` from the axis and at one of the two ends.
            approx::assert_relative_eq!(p.xy().coords.norm(), 0.1, epsilon = 1e-12);
            approx::assert_relative_eq!(p.z, if k < 3 { 0.0 } else { 2.0 });
        }
        // A zero-length line adds nothing.
        s.add_line(&mut colours, (a, a), 0.1, [1, 2, 3]).unwrap();
        assert_eq!(s.mesh.num_vertices(), 12);
    }

    #[test]
    fn spread_out_takes_far_apart_points_first() {
        let m = TriMesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [0.1, 0.0, 0.0],
                [10.0, 0.0, 0.0],
                [5.0, 0.0, 0.0],
            ],
            vec![[0, 1, 2], [1, 2, 3]],
        )
        .unwrap();
        let pairs: Vec<symcorr_correspond::Pair> = (0..4)
            .map(|v| symcorr_correspond::Pair {
                template: v,
                target: v,
                confidence: 1.0,
            })
            .collect();
        let refs: Vec<&symcorr_correspond::Pair> = pairs.iter().collect();
        let picked: Vec<u32> = spread_out(&m, &refs, 3)
            .iter()
            .map(|p| p.template)
            .collect();
        assert_eq!(picked, vec![0, 2, 3]);
        assert_eq!(spread_out(&m, &refs, 10).len(), 4);
    }
}
