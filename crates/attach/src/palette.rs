//! A fixed 17-colour palette for segment-coloured meshes: one colour per [`Segment`], left and
//! right twins deliberately far apart (warm/light on the left, cool/dark on the right) so that a
//! left/right swap is visible at a glance.

use crate::Segment;

/// sRGB colour per segment, indexed by [`Segment::index`].
pub const PALETTE: [[u8; 3]; 17] = [
    [140, 110, 90],  // pelvis: brown-grey
    [200, 200, 200], // torso: light grey
    [250, 220, 170], // head: skin
    [230, 25, 75],   // clavicle_left: red
    [0, 130, 200],   // clavicle_right: blue
    [245, 130, 48],  // upper_arm_left: orange
    [70, 240, 240],  // upper_arm_right: cyan
    [255, 225, 25],  // forearm_left: yellow
    [145, 30, 180],  // forearm_right: purple
    [250, 190, 212], // hip_left: pink
    [0, 128, 128],   // hip_right: teal
    [128, 0, 0],     // thigh_left: maroon
    [0, 0, 128],     // thigh_right: navy
    [170, 110, 40],  // shin_left: ochre
    [0, 100, 0],     // shin_right: dark green
    [240, 50, 230],  // foot_left: magenta
    [210, 245, 60],  // foot_right: lime
];

/// The palette colour of a segment.
///
/// ```
/// use symcorr_attach::{palette::colour, Segment};
/// assert_ne!(colour(Segment::ThighLeft), colour(Segment::ThighRight));
/// ```
pub fn colour(s: Segment) -> [u8; 3] {
    PALETTE[s.index()]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn d(a: [u8; 3], b: [u8; 3]) -> f64 {
        (0..3)
            .map(|k| (a[k] as f64 - b[k] as f64).powi(2))
            .sum::<f64>()
            .sqrt()
    }

    #[test]
    fn colours_are_distinct_and_twins_far_apart() {
        for a in Segment::ALL {
            for b in Segment::ALL {
                if a != b {
                    assert!(d(colour(a), colour(b)) > 40.0, "{a:?} vs {b:?}");
                }
            }
            if a.mirror() != a {
                assert!(d(colour(a), colour(a.mirror())) > 150.0, "{a:?} twin");
            }
        }
    }
}
