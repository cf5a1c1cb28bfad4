//! Skeleton landmark coordinates (DESIGN.md, Algorithm 7): surface landmarks taken from the
//! refined joints correspond by joint name across meshes, and every vertex's geodesic distances
//! to them (over √area) are coordinates that an isometry preserves and that already tell left
//! from right (the distance to the left hand is not the distance to the right hand).

use crate::CorrespondError;
use faer::Mat;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use symcorr_skeleton::{Joint, Skeleton};
use symcorr_spectral::HeatGeodesics;

/// One landmark per joint of [`Joint::ALL`], in that order: the mesh vertex nearest (Euclidean)
/// to the refined joint position. Empty meshes give an empty list.
///
/// ```
/// use symcorr_skeleton::{Joint, Skeleton};
/// use symcorr_correspond::joint_landmarks;
/// let mut sk = Skeleton::from_arrays([[0.0; 3]; Joint::COUNT]);
/// sk.positions[Joint::Head.index()] = [0.0, 2.0, 0.0].into();
/// let pos = [[0.0, 0.1, 0.0], [0.0, 1.9, 0.0]];
/// let l = joint_landmarks(&pos, &sk);
/// assert_eq!(l[Joint::Head.index()], 1);
/// assert_eq!(l[Joint::HipCenter.index()], 0);
/// ```
pub fn joint_landmarks(positions: &[[f64; 3]], joints: &Skeleton) -> Vec<u32> {
    if positions.is_empty() {
        return Vec::new();
    }
    Joint::ALL
        .iter()
        .map(|&j| {
            let c = joints.position(j);
            positions
                .iter()
                .enumerate()
                .map(|(v, &p)| (v, (Point3::from(p) - c).norm_squared()))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map_or(0, |(v, _)| v as u32)
        })
        .collect()
}

/// Landmark coordinates: column `i` holds every vertex's geodesic distance (heat method) to the
/// landmark source set `sources[i]`, divided by `√area` so that meshes of different size
/// compare. Distances to sets are computed in parallel; an unreachable vertex (another
/// component) gets the column's largest finite value.
///
/// Errors: [`CorrespondError::InvalidArea`] for an area that is not positive and finite,
/// [`CorrespondError::EmptyLandmark`] for an empty source set, and
/// [`CorrespondError::Geodesics`] for a source out of range.
pub fn landmark_coordinates(
    heat: &HeatGeodesics,
    sources: &[Vec<u32>],
    area: f64,
) -> Result<Mat<f64>, CorrespondError> {
    if !(area > 0.0 && area.is_finite()) {
        return Err(CorrespondError::InvalidArea(area));
    }
    if let Some(i) = sources.iter().position(Vec::is_empty) {
        return Err(CorrespondError::EmptyLandmark(i));
    }
    let cols: Vec<Vec<f64>> = sources
        .par_iter()
        .map(|s| heat.distance(s).map_err(CorrespondError::from))
        .collect::<Result<_, _>>()?;
    let n = cols.first().map_or(0, Vec::len);
    let s = area.sqrt();
    let maxes: Vec<f64> = cols
        .iter()
        .map(|c| {
            c.iter()
                .copied()
                .filter(|x| x.is_finite())
                .fold(0.0, f64::max)
        })
        .collect();
    Ok(Mat::from_fn(n, cols.len(), |v, i| {
        let d = cols[i][v];
        // The heat method can give tiny negative values next to the source.
        (if d.is_finite() { d.max(0.0) } else { maxes[i] }) / s
    }))
}

/// Joints at the ends of the skeleton's chains: their landmark is the surface tip beyond them.
const TIPS: [Joint; 5] = [
    Joint::Head,
    Joint::HandLeft,
    Joint::HandRight,
    Joint::FootLeft,
    Joint::FootRight,
];

