//! Poses: named poses, the walk cycle, a seeded random sampler, and rotation files.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Deserialize;

use crate::assets::Assets;
use crate::body::Pose;
use crate::error::{Result, SynthError};
use crate::math::V3;

/// Forward-kinematics curves of the MPFB2 walk cycle, renamed to the game_engine rig.
#[derive(Debug, Clone, Default)]
pub struct WalkCurves {
    /// Rig bone → keyframes `(frame, euler)` sorted by frame.
    pub curves: BTreeMap<String, Vec<(f64, V3)>>,
    /// Last keyframe (cycle length in frames).
    pub length: f64,
}

#[derive(Deserialize)]
struct RawChannel {
    values: Vec<f64>,
}

#[derive(Deserialize)]
struct RawWalk {
    animation_data: BTreeMap<String, BTreeMap<String, BTreeMap<String, RawChannel>>>,
}

/// Walk-cycle bone (MakeHuman default rig) → game_engine rig bone. Only forward-kinematics
/// bones transfer; the file's limbs are driven by IK targets of another rig (see crate docs).
pub const WALK_BONE_MAP: [(&str, &str); 7] = [
    ("clavicle.L", "clavicle_l"),
    ("clavicle.R", "clavicle_r"),
    ("head", "head"),
    ("neck01", "neck_01"),
    ("spine04", "spine_01"),
    ("spine03", "spine_02"),
    ("spine02", "spine_03"),
];

impl WalkCurves {
    /// Reads a Blender action export (`animation_data[bone][frame]["rotation_euler"]`).
    pub fn load(path: &Path) -> Result<WalkCurves> {
        let text = std::fs::read_to_string(path).map_err(|e| SynthError::io(path, e))?;
        let raw: RawWalk = serde_json::from_str(&text).map_err(|e| SynthError::json(path, e))?;
        let mut curves = BTreeMap::new();
        let mut length: f64 = 0.0;
        for (src, dst) in WALK_BONE_MAP {
            let Some(frames) = raw.animation_data.get(src) else {
                continue;
            };
            let mut keys = Vec::new();
            for (f, chans) in frames {
                let frame: f64 = f
                    .parse()
                    .map_err(|_| SynthError::json(path, format!("{src}: bad frame `{f}`")))?;
                if let Some(c) = chans.get("rotation_euler") {
                    if c.values.len() != 3 || c.values.iter().any(|x| !x.is_finite()) {
                        return Err(SynthError::json(
                            path,
                            format!("{src} frame {f}: bad rotation"),
                        ));
                    }
                    keys.push((frame, [c.values[0], c.values[1], c.values[2]]));
                    length = length.max(frame);
                }
            }
            keys.sort_by(|a, b| a.0.total_cmp(&b.0));
            curves.insert(dst.to_string(), keys);
        }
        Ok(WalkCurves { curves, length })
    }
}

/// Names accepted by [`named_pose`] besides `walk-PP` (PP = percent of the cycle, 00–99).
pub const NAMED_POSES: [&str; 4] = ["rest", "t-pose", "arms-down", "arms-tight"];

fn mirror_euler(e: V3) -> V3 {
    // A left bone's rotation mirrored onto its right twin: the rig's left/right bone frames are
    // mirror images (roll negated), so x stays and y, z flip (compare poses/t-pose.json).
    [e[0], -e[1], -e[2]]
}

fn set_pair(pose: &mut Pose, left: &str, e: V3) {
    pose.rotations.insert(left.to_string(), e);
    let right = format!("{}_r", left.trim_end_matches("_l"));
    pose.rotations.insert(right, mirror_euler(e));
}

/// The arms-down pose: upper arms adducted from the rest A-pose toward the sides, elbows
/// slightly bent.
pub fn arms_down() -> Pose {
    let mut p = Pose::default();
    set_pair(&mut p, "upperarm_l", [0.05, 0.0, -0.55]);
    set_pair(&mut p, "lowerarm_l", [0.15, 0.0, 0.0]);
    p
}

/// Arms against the torso: upper arms adducted until they touch the flanks (slightly forward,
/// so that the forearms lie against the hips rather than in them: on the base shape the
/// forearm comes within ~2.5 cm of the hip, on heavier shapes it presses against it), elbows
/// nearly straight. Arm and torso then meet in a depth jump of a few centimetres.
pub fn arms_tight() -> Pose {
    let mut p = Pose::default();
    set_pair(&mut p, "upperarm_l", [0.15, 0.0, -0.65]);
    set_pair(&mut p, "lowerarm_l", [0.1, 0.0, 0.0]);
    p
}

