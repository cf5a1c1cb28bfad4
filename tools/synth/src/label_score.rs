//! Scoring of segment labels against the rig's reference labels: the one definition behind
//! `tests/attach_labels.rs` (which asserts the figures) and the experiment `attach_report`
//! (which prints them).
//!
//! The acceptance set is [`acceptance_bodies`]: 20 poses ([`ACCEPTANCE_POSES`]) × 2 shapes, with
//! exact Kinect joints, or noisy ones ([`acceptance_noise`], [`AcceptanceBody::joints_with`]);
//! the committed virtual-Kinect scans are read by [`GroundTruth::scan`]. Labels are scored with
//! [`score_labels`] and a set of bodies is summarised by [`Summary::of`].
//!
//! Metrics (all area-weighted; vertex area = a third of its triangles' areas):
//! * **strict agreement**: area fraction whose label equals the reference label;
//! * **mirrored area**: area fraction labelled with the mirror of its reference segment
//!   (`hip_left` where the reference says `hip_right`, …);
//! * **boundary-tolerant agreement**: a disagreement between two *neighbouring* segments
//!   (sharing a skeleton joint) also counts as agreeing when the vertex lies within
//!   [`TOLERANCE_M`] of a vertex whose reference label is the label given to it — "boundaries
//!   between neighbouring segments may differ";
//! * **cross-side area**: area labelled with a side segment of the other side than its reference
//!   segment ([`Score::cross_ref`]), than its rest-pose side beyond [`MIDLINE_M`] of the plane of
//!   symmetry ([`Score::cross_anat`]), and beyond [`FAR_M`] ([`Score::cross_far`]).
//!
//! ```
//! use symcorr_attach::Segment;
//! use symcorr_mesh::TriMesh;
//! use symcorr_synth::label_score::{score_labels, Truth};
//! let mesh = TriMesh::new(
//!     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
//!     vec![[0, 1, 2]],
//! )
//! .unwrap();
//! let want = vec![Some(Truth { segment: Segment::Torso, side: 0.0 }); 3];
//! let s = score_labels(&mesh, &[Segment::Torso; 3], &want).score;
//! assert_eq!((s.strict, s.mirrored), (1.0, 0.0));
//! ```

use std::path::Path;

use symcorr_attach::{AttachOptions, BoundaryConvention, MirrorCheck, Segment, Skeleton};
use symcorr_kinect::scan::scan_mesh;
use symcorr_mesh::TriMesh;

use crate::dataset::resolve_pose;
use crate::mapping::{kinect_joints, reference_labels, segment_hops, SelfIntersectionCheck};
use crate::noise::{apply_joint_noise, JointNoise};
use crate::{Model, Result, Shape, SynthError};

/// Distance to the reference boundary within which a neighbouring-segment disagreement counts
/// as agreeing in the boundary-tolerant figure (metres).
pub const TOLERANCE_M: f64 = 0.03;

/// Vertices closer than this to the rest-pose plane of symmetry have no anatomical side in the
/// anatomical cross-side figure (metres).
pub const MIDLINE_M: f64 = 0.01;

/// See [`Score::cross_far`] (metres).
pub const FAR_M: f64 = 0.03;

/// The 20 poses of the acceptance set: the named ones, four walk phases, and 13 random
/// joint-limited poses (rejected while distant parts intersect).
pub const ACCEPTANCE_POSES: [&str; 20] = [
    "rest",
    "t-pose",
    "arms-down",
    "walk-00",
    "walk-25",
    "walk-50",
    "walk-75",
    "random-1",
    "random-2",
    "random-3",
    "random-4",
    "random-5",
    "random-6",
    "random-7",
    "random-8",
    "random-9",
    "random-10",
    "random-11",
    "random-12",
    "random-13",
];

/// The acceptance noise: σ = 3 cm per coordinate, 10 % of the joints moved onto the surface
/// first, none dropped. The acceptance set uses seed 5, the benchmark datasets 2026.
pub fn acceptance_noise(seed: u64) -> JointNoise {
    JointNoise {
        sigma_cm: 3.0,
        surface_fraction: 0.1,
        drop_fraction: 0.0,
        seed,
    }
}

/// Attachment with the MakeHuman boundary convention (symcorr-attach's `BoundaryConvention`),
/// the convention the reference labels follow.
pub fn makehuman_options() -> AttachOptions {
    AttachOptions {
        convention: Some(BoundaryConvention::makehuman()),
        ..AttachOptions::default()
    }
}