/// One landmark source set per joint of [`Joint::ALL`], in that order, chosen to be stable
/// under pose, joint noise and body shape:
///
/// * **tips** (head, hands, feet): the vertex of the joint's segment farthest along its bone
///   (parent → joint) — top of the head, fingertip, toe tip;
/// * every other joint: the **ring** where the plane through the joint, normal to the bone
///   that leaves it along the limb (the incoming bone for elbows, wrists, knees, ankles,
///   shoulders and the spine joints; the thigh for hips; the pelvis bone for the hip centre),
///   cuts the surface of the segments meeting at the joint: vertices within `slab` of the
///   plane and within three times the joint's distance to the surface.
///
/// A distance to a ring does not depend on which side of the limb the nearest surface point
/// happens to lie (it moves with shape and noise); the ring falls back to the nearest vertex
/// when the slab catches nothing.
///
/// Panics if `labels.len() != positions.len()` (a caller bug).
pub fn skeleton_landmarks(
    positions: &[[f64; 3]],
    labels: &[symcorr_attach::Segment],
    joints: &Skeleton,
    slab: f64,
) -> Vec<Vec<u32>> {
    use symcorr_skeleton::Segment;
    assert_eq!(labels.len(), positions.len(), "one label per vertex");
    if positions.is_empty() {
        return vec![Vec::new(); Joint::ALL.len()];
    }
    // A zero axis (coincident joints) falls back to "up".
    let unit = |a: Vector3<f64>| {
        let n = a.norm();
        if n > 0.0 {
            a / n
        } else {
            Vector3::y()
        }
    };
    let p = |j: Joint| joints.position(j);
    let nearest = joint_landmarks(positions, joints);
    let positions: Vec<Point3<f64>> = positions.iter().copied().map(Point3::from).collect();
    // Segments whose bones touch a joint.
    let touching = |j: Joint| -> Vec<Segment> {
        Segment::ALL
            .iter()
            .copied()
            .filter(|s| s.bones().iter().any(|b| b.parent == j || b.child == j))
            .collect()
    };
    Joint::ALL
        .iter()
        .map(|&j| {
            let c = p(j);
            if TIPS.contains(&j) {
                let parent = j.parent().unwrap_or(Joint::HipCenter);
                let dir = unit(c - p(parent));
                let segs = touching(j);
                let best = positions
                    .iter()
                    .enumerate()
                    .filter(|(v, _)| segs.contains(&labels[*v]))
                    .max_by(|a, b| (a.1 - c).dot(&dir).total_cmp(&(b.1 - c).dot(&dir)));
                return vec![best.map_or(nearest[j.index()], |(v, _)| v as u32)];
            }
            let axis = match j {
                Joint::HipCenter => unit(p(Joint::Spine) - c),
                Joint::HipLeft => unit(p(Joint::KneeLeft) - c),
                Joint::HipRight => unit(p(Joint::KneeRight) - c),
                _ => unit(c - p(j.parent().unwrap_or(Joint::HipCenter))),
            };
            let q = positions[nearest[j.index()] as usize];
            let r0 = (q - c).norm();
            let radius = 3.0 * r0.max(slab);
            let segs = touching(j);
            let ring: Vec<u32> = positions
                .iter()
                .enumerate()
                .filter(|(v, x)| {
                    let d = *x - c;
                    segs.contains(&labels[*v])
                        && d.dot(&axis).abs() <= slab
                        && d.norm_squared() <= radius * radius
                })
                .map(|(v, _)| v as u32)
                .collect();
            if ring.is_empty() {
                vec![nearest[j.index()]]
            } else {
                ring
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use symcorr_attach::testbody::{capsule_body, t_pose};
    use symcorr_skeleton::Segment;
    use symcorr_spectral::EdgeGraph;

    #[test]
    fn landmark_columns_are_heat_distances_and_close_to_dijkstra() {
        let sk = t_pose(1.0);
        let (mesh, labels) = capsule_body(&sk, 0.05);
        let heat = HeatGeodesics::new(&mesh, 1.0).unwrap();
        let area = mesh.total_area();
        let sources = skeleton_landmarks(&mesh.positions, &labels, &sk, 0.05);
        assert_eq!(sources.len(), Joint::COUNT);
        let lm = landmark_coordinates(&heat, &sources, area).unwrap();
        assert_eq!(
            (lm.nrows(), lm.ncols()),
            (mesh.num_vertices(), Joint::COUNT)
        );
        let graph = EdgeGraph::new(&mesh);
        for (i, s) in sources.iter().enumerate() {
            let h = heat.distance(s).unwrap();
            let d = graph.distances_within(s, f64::INFINITY).unwrap();
            let mut rel = 0.0;
            for v in 0..mesh.num_vertices() {
                assert!((lm[(v, i)] - h[v].max(0.0) / area.sqrt()).abs() < 1e-12);
                rel += (h[v] - d[v]).abs();
            }
            // Edge paths overestimate (zig-zag), the heat method smooths over about one edge
            // (t = h²): on this coarse body (edges ≈ 0.05) they agree to a few edge lengths.
            let (nv, finite) = (
                mesh.num_vertices(),
                d.iter().filter(|x| x.is_finite()).count(),
            );
            assert!(
                rel / (nv as f64) < 2.5 * 0.05,
                "landmark {i}: mean {} over {nv} ({finite} reachable, {} sources)",
                rel / nv as f64,
                s.len()
            );
        }
        assert!(landmark_coordinates(&heat, &[vec![]], area).is_err());
    }

    #[test]
    fn rings_and_tips_sit_on_their_segments() {
        let sk = t_pose(1.0);
        let (mesh, labels) = capsule_body(&sk, 0.04);
        let s = skeleton_landmarks(&mesh.positions, &labels, &sk, 0.04);
        // Tips: the hand tip is the left forearm's vertex farthest from the body.
        let hand = s[Joint::HandLeft.index()][0] as usize;
        assert_eq!(labels[hand], Segment::ForearmLeft);
        let far = (0..mesh.num_vertices())
            .filter(|&v| labels[v] == Segment::ForearmLeft)
            .map(|v| {
                let d = [
                    mesh.positions[v][0] - sk.position(Joint::HandLeft)[0],
                    mesh.positions[v][1] - sk.position(Joint::HandLeft)[1],
                ];
                (d[0], v)
            })
            .fold(f64::NEG_INFINITY, |m, (d, _)| m.max(d.abs()));
        assert!(far > 0.0);
        // Knee ring: several vertices, all within the slab of the knee's plane, on thigh/shin.
        let knee = &s[Joint::KneeRight.index()];
        assert!(knee.len() >= 4, "{} ring vertices", knee.len());
        for &v in knee {
            let l = labels[v as usize];
            assert!(l == Segment::ThighRight || l == Segment::ShinRight);
        }
        // Left and right rings differ (the coordinates are left/right-aware).
        assert_ne!(s[Joint::KneeLeft.index()], s[Joint::KneeRight.index()]);
    }
}
