//! The canonical human skeleton of symcorr: Kinect v1's 20 [`Joint`]s, its 19 [`Bone`]s, the
//! 17 body [`Segment`]s (the two wrist → hand bones merge into the forearms), the [`BodySide`]
//! each is on, a [`Skeleton`] (one position, confidence and provenance per joint) and its
//! [`SagittalPlanes`].
//!
//! Every joint importer in symcorr produces a [`Skeleton`]; attachment labels each vertex with
//! a [`Segment`]; matching never pairs a [`BodySide::Left`] point with a [`BodySide::Right`]
//! one. This crate is the leaf they share: it depends on nothing of symcorr, and speaks
//! nalgebra's [`Point3`](nalgebra::Point3) and [`Vector3`](nalgebra::Vector3).
//!
//! ```
//! use symcorr_skeleton::{BodySide, Joint, Segment, Skeleton, BONES};
//! let mut xyz = [[0.0; 3]; Joint::COUNT];
//! xyz[Joint::KneeLeft.index()] = [0.1, 0.5, 0.0];
//! let skeleton = Skeleton::from_arrays(xyz);
//! // A tracker that mixed up the legs reports the left knee where the right one is.
//! let swapped = skeleton.swap_sides();
//! assert_eq!(swapped.position(Joint::KneeRight), skeleton.position(Joint::KneeLeft));
//! // Each segment knows its bones and its side; twins mirror each other.
//! assert_eq!(Segment::ThighLeft.bones()[0].child, Joint::KneeLeft);
//! assert_eq!(Segment::ThighLeft.mirror().side(), BodySide::Right);
//! assert_eq!(BONES.len(), 19);
//! ```
//!
//! Invariants: [`Joint::ALL`], [`BONES`] and [`Segment::ALL`] are in the numbering of
//! DESIGN.md (a joint's, bone's or segment's index is its id in every file); bones list
//! parents before children; every bone belongs to exactly one segment; `mirror` is an
//! involution on joints, bones, segments and sides. Left and right are the subject's
//! anatomical sides, never the camera's.

mod joint;
mod planes;
mod segment;
mod skeleton;

pub use joint::{Bone, Joint, LimbPair, BONES};
pub use planes::{Plane, SagittalPlanes};
pub use segment::{BodySide, Segment};
pub use skeleton::Skeleton;
