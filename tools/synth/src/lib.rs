//! symcorr-synth: synthetic human bodies with exact ground truth, and a virtual Kinect.

pub mod assets;
pub mod body;
mod error;
pub mod math;
pub mod poses;

pub use assets::Assets;
pub use body::{Body, Model, Pose, Posed, Shape};
pub use error::{Result, SynthError};
pub mod dataset;
pub mod fixtures;
pub mod geom;
pub mod kinect;
pub mod mapping;
pub mod noise;
pub mod render;
