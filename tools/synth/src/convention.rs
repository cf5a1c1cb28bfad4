//! The MakeHuman boundary convention of symcorr-attach ([`symcorr_attach::BoundaryConvention`]):
//! fitted here on generated bodies with the reference labels of [`crate::mapping`], written as
//! the Rust table `crates/attach/src/convention_makehuman.rs`.
//!
//! Training bodies: three shapes, [`TRAINING_SHAPES`] (the base shape, a heavy woman, a
//! muscular man), each in the rest pose and the [`TRAINING_POSES`], with exact joints (39
//! bodies). tools/synth/tests/attach_labels.rs evaluates on 20 poses of the base shape and of a
//! heavy young man that is not among them, so 39 of its 40 bodies (all but the base shape's
//! rest pose) and both scans are held out.
//!
//! Every training body is also seen as a single-view scan ([`scan_target`] with the fixture
//! camera and Kinect realism, seed [`TRAINING_SCAN_SEED`]; a scan vertex's reference is the
//! label of the body vertex seen at its pixel): the rules use bone heat's vote, and bone heat
//! on an open, half-seen surface differs from bone heat on a closed body. The committed test
//! scans show the base shape from the same camera, but in a pose (walk-10) and with sensor
//! noise (seed 11) the training does not use.
//!
//! Measured (rest pose only vs posed training bodies, 22 poses, scans in the training):
//! `docs/decisions/2026-12-02-attach-convention-posed-training.md` and
//! `docs/decisions/2026-12-02-attach-convention-heat-vote-and-scans.md`.

use std::fmt::Write;

use symcorr_attach::{AttachOptions, BoundaryConvention, LabelledBody};
use symcorr_skeleton::Segment;

use crate::body::{Model, Pose, Shape};
use crate::dataset::resolve_pose;
use crate::error::{Result, SynthError};
use crate::kinect::scan_target;
use crate::mapping::{kinect_joints, reference_labels, SelfIntersectionCheck};
use crate::render::Realism;

/// Sensor-noise seed of the training scans (the committed test scans use 11 and 12).
pub const TRAINING_SCAN_SEED: u64 = 101;

/// The training shapes (see the module docs).
pub const TRAINING_SHAPES: [&str; 3] = [
    "",
    "female-young-averagemuscle-maxweight=0.5",
    "male-young-maxmuscle-averageweight=0.5",
];

/// The training poses besides the rest pose (names as `symcorr-synth dataset --poses` takes
/// them): ten random poses and two walk phases, none of them a pose the tests evaluate
/// (random-1…13, walk-00/25/50/75, and walk-10 of the committed scans).
pub const TRAINING_POSES: [&str; 12] = [
    "random-101",
    "random-102",
    "random-103",
    "random-104",
    "random-105",
    "random-106",
    "random-107",
    "random-108",
    "random-109",
    "random-110",
    "walk-35",
    "walk-85",
];

/// Fits the convention on the training bodies and their scans with [`AttachOptions::default`].
pub fn fit_makehuman(model: &Model) -> Result<BoundaryConvention> {
    let base = model.body(&Shape::default())?;
    let raw = reference_labels(&base)?;
    let labels: Vec<Segment> = raw
        .iter()
        .map(|&l| Segment::from_index(l as usize))
        .collect::<Option<_>>()
        .ok_or_else(|| SynthError::Invalid("reference label out of range".into()))?;
    let check = SelfIntersectionCheck::new(&base.rest.triangles, &raw);
    let mut poses = vec![Pose::default()];
    for name in TRAINING_POSES {
        poses.push(resolve_pose(model, &base, &check, name)?);
    }
    let whole: Vec<Option<Segment>> = labels.iter().copied().map(Some).collect();
    let camera = crate::fixtures::fixture_camera();
    let mut bodies = Vec::new();
    for (k, s) in TRAINING_SHAPES.iter().enumerate() {
        let body = model.body(&Shape::parse(s)?)?;
        for (i, pose) in poses.iter().enumerate() {
            let posed = body.pose(pose)?;
            let joints = kinect_joints(&body, &posed)?;
            // A single-view scan of every training body too: bone heat on an open surface is
            // not bone heat on a closed one, and the rules use it (TRAINING_SCAN_SEED).
            let stream = (k * poses.len() + i) as u64;
            let scan = scan_target(
                &posed.mesh,
                &joints,
                &camera,
                &Realism::kinect(TRAINING_SCAN_SEED),
                stream,
            )?;
            let seen: Vec<Option<Segment>> = scan
                .truth
                .iter()
                .map(|t| t.map(|v| labels[v as usize]))
                .collect();
            bodies.push((posed.mesh, joints, None));
            bodies.push((scan.mesh, scan.joints, Some(seen)));
        }
    }
    let examples: Vec<LabelledBody<'_>> = bodies
        .iter()
        .map(|(mesh, skeleton, seen)| LabelledBody {
            mesh,
            skeleton,
            // A whole body has every vertex's reference; a scan the seen ones.
            labels: seen.as_deref().unwrap_or(&whole),
        })
        .collect();
    BoundaryConvention::fit(&examples, &AttachOptions::default())
        .map_err(|e| SynthError::Invalid(format!("fitting the convention: {e}")))
}

/// The Rust source of `crates/attach/src/convention_makehuman.rs` for `c`.
pub fn rust_table(c: &BoundaryConvention) -> String {
    let mut s = String::from(
        "//! Generated by `cargo run --release -p symcorr-synth -- convention` (tools/synth/src/convention.rs:\n\
         //! MakeHuman reference labels, three shapes in 13 poses and a scan of each); do not edit.\n\
         use crate::{Joint, Segment};\n\n\
         #[rustfmt::skip]\n\
         pub(crate) const RULES: &[(Segment, Segment, Joint, [f64; 5])] = &[\n",
    );
    for r in &c.rules {
        let _ = writeln!(
            s,
            "    (Segment::{:?}, Segment::{:?}, Joint::{:?}, [{:e}, {:e}, {:e}, {:e}, {:e}]),",
            r.a, r.b, r.joint, r.plane[0], r.plane[1], r.plane[2], r.plane[3], r.plane[4]
        );
    }
    s.push_str("];\n");
    s
}
