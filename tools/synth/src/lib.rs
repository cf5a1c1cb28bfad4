//! symcorr-synth: synthetic human bodies with exact ground truth, and a virtual Kinect.
//!
//! Built on the CC0 MakeHuman / MPFB2 assets committed in `fixtures/mpfb2/` (see
//! [`Assets::default_dir`]), so it works on a fresh clone. The command-line tool
//! `symcorr-synth` and the output layouts are described in `tools/synth/README.md`.
//!
//! ```no_run
//! use symcorr_synth::{Assets, Model, Shape, poses, mapping};
//! let model = Model::new(Assets::load(&Assets::default_dir())?)?;
//! let body = model.body(&Shape::parse("male-young-minmuscle-maxweight=0.5")?)?;
//! let posed = body.pose(&poses::named_pose(&model.assets, "walk-10")?)?;
//! let joints = mapping::kinect_joints(&body, &posed)?; // 20 Kinect v1 joints, metres
//! assert_eq!(posed.mesh.num_vertices(), 13_380);
//! # Ok::<(), symcorr_synth::SynthError>(())
//! ```
//!
//! ## Decisions (what the design left open)
//!
//! * **Body**: base-mesh group `body` only (vertices 0..13379 in file order, quads
//!   fan-triangulated `(0,1,2),(0,2,3)`) — identical to `fixtures/body/body.off`, scaled from
//!   decimetres to metres. Frame: MakeHuman's (x = subject's left, y up, z = subject's front);
//!   the rest pose is centred near the origin, feet at y ≈ −0.82 m.
//! * **Shape**: sparse macro targets added to *all* 19,158 base vertices (so the joint cubes and
//!   helper vertices follow), weighted in [0, 1]; rig joints are then recomputed from the
//!   shaped vertices (`CUBE` = centroid of a vertex group, `MEAN`/`VERTEX` = mean of listed
//!   vertices). Several empty targets in the asset set (`*-averagemuscle-averageweight`) do
//!   nothing.
//! * **Posing**: Blender semantics so that MPFB2 pose files apply unchanged: bone rest frames
//!   from head, tail and roll ([`math::vec_roll_to_mat3`]), rotations are `XYZ` Euler in the
//!   bone's rest frame, forward kinematics parent before child, then linear blend skinning with
//!   the `game_engine` weights normalised per vertex. Computation happens in Blender's z-up
//!   frame and is converted back.
//! * **Walk**: the MPFB2 walk cycle's legs and arms are IK targets of a different rig; only its
//!   FK curves (spine, neck, head, clavicles) are replayed, the limbs follow a procedural gait
//!   ([`poses::walk_pose`]).
//! * **Random poses**: uniform per-bone Euler boxes ([`poses::JOINT_LIMITS`]), rejected while
//!   parts ≥ 3 segment hops apart intersect ([`mapping::SelfIntersectionCheck`]).
//! * **Joints and labels**: the two tables in [`mapping`].
//! * **Mirror map**: `hm08.mirror` restricted to the body (every body vertex maps to a body
//!   vertex; checked).
//! * **Virtual Kinect**: see [`render`]; depth is z (not range) in mm; vertex ids are the nearest
//!   corner of the visible triangle.
//! * **Randomness**: ChaCha8 streams with explicit seeds and per-body/per-frame stream numbers:
//!   output is bit-for-bit reproducible and independent of generation order.

pub mod assets;
pub mod body;
pub mod convention;
pub mod dataset;
mod error;
pub mod fixtures;
pub mod geom;
pub mod kinect;
pub mod mapping;
pub mod math;
pub mod noise;
pub mod poses;
pub mod render;

pub use assets::Assets;
pub use body::{Body, Model, Pose, Posed, Shape};
pub use error::{Result, SynthError};
