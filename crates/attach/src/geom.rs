//! The 3-vector helpers attach uses beyond the basic ones, from their one owner
//! (`symcorr_mesh::geometry`).

pub(crate) use symcorr_mesh::geometry::{closest_on_segment, mat_vec, unit};