/// What is known about a vertex: its reference segment and its anatomical side (rest-pose
/// signed distance to the plane of symmetry, metres, positive = the subject's left).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// The rig's reference segment.
    pub segment: Segment,
    /// Rest-pose signed distance to the plane of symmetry (metres, positive = the subject's left).
    pub side: f64,
}

/// The ground truth of the base mesh's body vertices, shared by every shape and pose.
#[derive(Debug, Clone)]
pub struct GroundTruth {
    /// Reference segment per body vertex ([`reference_labels`] of the base shape).
    pub reference: Vec<Segment>,
    /// Mirror vertex per body vertex.
    pub mirror: Vec<u32>,
    /// Rest-pose signed distance to the plane of symmetry per body vertex: half the lateral
    /// offset between the vertex and its mirror vertex (the vertex's side, whatever the pose;
    /// metres, positive = the subject's left).
    pub rest_side: Vec<f64>,
}

impl GroundTruth {
    /// Reference labels, mirror map and rest-pose sides of `model`'s base shape.
    pub fn new(model: &Model) -> Result<GroundTruth> {
        let base = model.body(&Shape::default())?;
        let reference = reference_labels(&base)?
            .into_iter()
            .map(|l| {
                Segment::from_index(l as usize)
                    .ok_or_else(|| SynthError::Invalid(format!("reference label {l} out of range")))
            })
            .collect::<Result<Vec<_>>>()?;
        let mirror = model.assets.body_mirror()?;
        // OBJ frame: x = the subject's left.
        let rest_side = base
            .rest
            .positions
            .iter()
            .enumerate()
            .map(|(v, p)| 0.5 * (p[0] - base.rest.positions[mirror[v] as usize][0]))
            .collect();
        Ok(GroundTruth {
            reference,
            mirror,
            rest_side,
        })
    }

    /// The truth of body vertex `v`.
    pub fn at(&self, v: usize) -> Truth {
        Truth {
            segment: self.reference[v],
            side: self.rest_side[v],
        }
    }

    /// Every body vertex's truth (all known), for scoring a posed body.
    pub fn truth(&self) -> Vec<Option<Truth>> {
        (0..self.reference.len())
            .map(|v| Some(self.at(v)))
            .collect()
    }

    /// A committed virtual-Kinect scan folder (`depth.png`, `vertex_ids.png`,
    /// `intrinsics.json`, `joints.json`; `fixtures/synth/scan` and `scan_kinect`) → the scan
    /// mesh, its joints and the truth per scan vertex (unknown where no body vertex was seen).
    pub fn scan(&self, dir: &Path) -> Result<ScanCase> {
        let ctx =
            |e: &dyn std::fmt::Display| SynthError::Invalid(format!("{}: {e}", dir.display()));
        let depth = symcorr_kinect::read_depth_png16(dir.join("depth.png")).map_err(|e| ctx(&e))?;
        let ids =
            symcorr_kinect::read_depth_png16(dir.join("vertex_ids.png")).map_err(|e| ctx(&e))?;
        let k = symcorr_kinect::camera::Intrinsics::read(dir.join("intrinsics.json"))
            .map_err(|e| ctx(&e))?;
        let log =
            symcorr_kinect::joints::read_joints(dir.join("joints.json")).map_err(|e| ctx(&e))?;
        let joints = log
            .frames
            .first()
            .ok_or_else(|| ctx(&"joints.json has no frame"))?
            .skeleton
            .clone();
        let scan = scan_mesh(&depth, &k, Some(&joints), &crate::kinect::scan_options())
            .map_err(|e| ctx(&e))?;
        let truth = scan
            .pixel_ids
            .iter()
            .map(|&px| {
                let (u, v) = (px % k.width, px / k.width);
                match ids.at(u, v) {
                    Some(id) if id > 0 => Some(self.at(id as usize - 1)),
                    _ => None,
                }
            })
            .collect();
        Ok(ScanCase {
            mesh: scan.mesh,
            joints,
            truth,
        })
    }
}

/// A single-view scan with the truth of its visible vertices ([`GroundTruth::scan`]).
#[derive(Debug, Clone)]
pub struct ScanCase {
    /// The scan mesh.
    pub mesh: TriMesh,
    /// The scan's joints (first frame of `joints.json`).
    pub joints: Skeleton,
    /// Truth per scan vertex; `None` where the pixel shows no body vertex.
    pub truth: Vec<Option<Truth>>,
}

