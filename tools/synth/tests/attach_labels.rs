//! Acceptance of symcorr-attach's segment labels, with the MakeHuman boundary convention
//! ([`BoundaryConvention::makehuman`], fitted on three shapes, only one of them here, in the
//! rest pose and twelve poses not used here), against the rig's reference labels
//! ([`symcorr_synth::mapping::reference_labels`]) on bodies generated here (20 poses × 2 shapes,
//! exact and noisy joints) and on the committed virtual-Kinect scans.
//!
//! The metrics (strict and boundary-tolerant agreement, mirrored and cross-side area; all
//! area-weighted) and the acceptance set are [`symcorr_synth::label_score`]'s: mirrored area must
//! be exactly zero with exact joints; the boundary-tolerant agreement is reported, not the
//! acceptance number.
//!
//! This file only asserts. The figures themselves (per body and per set, confusions, mirrored
//! and cross-side vertices, label dumps) are printed by the experiment
//! `cargo run --release -p symcorr-experiments --bin attach_report -- [--verbose] [--dump DIR]`
//! (experiments/README.md), which scores the same bodies with the same module.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use symcorr_attach::{attach, BoundaryConvention};
use symcorr_synth::label_score::{
    acceptance_bodies, acceptance_noise, handedness_cases, makehuman_options, score_labels,
    AcceptanceBody, GroundTruth, Score, Summary,
};
use symcorr_synth::noise::JointNoise;
use symcorr_synth::{Assets, Model};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn model() -> &'static Model {
    static M: OnceLock<Model> = OnceLock::new();
    M.get_or_init(|| Model::new(Assets::load(&Assets::default_dir()).unwrap()).unwrap())
}

/// Reference labels, mirror map and rest-pose sides of the base mesh.
fn ground_truth() -> &'static GroundTruth {
    static G: OnceLock<GroundTruth> = OnceLock::new();
    G.get_or_init(|| GroundTruth::new(model()).unwrap())
}

/// 20 poses × 2 shapes (base, heavy male), exact joints; generated once per test binary.
fn bodies() -> &'static Vec<AcceptanceBody> {
    static B: OnceLock<Vec<AcceptanceBody>> = OnceLock::new();
    B.get_or_init(|| acceptance_bodies(model(), ground_truth()).unwrap())
}

fn run_bodies(noise: Option<JointNoise>) -> Vec<Score> {
    let want = ground_truth().truth();
    bodies()
        .iter()
        .map(|b| {
            let a = attach(
                &b.mesh,
                &b.joints_with(noise.as_ref()),
                &makehuman_options(),
            )
            .unwrap();
            score_labels(&b.mesh, &a.labels, &want).score
        })
        .collect()
}

// Measured 2026-12-02 (2 shapes × 20 poses; `cargo run --release -p symcorr-experiments --bin
// attach_report -- --verbose`, history in docs/decisions) with the MakeHuman boundary convention
// ([`makehuman_options`]; joint planes in brackets): exact joints strict mean 0.937 / worst 0.910
// (0.859 / 0.828), boundary-tolerant (3 cm) 0.974 / 0.953; noisy joints strict 0.856 / 0.805
// (0.816 / 0.757), tolerant 0.915 / 0.870, mirrored ≤ 0.0003. The targets ≥ 0.95 (exact) and
// ≥ 0.90 (noisy) strict agreement and zero mirrored area: the agreement targets and zero mirrored area with
// noisy joints are NOT reached. The remaining confusion is printed by
// `cargo run --release -p symcorr-experiments --bin attach_report -- --verbose` (the
// bracketed figures: add `--boundaries joint-planes`) and listed in symcorr-attach's docs; its
// section "What limits agreement with noisy joints" splits the noisy loss by joint-noise component (along-bone positions and the hips). The
// assertions guard the measured levels (a little below them).

#[test]
fn exact_joints_40_bodies() {
    let s = run_bodies(None);
    let r = Summary::of(&s);
    // Body 0 (the base shape at rest) is one of the convention's training bodies.
    let held = Summary::of(&s[1..]);
    assert!(
        held.strict_mean >= 0.934,
        "held-out mean strict agreement {}",
        held.strict_mean
    );
    assert!(
        r.strict_mean >= 0.934,
        "mean strict agreement {}",
        r.strict_mean
    );
    assert!(
        r.strict_worst >= 0.905,
        "worst strict agreement {}",
        r.strict_worst
    );
    assert!(
        r.tolerant_mean >= 0.970,
        "mean tolerant agreement {}",
        r.tolerant_mean
    );
    assert_eq!(r.mirrored_max, 0.0, "mirrored area");
    assert!(
        r.cross_anat_max <= 0.0025,
        "cross-side area {}",
        r.cross_anat_max
    );
    assert!(
        r.cross_far_max <= 0.0005,
        "cross-side area beyond 3 cm {}",
        r.cross_far_max
    );
}

