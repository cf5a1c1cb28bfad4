//! symcorr-synth: synthetic human bodies with exact ground truth, and a virtual Kinect.
//!
//! Built on the CC0 MakeHuman / MPFB2 assets committed in `fixtures/mpfb2/` (see
//! [`Assets::default_dir`]), so it works on a fresh clone. It writes the test fixtures
//! (`fixtures/synth`), the benchmark datasets (`tools/bench/make_datasets.sh`) and the MakeHuman
//! boundary convention of symcorr-attach ([`convention`]). The command-line tool
//! `symcorr-synth` and the output layouts are described in `tools/synth/README.md`.
//!
//! # Data flow
//! [`Assets`] → [`Model`] (rig and skin weights) → [`Model::body`] with a [`Shape`] (macro
//! targets; rig joints recomputed from the shaped mesh) → [`Body::pose`] with a [`Pose`]
//! (named, walk-cycle or random; [`poses`]) → [`Posed`] mesh → [`mapping`]: 20 Kinect v1
//! joints and 17-segment reference labels → optional joint noise ([`noise`]) → [`dataset`]
//! folders, or [`render`]: a virtual-Kinect depth frame with per-pixel vertex ids ([`kinect`]),
//! or a whole recording with a tracker-like corrupted joint log ([`recording`]).
//!
//! ```
//! use symcorr_synth::{Assets, Model, Shape, poses, mapping};
//! let model = Model::new(Assets::load(&Assets::default_dir())?)?;
//! let body = model.body(&Shape::parse("male-young-minmuscle-maxweight=0.5")?)?;
//! let posed = body.pose(&poses::named_pose(&model.assets, "walk-10")?)?;
//! let joints = mapping::kinect_joints(&body, &posed)?; // 20 Kinect v1 joints, metres
//! assert_eq!(posed.mesh.num_vertices(), 13_380);
//! assert!(joints.positions.iter().all(|p| p.iter().all(|c| c.is_finite())));
//! # Ok::<(), symcorr_synth::SynthError>(())
//! ```
//!
//! # Invariants and decisions
//! * **Ground truth is the vertex id**: base-mesh group `body` only (vertices 0..13379 in file
//!   order, quads fan-triangulated `(0,1,2),(0,2,3)`) — identical to `fixtures/body/body.off`,
//!   scaled from decimetres to metres. Frame: MakeHuman's (x = subject's left, y up, z = the
//!   subject's front); the rest pose is centred near the origin, feet at y ≈ −0.82 m.
//! * **Shape**: sparse macro targets added to *all* 19,158 base vertices (so the joint cubes and
//!   helper vertices follow), weighted in [0, 1]; several empty targets in the asset set
//!   (`*-averagemuscle-averageweight`) do nothing.
//! * **Posing** follows Blender's semantics so that MPFB2 pose files apply unchanged: bone rest
//!   frames from head, tail and roll ([`math::vec_roll_to_mat3`]), `XYZ` Euler rotations in the
//!   bone's rest frame, forward kinematics parent before child, linear blend skinning with the
//!   `game_engine` weights normalised per vertex. The walk cycle's limbs are IK targets of
//!   another rig, so only its FK curves are replayed and the limbs follow a procedural gait
//!   ([`poses::walk_pose`]); random poses are uniform per-bone Euler boxes
//!   ([`poses::JOINT_LIMITS`]), rejected while parts ≥ 3 segment hops apart intersect
//!   ([`mapping::SelfIntersectionCheck`]).
//! * **Mirror map**: `hm08.mirror` restricted to the body (every body vertex maps to a body
//!   vertex; checked). **Virtual Kinect**: depth is z (not range) in mm; vertex ids are the
//!   nearest corner of the visible triangle.
//! * **Randomness**: ChaCha8 streams with explicit seeds and per-body/per-frame stream numbers:
//!   output is bit-for-bit reproducible and independent of generation order (a test checks the
//!   committed fixtures).
//!
//! Measured with these bodies: `docs/decisions/` (attachment and correspondence records); the
//! label-agreement figures of symcorr-attach are scored by [`label_score`].

pub mod assets;
pub mod body;
pub mod convention;
pub mod dataset;
mod error;
pub mod fixtures;
pub mod geom;
pub mod kinect;
pub mod label_score;
pub mod mapping;
pub mod math;
pub mod noise;
pub mod poses;
pub mod recording;
pub mod render;
pub mod tracker;

pub use assets::Assets;
pub use body::{Body, Model, Pose, Posed, Shape};
pub use error::{Result, SynthError};