/// A generated body of the acceptance set.
#[derive(Debug, Clone)]
pub struct AcceptanceBody {
    /// `SHAPE_POSE`, e.g. `s1_walk-25`.
    pub name: String,
    /// Position in the set: the noise stream of its noisy joints.
    pub index: usize,
    /// The posed body mesh (body vertices in base-mesh order).
    pub mesh: TriMesh,
    /// Its exact Kinect joints.
    pub joints: Skeleton,
}

impl AcceptanceBody {
    /// The exact joints (`noise` None) or the joints with `noise` applied (stream = the body's
    /// index).
    pub fn joints_with(&self, noise: Option<&JointNoise>) -> Skeleton {
        match noise {
            Some(n) => apply_joint_noise(&self.joints, &self.mesh, n, self.index as u64),
            None => self.joints.clone(),
        }
    }
}

/// The acceptance set: 20 poses ([`ACCEPTANCE_POSES`]) × 2 shapes (`s0` the base shape, `s1`
/// a heavy young man that is not a training shape of the MakeHuman convention), exact joints.
pub fn acceptance_bodies(model: &Model, truth: &GroundTruth) -> Result<Vec<AcceptanceBody>> {
    let base = model.body(&Shape::default())?;
    let labels: Vec<u8> = truth.reference.iter().map(|s| s.index() as u8).collect();
    let check = SelfIntersectionCheck::new(&base.rest.triangles, &labels);
    let poses = ACCEPTANCE_POSES
        .iter()
        .map(|p| resolve_pose(model, &base, &check, p))
        .collect::<Result<Vec<_>>>()?;
    let shapes = [
        ("s0", Shape::default()),
        ("s1", Shape::parse("male-young-minmuscle-maxweight=0.5")?),
    ];
    let mut out = Vec::new();
    for (sname, shape) in shapes {
        let body = model.body(&shape)?;
        for (pname, pose) in ACCEPTANCE_POSES.iter().zip(&poses) {
            let posed = body.pose(pose)?;
            let joints = kinect_joints(&body, &posed)?;
            out.push(AcceptanceBody {
                name: format!("{sname}_{pname}"),
                index: out.len(),
                mesh: posed.mesh,
                joints,
            });
        }
    }
    Ok(out)
}

/// The figures of one labelled mesh (area fractions of the vertices whose truth is known).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Score {
    /// Strict agreement.
    pub strict: f64,
    /// Area labelled with the mirror of its reference segment.
    pub mirrored: f64,
    /// Boundary-tolerant agreement ([`TOLERANCE_M`]).
    pub tolerant: f64,
    /// Area labelled with a left (right) segment whose reference segment is a midline or right
    /// (left) one.
    pub cross_ref: f64,
    /// Area labelled with a left (right) segment lying more than [`MIDLINE_M`] on the right
    /// (left) of the plane of symmetry in the rest pose: the labels that let a correspondence
    /// map a vertex onto the other side of the body.
    pub cross_anat: f64,
    /// The same beyond [`FAR_M`] of the plane of symmetry (a vertex that far from the midline
    /// mapped to the other side is a left/right flip, not a boundary question).
    pub cross_far: f64,
}

/// A vertex whose label is on the wrong side ([`Scoring::mirrored_at`],
/// [`Scoring::cross_side_at`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mislabel {
    /// The vertex.
    pub vertex: usize,
    /// Its reference segment.
    pub reference: Segment,
    /// The label it was given.
    pub label: Segment,
    /// Its rest-pose side ([`Truth::side`]).
    pub rest_side: f64,
}

/// [`score_labels`]'s result: the figures and where they come from.
#[derive(Debug, Clone)]
pub struct Scoring {
    /// The area fractions.
    pub score: Score,
    /// Area of the vertices whose truth is known (the denominator of every fraction).
    pub total_area: f64,
    /// Area by reference segment (row) and label (column).
    pub confusion: [[f64; 17]; 17],
    /// The same restricted to the anatomical cross-side area ([`Score::cross_anat`]).
    pub cross_confusion: [[f64; 17]; 17],
    /// The mirrored vertices, in vertex order.
    pub mirrored_at: Vec<Mislabel>,
    /// The anatomical cross-side vertices, in vertex order.
    pub cross_side_at: Vec<Mislabel>,
}