#[test]
fn noisy_joints_40_bodies() {
    // σ = 3 cm per coordinate, 10 % of the joints moved onto the surface first.
    let s = run_bodies(Some(acceptance_noise(5)));
    let r = Summary::of(&s);
    assert!(
        r.strict_mean >= 0.852,
        "mean strict agreement {}",
        r.strict_mean
    );
    assert!(
        r.strict_worst >= 0.800,
        "worst strict agreement {}",
        r.strict_worst
    );
    assert!(
        r.tolerant_mean >= 0.91,
        "mean tolerant agreement {}",
        r.tolerant_mean
    );
    assert!(r.mirrored_max <= 0.0025, "mirrored area {}", r.mirrored_max);
    assert!(
        r.cross_anat_max <= 0.005,
        "cross-side area {}",
        r.cross_anat_max
    );
    assert!(
        r.cross_far_max <= 0.001,
        "cross-side area beyond 3 cm {}",
        r.cross_far_max
    );
}

/// The committed MakeHuman boundary convention (symcorr-attach's `convention_makehuman.rs`) is
/// exactly what `symcorr-synth convention` fits.
#[test]
fn makehuman_convention_table_is_reproducible() {
    let fitted = symcorr_synth::convention::fit_makehuman(model()).unwrap();
    let committed = BoundaryConvention::makehuman();
    assert_eq!(fitted.rules.len(), committed.rules.len());
    for (f, c) in fitted.rules.iter().zip(&committed.rules) {
        assert_eq!((f.a, f.b, f.joint), (c.a, c.b, c.joint));
        for k in 0..5 {
            assert!(
                (f.plane[k] - c.plane[k]).abs() <= 1e-9 * (1.0 + c.plane[k].abs()),
                "{f:?} vs {c:?}"
            );
        }
    }
}

// Measured 2026-12-02 with the MakeHuman convention trained on posed bodies and their
// single-view scans: strict 0.950 (ideal scan) / 0.948 (Kinect realism), tolerant 0.985 / 0.988;
// no mirrored or cross-side area (joint planes: 0.870 / 0.867). These scans are s0_walk-10 seen
// by the fixture camera: the training scans use the same camera and shape but other poses and
// another noise seed. The target ≥ 0.90 strict agreement on the visible surface is reached on
// both. Before refinement refused circles far from the joint (2026-12-01) the realistic scan
// scored 0.894: its left wrist, hidden against the hip, was moved 12 cm onto the hip and 3 % of
// the pelvis/hip became forearm.
#[test]
fn virtual_kinect_scans() {
    let mut s = Vec::new();
    for dir in ["scan", "scan_kinect"] {
        let scan = ground_truth()
            .scan(&root().join("fixtures/synth").join(dir))
            .unwrap();
        let a = attach(&scan.mesh, &scan.joints, &makehuman_options()).unwrap();
        s.push(score_labels(&scan.mesh, &a.labels, &scan.truth).score);
    }
    let r = Summary::of(&s);
    assert!(
        r.strict_worst >= 0.94,
        "worst strict agreement {}",
        r.strict_worst
    );
    assert!(
        r.tolerant_worst >= 0.98,
        "worst tolerant agreement {}",
        r.tolerant_worst
    );
    assert_eq!(r.mirrored_max, 0.0, "mirrored area");
    assert_eq!(r.cross_anat_max, 0.0, "cross-side area");
}

/// The handedness check (symcorr-attach's `check_handedness`, which `attach` uses to fix a
/// side-swapped skeleton): on every body, with exact and with noisy joints, the skeleton as
/// given is never called swapped, and the same skeleton with its sides exchanged is.
#[test]
fn handedness_of_the_40_bodies() {
    // Exact joints and two noise seeds: the acceptance set's (5) and the benchmark datasets'
    // (2026).
    let mut failures = Vec::new();
    let mut undetected_2026 = Vec::new();
    for c in handedness_cases(bodies()).unwrap() {
        let (name, kind, ok, sw) = (&c.name, c.kind, &c.given, &c.swapped);
        if ok.says_swapped() {
            failures.push(format!("{name} {kind}: correct skeleton called swapped"));
        }
        if !sw.says_swapped() && kind == "noisy-2026" {
            // Measured: 2 of 40 (s0_t-pose: noisy ankles, mesh cue 0.25; s1_random-3:
            // contorted legs) stay below the margin and would be left as given (weak
            // evidence is reported, never acted on).
            undetected_2026.push(format!("{name} {:.3}", sw.evidence()));
        } else if !sw.says_swapped() {
            failures.push(format!(
                "{name} {kind}: {:.3} / swapped {:.3}",
                ok.evidence(),
                sw.evidence()
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
    assert!(undetected_2026.len() <= 2, "{undetected_2026:?}");
}
