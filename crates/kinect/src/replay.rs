//! Replay of joint logs: a frame by index or time, or a robust average over a time window, and
//! the consistency of bone lengths over the log (a rigid skeleton's bones do not change length;
//! a tracker's do, and by how much says how far to trust it).
//!
//! ```
//! use symcorr_skeleton::Skeleton;
//! use symcorr_kinect::joints::JointLog;
//! use symcorr_kinect::replay::FrameSelect;
//! let mut p = [[0.0; 3]; 20];
//! for (i, q) in p.iter_mut().enumerate() { *q = [0.1 * i as f64, 0.0, 2.0]; }
//! let log = JointLog::from_skeletons(vec![Skeleton::from_arrays(p); 5], 30.0);
//! let s = log.select(FrameSelect::Window { start_s: 0.0, end_s: 1.0 }).unwrap();
//! assert_eq!(s, Skeleton::from_arrays(p));
//! assert!(log.bone_lengths().max_relative_std < 1e-12);
//! ```

use crate::error::KinectError;
use crate::joints::JointLog;
use nalgebra::{distance, Point3};
use symcorr_skeleton::{Bone, Joint, Skeleton, BONES};

/// Which skeleton of a log to use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrameSelect {
    /// The frame with this index (0-based, file order).
    Index(usize),
    /// The frame whose time is nearest to this (seconds).
    Time(f64),
    /// The robust average of the frames with `start_s ≤ time ≤ end_s` ([`JointLog::robust_average`]).
    Window {
        /// Window start, seconds.
        start_s: f64,
        /// Window end, seconds.
        end_s: f64,
    },
}

/// Length statistics of one bone over a log.
#[derive(Debug, Clone, PartialEq)]
pub struct BoneLengthStats {
    /// The bone (parent, child).
    pub bone: Bone,
    /// Mean length, metres.
    pub mean: f64,
    /// Standard deviation, metres.
    pub std: f64,
    /// Shortest length seen.
    pub min: f64,
    /// Longest length seen.
    pub max: f64,
}

/// Bone-length consistency over a log.
#[derive(Debug, Clone, PartialEq)]
pub struct BoneLengthReport {
    /// One entry per bone of [`BONES`], same order.
    pub bones: Vec<BoneLengthStats>,
    /// The largest std/mean over all bones (0 for a rigid skeleton).
    pub max_relative_std: f64,
    /// The bone with the largest relative spread.
    pub worst_bone: Bone,
}

impl BoneLengthReport {
    /// Whether every bone's length varies by less than `tolerance` relative to its mean
    /// (e.g. 0.1 for 10 %).
    pub fn is_consistent(&self, tolerance: f64) -> bool {
        self.max_relative_std <= tolerance
    }
}

impl std::fmt::Display for BoneLengthReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "bone lengths: worst {}→{} varies by {:.1} % (std/mean)",
            self.worst_bone.parent.name(),
            self.worst_bone.child.name(),
            100.0 * self.max_relative_std
        )?;
        for b in &self.bones {
            writeln!(
                f,
                "  {:>15} → {:<15} mean {:.3} m  std {:.4} m  range [{:.3}, {:.3}]",
                b.bone.parent.name(),
                b.bone.child.name(),
                b.mean,
                b.std,
                b.min,
                b.max
            )?;
        }
        Ok(())
    }
}

/// The median of a window's values; a window is never empty (`robust_average` refuses one),
/// so the fallback is never taken.
fn median(v: &mut [f64]) -> f64 {
    crate::geom::median(v).unwrap_or(0.0)
}

/// Weighted median: the smallest value whose cumulative weight reaches half the total.
fn weighted_median(values: &[(f64, f64)]) -> f64 {
    let mut v: Vec<(f64, f64)> = values.to_vec();
    let total: f64 = v.iter().map(|x| x.1).sum();
    if total <= 0.0 {
        let mut plain: Vec<f64> = v.iter().map(|x| x.0).collect();
        return median(&mut plain);
    }
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut acc = 0.0;
    for (x, w) in &v {
        acc += w;
        if acc >= 0.5 * total {
            return *x;
        }
    }
    v[v.len() - 1].0
}

impl JointLog {
    /// The skeleton chosen by `select`.
    pub fn select(&self, select: FrameSelect) -> Result<Skeleton, KinectError> {
        match select {
            FrameSelect::Index(i) => self.frame(i).cloned(),
            FrameSelect::Time(t) => self.frame_at_time(t).cloned(),
            FrameSelect::Window { start_s, end_s } => self.robust_average(start_s, end_s),
        }
    }

    /// Frame `i` (0-based).
    pub fn frame(&self, i: usize) -> Result<&Skeleton, KinectError> {
        self.frames.get(i).map(|f| &f.skeleton).ok_or_else(|| {
            KinectError::Replay(format!(
                "frame {i} requested, but the log has {} frames (0..{})",
                self.frames.len(),
                self.frames.len().saturating_sub(1)
            ))
        })
    }