/// Scores the labels `got` of mesh `m` against `want` on the vertices where `want` is known.
pub fn score_labels(m: &TriMesh, got: &[Segment], want: &[Option<Truth>]) -> Scoring {
    let hops = segment_hops();
    let area = m.vertex_areas();
    let mut by_ref: Vec<Vec<[f64; 3]>> = vec![Vec::new(); 17];
    for (v, w) in want.iter().enumerate() {
        if let Some(w) = w {
            by_ref[w.segment.index()].push(m.positions[v]);
        }
    }
    let mut conf = [[0.0f64; 17]; 17];
    let mut cross_conf = [[0.0f64; 17]; 17];
    let (mut total, mut same, mut mirrored, mut tolerant) = (0.0, 0.0, 0.0, 0.0);
    let (mut cross_ref, mut cross_anat, mut cross_far) = (0.0, 0.0, 0.0);
    let mut mirrored_at = Vec::new();
    let mut anat_at = Vec::new();
    for v in 0..m.num_vertices() {
        let Some(t) = want[v] else { continue };
        let w = t.segment;
        let g = got[v];
        let at = Mislabel {
            vertex: v,
            reference: w,
            label: g,
            rest_side: t.side,
        };
        total += area[v];
        conf[w.index()][g.index()] += area[v];
        let gs = g.side().sign();
        if gs != 0 && w.side().sign() != gs {
            cross_ref += area[v];
        }
        if gs != 0 && t.side * f64::from(gs) < -MIDLINE_M {
            cross_anat += area[v];
            cross_conf[w.index()][g.index()] += area[v];
            anat_at.push(at);
            if t.side * f64::from(gs) < -FAR_M {
                cross_far += area[v];
            }
        }
        if g == w {
            same += area[v];
            tolerant += area[v];
            continue;
        }
        if w.mirror() != w && g == w.mirror() {
            mirrored += area[v];
            mirrored_at.push(at);
        }
        if hops[w.index()][g.index()] == 1 {
            let p = m.positions[v];
            let near = by_ref[g.index()].iter().any(|q| {
                (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)
                    <= TOLERANCE_M * TOLERANCE_M
            });
            if near {
                tolerant += area[v];
            }
        }
    }
    Scoring {
        score: Score {
            strict: same / total,
            mirrored: mirrored / total,
            tolerant: tolerant / total,
            cross_ref: cross_ref / total,
            cross_anat: cross_anat / total,
            cross_far: cross_far / total,
        },
        total_area: total,
        confusion: conf,
        cross_confusion: cross_conf,
        mirrored_at,
        cross_side_at: anat_at,
    }
}

/// Mean / worst / largest figures over a set of scored meshes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    /// Mean strict agreement.
    pub strict_mean: f64,
    /// Lowest strict agreement.
    pub strict_worst: f64,
    /// Mean boundary-tolerant agreement.
    pub tolerant_mean: f64,
    /// Lowest boundary-tolerant agreement.
    pub tolerant_worst: f64,
    /// Largest mirrored area.
    pub mirrored_max: f64,
    /// Mean cross-side area by reference segment.
    pub cross_ref_mean: f64,
    /// Largest cross-side area by reference segment.
    pub cross_ref_max: f64,
    /// Largest anatomical cross-side area.
    pub cross_anat_max: f64,
    /// Largest anatomical cross-side area beyond [`FAR_M`].
    pub cross_far_max: f64,
}

impl Summary {
    /// Summarises `s` (worst figures start at 1, largest at 0).
    pub fn of(s: &[Score]) -> Summary {
        let n = s.len() as f64;
        let mean = |f: fn(&Score) -> f64| s.iter().map(f).sum::<f64>() / n;
        let worst = |f: fn(&Score) -> f64| s.iter().map(f).fold(1.0, f64::min);
        let max = |f: fn(&Score) -> f64| s.iter().map(f).fold(0.0, f64::max);
        Summary {
            strict_mean: mean(|x| x.strict),
            strict_worst: worst(|x| x.strict),
            tolerant_mean: mean(|x| x.tolerant),
            tolerant_worst: worst(|x| x.tolerant),
            mirrored_max: max(|x| x.mirrored),
            cross_ref_mean: mean(|x| x.cross_ref),
            cross_ref_max: max(|x| x.cross_ref),
            cross_anat_max: max(|x| x.cross_anat),
            cross_far_max: max(|x| x.cross_far),
        }
    }
}

