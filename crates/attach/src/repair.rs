//! Joint repair before attachment: missing, untracked or non-finite joints are rebuilt from
//! their chain where that is well defined, otherwise dropped (with their bones).

use crate::geom::{lerp, Joints};
use crate::{AttachError, Joint, JointRepair, Skeleton, BONES};
use nalgebra::{distance, Point3};

pub(crate) struct Repaired {
    pub positions: Joints,
    pub usable: [bool; 20],
    pub repaired: Vec<(Joint, JointRepair)>,
}

/// Rebuild rules, tried in order until nothing changes: `(joint, a, b, t)` puts the joint at
/// `a + t·(b − a)` when `a` and `b` are usable. Interior joints are midpoints of their chain
/// neighbours; hand and head extrapolate their parent bone with typical proportions.
const RULES: [(Joint, Joint, Joint, f64); 17] = {
    use Joint as J;
    [
        (J::HipCenter, J::HipLeft, J::HipRight, 0.5),
        (J::ShoulderCenter, J::ShoulderLeft, J::ShoulderRight, 0.5),
        (J::Spine, J::HipCenter, J::ShoulderCenter, 0.5),
        (J::HipCenter, J::ShoulderCenter, J::Spine, 2.0),
        (J::ShoulderCenter, J::HipCenter, J::Spine, 2.0),
        (J::Head, J::Spine, J::ShoulderCenter, 1.7),
        (J::ElbowLeft, J::ShoulderLeft, J::WristLeft, 0.5),
        (J::WristLeft, J::ElbowLeft, J::HandLeft, 0.75),
        (J::HandLeft, J::ElbowLeft, J::WristLeft, 1.3),
        (J::ElbowRight, J::ShoulderRight, J::WristRight, 0.5),
        (J::WristRight, J::ElbowRight, J::HandRight, 0.75),
        (J::HandRight, J::ElbowRight, J::WristRight, 1.3),
        (J::KneeLeft, J::HipLeft, J::AnkleLeft, 0.5),
        (J::AnkleLeft, J::KneeLeft, J::FootLeft, 0.8),
        (J::KneeRight, J::HipRight, J::AnkleRight, 0.5),
        (J::AnkleRight, J::KneeRight, J::FootRight, 0.8),
        (J::Spine, J::ShoulderCenter, J::HipCenter, 0.5),
    ]
};

pub(crate) fn repair(sk: &Skeleton) -> Result<Repaired, AttachError> {
    let mut positions = sk.positions;
    let mut usable = [false; 20];
    for j in Joint::ALL {
        let finite = positions[j.index()].iter().all(|c| c.is_finite());
        usable[j.index()] = finite && sk.tracks(j);
    }
    let mut repaired = Vec::new();
    loop {
        let mut changed = false;
        for &(j, a, b, t) in &RULES {
            if !usable[j.index()] && usable[a.index()] && usable[b.index()] {
                positions[j.index()] = lerp(&positions[a.index()], &positions[b.index()], t);
                usable[j.index()] = true;
                repaired.push((j, JointRepair::Interpolated));
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    for j in Joint::ALL {
        if !usable[j.index()] {
            repaired.push((j, JointRepair::Dropped));
        }
    }
    let n_usable = usable.iter().filter(|&&u| u).count();
    let extent = extent(&positions, &usable);
    let torso = usable[Joint::HipCenter.index()] && usable[Joint::ShoulderCenter.index()];
    let any_bone = BONES
        .iter()
        .any(|b| usable[b.parent.index()] && usable[b.child.index()]);
    if !torso || !any_bone || !(extent > 0.0) || n_usable < 3 {
        return Err(AttachError::EmptySkeleton {
            usable: n_usable,
            extent,
        });
    }
    for j in 0..20 {
        if !usable[j] {
            // Keep non-finite numbers out of everything downstream.
            positions[j] = positions[Joint::HipCenter.index()];
        }
    }
    Ok(Repaired {
        positions,
        usable,
        repaired,
    })
}

/// Bounding-box diagonal of the usable joints (0 if fewer than two).
pub(crate) fn extent(p: &Joints, usable: &[bool; 20]) -> f64 {
    let mut lo = Point3::from([f64::INFINITY; 3]);
    let mut hi = Point3::from([f64::NEG_INFINITY; 3]);
    let mut n = 0;
    for j in 0..20 {
        if usable[j] {
            n += 1;
            lo = lo.inf(&p[j]);
            hi = hi.sup(&p[j]);
        }
    }
    if n < 2 {
        return 0.0;
    }
    distance(&lo, &hi)
}

/// Pose-independent skeleton height: head → shoulder centre → spine → hip centre, plus the
/// longer leg chain (hip → knee → ankle). Falls back to the joints' extent.
pub(crate) fn skeleton_height(p: &Joints, usable: &[bool; 20]) -> f64 {
    use Joint as J;
    let chain = |c: &[Joint]| -> Option<f64> {
        let mut s = 0.0;
        for w in c.windows(2) {
            if !usable[w[0].index()] || !usable[w[1].index()] {
                return None;
            }
            s += distance(&p[w[0].index()], &p[w[1].index()]);
        }
        Some(s)
    };
    let torso = chain(&[J::Head, J::ShoulderCenter, J::Spine, J::HipCenter]);
    let legl = chain(&[J::HipCenter, J::HipLeft, J::KneeLeft, J::AnkleLeft]);
    let legr = chain(&[J::HipCenter, J::HipRight, J::KneeRight, J::AnkleRight]);
    let leg = match (legl, legr) {
        (Some(a), Some(b)) => Some(a.max(b)),
        (a, b) => a.or(b),
    };
    match (torso, leg) {
        // Head joint is mid-head and the ankle above the sole: add ~10 % for the real height.
        (Some(t), Some(l)) if t + l > 0.0 => 1.1 * (t + l),
        _ => extent(p, usable).max(f64::MIN_POSITIVE),
    }
}