/// A walk-cycle pose at `phase` ∈ [0, 1).
///
/// The MPFB2 walk cycle drives its legs and arms with IK targets of another rig (MakeHuman's
/// `default_no_toes`), which cannot be replayed on the game_engine rig without that rig; its
/// forward-kinematics curves (spine, neck, head, clavicles — renamed by [`WALK_BONE_MAP`]) are
/// replayed (linear interpolation between keyframes, cycle length from the file), and the limbs
/// follow a procedural gait with the same period: hip flexion ±0.35 rad, knee flexion peaking in
/// swing, counter-swinging arms at the sides.
pub fn walk_pose(curves: Option<&WalkCurves>, phase: f64) -> Pose {
    let mut p = Pose::default();
    if let Some(c) = curves {
        let frame = phase.rem_euclid(1.0) * c.length;
        for (bone, keys) in &c.curves {
            if keys.is_empty() {
                continue;
            }
            let e = match keys.iter().position(|k| k.0 > frame) {
                None => keys[keys.len() - 1].1,
                Some(0) => keys[0].1,
                Some(i) => {
                    let (f0, a) = keys[i - 1];
                    let (f1, b) = keys[i];
                    let t = (frame - f0) / (f1 - f0);
                    [0, 1, 2].map(|k| a[k] + t * (b[k] - a[k]))
                }
            };
            p.rotations.insert(bone.clone(), e);
        }
    }
    let w = 2.0 * std::f64::consts::PI * phase;
    let (s, c) = w.sin_cos();
    // Left leg forward when sin > 0 (negative thigh x = hip flexion); right leg in antiphase.
    // z = +0.1 adducts the legs from the wide rest stance (as poses/t-pose.json does).
    p.rotations.insert("thigh_l".into(), [-0.35 * s, 0.0, 0.1]);
    p.rotations
        .insert("thigh_r".into(), mirror_euler([0.35 * s, 0.0, 0.1]));
    // Knee flexion (positive calf x) peaks while the leg swings forward (cos > 0 for the left).
    p.rotations
        .insert("calf_l".into(), [0.1 + 0.6 * c.max(0.0), 0.0, 0.0]);
    p.rotations
        .insert("calf_r".into(), [0.1 + 0.6 * (-c).max(0.0), 0.0, 0.0]);
    p.rotations.insert("foot_l".into(), [0.15 * s, 0.0, 0.0]);
    p.rotations.insert("foot_r".into(), [-0.15 * s, 0.0, 0.0]);
    // Arms down at the sides, swinging against the legs (positive upperarm x = forward).
    p.rotations
        .insert("upperarm_l".into(), [-0.3 * s, 0.0, -0.5]);
    p.rotations
        .insert("upperarm_r".into(), mirror_euler([0.3 * s, 0.0, -0.5]));
    p.rotations
        .insert("lowerarm_l".into(), [0.25 + 0.15 * (-s).max(0.0), 0.0, 0.0]);
    p.rotations
        .insert("lowerarm_r".into(), [0.25 + 0.15 * s.max(0.0), 0.0, 0.0]);
    p
}

/// A named pose: `rest`, `t-pose` (poses/t-pose.json), `arms-down`, `arms-tight`
/// or `walk-PP`.
pub fn named_pose(assets: &Assets, name: &str) -> Result<Pose> {
    match name {
        "rest" => Ok(Pose::default()),
        "t-pose" => Ok(Pose {
            rotations: assets.t_pose.clone(),
        }),
        "arms-down" => Ok(arms_down()),
        "arms-tight" => Ok(arms_tight()),
        n => {
            let pct = n
                .strip_prefix("walk-")
                .and_then(|p| p.parse::<u32>().ok())
                .filter(|&p| p < 100)
                .ok_or_else(|| {
                    SynthError::Invalid(format!(
                        "unknown pose `{n}` (known: rest, t-pose, arms-down, arms-tight, walk-00 … walk-99, random-SEED)"
                    ))
                })?;
            Ok(walk_pose(assets.walk.as_ref(), pct as f64 / 100.0))
        }
    }
}