/// The handedness check on one body's joints ([`handedness_cases`]).
#[derive(Debug, Clone)]
pub struct HandednessCase {
    /// The body's name ([`AcceptanceBody::name`]).
    pub name: String,
    /// `exact`, `noisy` (acceptance noise, seed 5) or `noisy-2026` (seed 2026).
    pub kind: &'static str,
    /// The check on the joints as given (correct sides).
    pub given: MirrorCheck,
    /// The check on the same joints with their sides exchanged.
    pub swapped: MirrorCheck,
}

/// symcorr-attach's handedness check on every body, with exact joints and two noise seeds (the
/// acceptance set's 5 and the benchmark datasets' 2026), each skeleton as given and with its
/// sides exchanged; body by body, in that order.
pub fn handedness_cases(bodies: &[AcceptanceBody]) -> Result<Vec<HandednessCase>> {
    let mut out = Vec::new();
    for b in bodies {
        for (kind, joints) in [
            ("exact", b.joints_with(None)),
            ("noisy", b.joints_with(Some(&acceptance_noise(5)))),
            ("noisy-2026", b.joints_with(Some(&acceptance_noise(2026)))),
        ] {
            let check = |j: &Skeleton| {
                symcorr_attach::check_handedness(&b.mesh, j)
                    .map_err(|e| SynthError::Invalid(format!("{} {kind}: {e}", b.name)))
            };
            out.push(HandednessCase {
                name: b.name.clone(),
                kind,
                given: check(&joints)?,
                swapped: check(&joints.swap_sides())?,
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles side by side; vertex 1 and 2 shared.
    fn strip() -> TriMesh {
        TriMesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 1.0, 0.0],
            ],
            vec![[0, 1, 2], [1, 3, 2]],
        )
        .unwrap()
    }

    #[test]
    fn score_counts_agreement_mirrored_and_cross_side_area() {
        let m = strip();
        let t = |segment, side| Some(Truth { segment, side });
        // Vertex 0: right hip in truth, 0.5 m on the right, labelled left hip: mirrored and
        // cross-side (by reference, anatomically, and beyond FAR_M). Vertex 3 is unknown.
        let want = [
            t(Segment::HipRight, -0.5),
            t(Segment::Pelvis, 0.0),
            t(Segment::Pelvis, 0.0),
            None,
        ];
        let got = [
            Segment::HipLeft,
            Segment::Pelvis,
            Segment::Pelvis,
            Segment::Head,
        ];
        let r = score_labels(&m, &got, &want);
        let area = m.vertex_areas();
        let total = area[0] + area[1] + area[2];
        assert_eq!(r.total_area, total);
        let f = area[0] / total;
        let s = r.score;
        assert!((s.strict - (1.0 - f)).abs() < 1e-12, "{s:?}");
        assert!((s.mirrored - f).abs() < 1e-12, "{s:?}");
        assert_eq!((s.cross_ref, s.cross_anat, s.cross_far), (f, f, f));
        // Hips do not share a joint: no tolerance.
        assert_eq!(s.tolerant, s.strict);
        assert_eq!(r.mirrored_at.len(), 1);
        assert_eq!(r.cross_side_at[0].vertex, 0);
        assert_eq!(
            r.confusion[Segment::HipRight.index()][Segment::HipLeft.index()],
            area[0]
        );

        let perfect = score_labels(
            &m,
            &[
                Segment::HipRight,
                Segment::Pelvis,
                Segment::Pelvis,
                Segment::Head,
            ],
            &want,
        )
        .score;
        let sum = Summary::of(&[s, perfect]);
        assert_eq!(sum.strict_worst, s.strict);
        assert_eq!(sum.mirrored_max, s.mirrored);
        assert!((sum.strict_mean - 0.5 * (1.0 + s.strict)).abs() < 1e-12);
        assert_eq!(sum.cross_ref_mean, 0.5 * f);
    }

    #[test]
    fn acceptance_noise_and_options() {
        let n = acceptance_noise(5);
        assert_eq!((n.sigma_cm, n.surface_fraction, n.seed), (3.0, 0.1, 5));
        assert!(makehuman_options().convention.is_some());
    }
}