    /// The frame whose time is nearest to `t` seconds (ties → the earlier frame).
    pub fn frame_at_time(&self, t: f64) -> Result<&Skeleton, KinectError> {
        if !t.is_finite() {
            return Err(KinectError::Replay(format!("time {t} is not finite")));
        }
        self.frames
            .iter()
            .min_by(|a, b| (a.time_s - t).abs().total_cmp(&(b.time_s - t).abs()))
            .map(|f| &f.skeleton)
            .ok_or_else(|| KinectError::Replay("the joint log has no frames".into()))
    }

    /// Robust average of the frames with `start_s ≤ time_s ≤ end_s` that track a joint (a
    /// frame in which the tracker lost the body, every joint untracked, says nothing):
    ///
    /// 1. per joint, the coordinate-wise median over the window;
    /// 2. a frame's deviation is the median over joints of its distance to that median; frames
    ///    deviating by more than `3 × median deviation + 1 cm` are dropped as outliers
    ///    (a mis-tracked frame moves many joints at once);
    /// 3. per joint and coordinate, the confidence-weighted median of the kept frames
    ///    (unweighted if every confidence is 0). Confidence is the kept frames' mean; a joint is
    ///    flagged interpolated if it was in every kept frame.
    pub fn robust_average(&self, start_s: f64, end_s: f64) -> Result<Skeleton, KinectError> {
        let window: Vec<&Skeleton> = self
            .frames
            .iter()
            .filter(|f| f.time_s >= start_s && f.time_s <= end_s)
            .map(|f| &f.skeleton)
            .filter(|s| s.tracks_any())
            .collect();
        if window.is_empty() {
            return Err(KinectError::Replay(format!(
                "no frame between {start_s} s and {end_s} s that tracks a joint (the log spans {} \
                 s to {} s)",
                self.frames.first().map_or(0.0, |f| f.time_s),
                self.frames.last().map_or(0.0, |f| f.time_s)
            )));
        }
        // Per-coordinate medians: not a point any frame had, but robust per axis.
        let med = |frames: &[&Skeleton]| -> [Point3<f64>; Joint::COUNT] {
            let mut m = [Point3::origin(); Joint::COUNT];
            for (j, mj) in m.iter_mut().enumerate() {
                for (k, c) in mj.iter_mut().enumerate() {
                    let mut v: Vec<f64> = frames.iter().map(|s| s.positions[j][k]).collect();
                    *c = median(&mut v);
                }
            }
            m
        };
        let center = med(&window);
        let deviation: Vec<f64> = window
            .iter()
            .map(|s| {
                let mut d: Vec<f64> = (0..20)
                    .map(|j| distance(&s.positions[j], &center[j]))
                    .collect();
                median(&mut d)
            })
            .collect();
        let typical = median(&mut deviation.clone());
        let limit = 3.0 * typical + 0.01;
        let kept: Vec<&Skeleton> = window
            .iter()
            .zip(&deviation)
            .filter(|(_, d)| **d <= limit)
            .map(|(s, _)| *s)
            .collect();
        // The median frame always satisfies the limit, so `kept` is never empty.
        let mut out = Skeleton::from_positions(center);
        for j in 0..20 {
            for k in 0..3 {
                let vals: Vec<(f64, f64)> = kept
                    .iter()
                    .map(|s| (s.positions[j][k], s.confidence[j]))
                    .collect();
                out.positions[j][k] = weighted_median(&vals);
            }
            out.confidence[j] =
                kept.iter().map(|s| s.confidence[j]).sum::<f64>() / kept.len() as f64;
            out.interpolated[j] = kept.iter().all(|s| s.interpolated[j]);
        }
        Ok(out)
    }

    /// Bone-length statistics over every frame.
    pub fn bone_lengths(&self) -> BoneLengthReport {
        let mut bones = Vec::with_capacity(BONES.len());
        let mut worst = (BONES[0], 0.0);
        for &bone in BONES.iter() {
            let lengths: Vec<f64> = self
                .frames
                .iter()
                .map(|f| f.skeleton.bone_vector(bone).norm())
                .collect();
            let n = lengths.len().max(1) as f64;
            let mean = lengths.iter().sum::<f64>() / n;
            let var = lengths.iter().map(|l| (l - mean) * (l - mean)).sum::<f64>() / n;
            let std = var.sqrt();
            let rel = if mean > 0.0 { std / mean } else { 0.0 };
            if rel > worst.1 {
                worst = (bone, rel);
            }
            bones.push(BoneLengthStats {
                bone,
                mean,
                std,
                min: lengths.iter().copied().fold(f64::INFINITY, f64::min),
                max: lengths.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            });
        }
        BoneLengthReport {
            bones,
            max_relative_std: worst.1,
            worst_bone: worst.0,
        }
    }
}