/// Reads a rotations file: MPFB2 pose JSON `{"bone_rotations": {"bone": [x, y, z], ...}}`
/// (Blender XYZ Euler, radians, bone rest frame) — the format of `poses/t-pose.json`; a plain
/// `{"bone": [x, y, z]}` object is accepted too.
pub fn read_pose_json(path: &Path) -> Result<Pose> {
    let text = std::fs::read_to_string(path).map_err(|e| SynthError::io(path, e))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| SynthError::json(path, e))?;
    let obj = v.get("bone_rotations").unwrap_or(&v);
    let map: BTreeMap<String, V3> =
        serde_json::from_value(obj.clone()).map_err(|e| SynthError::json(path, e))?;
    if let Some((b, _)) = map.iter().find(|(_, e)| e.iter().any(|x| !x.is_finite())) {
        return Err(SynthError::json(
            path,
            format!("bone {b}: non-finite rotation"),
        ));
    }
    Ok(Pose { rotations: map })
}

/// Per-bone Euler limits `[(min, max); 3]` (radians, bone rest frame) of the random sampler,
/// for left and midline bones; right bones use the mirror image (x kept, y and z negated).
/// Signs: thigh x < 0 flexes the hip forward, calf x > 0 bends the knee, upperarm x > 0 swings
/// the arm forward and z > 0 raises it sideways, lowerarm x > 0 bends the elbow, spine x > 0
/// bends forward.
pub const JOINT_LIMITS: [(&str, [(f64, f64); 3]); 12] = [
    ("spine_01", [(-0.1, 0.2), (-0.15, 0.15), (-0.1, 0.1)]),
    ("spine_02", [(-0.1, 0.2), (-0.15, 0.15), (-0.1, 0.1)]),
    ("spine_03", [(-0.1, 0.2), (-0.15, 0.15), (-0.1, 0.1)]),
    ("neck_01", [(-0.2, 0.3), (-0.4, 0.4), (-0.2, 0.2)]),
    ("head", [(-0.2, 0.2), (-0.3, 0.3), (-0.15, 0.15)]),
    ("clavicle_l", [(-0.1, 0.1), (0.0, 0.0), (-0.1, 0.25)]),
    ("upperarm_l", [(-0.5, 1.2), (-0.4, 0.4), (-0.5, 1.0)]),
    ("lowerarm_l", [(0.0, 1.5), (-0.4, 0.4), (0.0, 0.0)]),
    ("hand_l", [(-0.5, 0.5), (-0.2, 0.2), (-0.3, 0.3)]),
    ("thigh_l", [(-1.0, 0.3), (-0.3, 0.3), (-0.4, 0.1)]),
    ("calf_l", [(0.0, 1.4), (0.0, 0.0), (0.0, 0.0)]),
    ("foot_l", [(-0.3, 0.4), (-0.1, 0.1), (-0.1, 0.1)]),
];

/// One draw of the random sampler: every limited bone gets an Euler triple uniform within its
/// limits (left and right drawn independently), from a ChaCha8 stream seeded by `seed`.
pub fn random_pose_unchecked(rng: &mut impl rand_core::RngCore) -> Pose {
    let mut p = Pose::default();
    let mut uniform = |lo: f64, hi: f64| lo + (hi - lo) * unit_f64(rng);
    for (bone, lim) in JOINT_LIMITS {
        let e = [0, 1, 2].map(|k| uniform(lim[k].0, lim[k].1));
        if let Some(stem) = bone.strip_suffix("_l") {
            p.rotations.insert(bone.to_string(), e);
            let e2 = [0, 1, 2].map(|k| uniform(lim[k].0, lim[k].1));
            p.rotations.insert(format!("{stem}_r"), mirror_euler(e2));
        } else {
            p.rotations.insert(bone.to_string(), e);
        }
    }
    p
}

/// A uniform f64 in [0, 1) from 53 random bits.
pub fn unit_f64(rng: &mut impl rand_core::RngCore) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

/// Linear interpolation of Euler angles between two poses (`t` = 0 gives `a`, 1 gives `b`;
/// bones missing from one pose count as rest).
pub fn interpolate(a: &Pose, b: &Pose, t: f64) -> Pose {
    let mut out = Pose::default();
    for name in a.rotations.keys().chain(b.rotations.keys()) {
        let ea = a.rotations.get(name).copied().unwrap_or([0.0; 3]);
        let eb = b.rotations.get(name).copied().unwrap_or([0.0; 3]);
        out.rotations
            .insert(name.clone(), [0, 1, 2].map(|k| ea[k] + t * (eb[k] - ea[k])));
    }
    out
}
