//! The canonical Kinect skeleton, its 17 segments, and skeleton attachment.
//!
//! [`Skeleton`], [`Joint`], [`Segment`] (with [`Segment::mirror`]) are the types every joint
//! importer in symcorr produces. Attachment (labels and bone-heat weights) arrives with the
//! attachment issue.

mod skeleton;

pub use skeleton::{Joint, Segment, Skeleton, BONES};
