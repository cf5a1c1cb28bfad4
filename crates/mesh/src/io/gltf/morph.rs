//! Animated GLB written frame by frame: one mesh whose morph targets are its frames, played in
//! turn by an animation of the mesh's weights.
//!
//! Layout of the file (glTF 2.0, one buffer in the GLB's BIN chunk, every view 4-byte aligned):
//! * mesh 0, one `TRIANGLES` primitive: `POSITION` (the rest positions, f32, with min/max),
//!   u32 indices, a plain double-sided material, and one morph target per frame — `POSITION`
//!   displacements from the rest positions (f32, each with its own min/max as the
//!   specification requires); `extras.targetNames` names them (Blender's shape keys, three.js'
//!   `morphTargetDictionary`); the mesh's default `weights` show frame 0.
//! * no `NORMAL`: normals fixed at the rest pose would light a moved limb as if it had not
//!   moved, and morphing normals too would double the file; viewers compute them from the
//!   posed triangles (three.js shades such a mesh flat, Blender computes its own).
//! * animation 0: one sampler, input the frames' times (seconds, strictly increasing, with
//!   min/max), output the weights — per key, one weight per target, 1 for the key's own target
//!   and 0 for the others (frames × targets floats: the caller bounds the number of frames,
//!   the weights grow with its square) — and one channel driving node 0's `weights`. At key k
//!   the mesh is exactly rest + target k; between keys, [`MorphInterpolation`] decides.
//!
//! The JSON chunk comes first in a GLB and holds every target's min/max, so the targets are
//! kept in an anonymous scratch file (removed when the writer is dropped) until
//! [`MorphAnimationWriter::finish`] streams the whole file into an [`OutputBatch`]: memory holds
//! the rest mesh and one frame, never the animation.

use std::fs::File;
use std::io::{BufWriter, Read as _, Seek as _, SeekFrom, Write};
use std::path::Path;

use serde_json::json;

use crate::io::OutputBatch;
use crate::{MeshError, TriMesh};

/// How the mesh moves between two frames of a [`MorphAnimationWriter`]'s animation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MorphInterpolation {
    /// Each frame is held until the next one (glTF `STEP`).
    Step,
    /// Positions blend linearly from one frame to the next (glTF `LINEAR` on one-hot weights).
    #[default]
    Linear,
}

impl MorphInterpolation {
    fn gltf_name(self) -> &'static str {
        match self {
            MorphInterpolation::Step => "STEP",
            MorphInterpolation::Linear => "LINEAR",
        }
    }
}

/// Writes an animated GLB of a mesh moving through frames (module docs), one frame at a time.
///
/// ```
/// use symcorr_mesh::io::gltf::{MorphAnimationWriter, MorphInterpolation};
/// use symcorr_mesh::io::OutputBatch;
/// use symcorr_mesh::TriMesh;
/// let dir = tempfile::tempdir().unwrap();
/// let rest = TriMesh::new(
///     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
///     vec![[0, 1, 2]],
/// ).unwrap();
/// let mut w = MorphAnimationWriter::new(&rest, MorphInterpolation::Linear, dir.path()).unwrap();
/// for (k, t) in [0.0f32, 0.033, 0.067].into_iter().enumerate() {
///     let lift = k as f32 * 0.1;
///     let frame = [[0.0, 0.0, lift], [1.0, 0.0, lift], [0.0, 1.0, lift]];
///     w.push(&format!("frame {k}"), t, &frame).unwrap();
/// }
/// let path = dir.path().join("anim.glb");
/// let mut batch = OutputBatch::new();
/// let bytes = w.finish(&mut batch, &path).unwrap();
/// batch.commit().unwrap();
/// assert_eq!(std::fs::metadata(&path).unwrap().len(), bytes);
/// // Any glTF reader sees the rest mesh.
/// assert_eq!(symcorr_mesh::io::read(&path).unwrap().mesh, rest);
/// ```
#[derive(Debug)]
pub struct MorphAnimationWriter {
    rest: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    interpolation: MorphInterpolation,
    /// The displacements of the targets pushed so far, f32 little-endian, in order.
    scratch: BufWriter<File>,
    names: Vec<String>,
    times: Vec<f32>,
    /// Per target, the min and max of its displacements.
    bounds: Vec<([f32; 3], [f32; 3])>,
}

/// Bytes of a GLB header and its two chunk headers.
const GLB_OVERHEAD: u64 = 12 + 8 + 8;

impl MorphAnimationWriter {
    /// A writer for frames of `rest` (its vertices and triangles; positions stored as f32),
    /// keeping the pushed frames in an anonymous scratch file in `scratch_dir` (choose the
    /// output's folder: the scratch file is as large as the targets, and a `/tmp` in memory
    /// would hold them in RAM).
    ///
    /// Errors: [`MeshError::NotRepresentable`] for a rest coordinate beyond f32,
    /// [`MeshError::Io`] when the scratch file cannot be created.
    pub fn new(
        rest: &TriMesh,
        interpolation: MorphInterpolation,
        scratch_dir: &Path,
    ) -> Result<MorphAnimationWriter, MeshError> {
        super::check_f32(rest, "GLB")?;
        let scratch = tempfile::tempfile_in(scratch_dir).map_err(|source| MeshError::Io {
            file: format!("scratch file in {}", scratch_dir.display()),
            source,
        })?;
        Ok(MorphAnimationWriter {
            rest: rest.positions.iter().map(|p| p.map(|x| x as f32)).collect(),
            triangles: rest.triangles.clone(),
            interpolation,
            scratch: BufWriter::new(scratch),
            names: Vec::new(),
            times: Vec::new(),
            bounds: Vec::new(),
        })
    }

    /// Frames pushed so far.
    pub fn frames(&self) -> usize {
        self.times.len()
    }

    /// Appends a frame: the mesh's vertex positions `positions` (one per rest vertex) shown at
    /// `time_s` seconds, as a morph target named `name`.
    ///
    /// Errors: [`MeshError::MorphTarget`] for another number of positions, a non-finite
    /// coordinate, or a time not after the previous frame's (nothing is appended);
    /// [`MeshError::GlbTooLarge`] when the file would pass 4 GiB; [`MeshError::Io`] from the
    /// scratch file.
    pub fn push(
        &mut self,
        name: &str,
        time_s: f32,
        positions: &[[f32; 3]],
    ) -> Result<(), MeshError> {
        let target = self.times.len();
        let bad = |message: String| Err(MeshError::MorphTarget { target, message });
        if positions.len() != self.rest.len() {
            return bad(format!(
                "{} positions for a mesh of {} vertices",
                positions.len(),
                self.rest.len()
            ));
        }
        if let Some(v) = positions
            .iter()
            .position(|p| p.iter().any(|x| !x.is_finite()))
        {
            return bad(format!("vertex {v} has a non-finite coordinate"));
        }
        // Strictly increasing, as glTF requires of an animation's input.
        if !time_s.is_finite() || self.times.last().is_some_and(|&t| time_s <= t) {
            return bad(format!(
                "time {time_s} s is not after the previous frame's ({:?} s)",
                self.times.last()
            ));
        }
        let bytes = self.file_bytes(target + 1, 0);
        if bytes > u64::from(u32::MAX) {
            return Err(MeshError::GlbTooLarge { bytes });
        }
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        let mut row = Vec::with_capacity(positions.len() * 12);
        for (p, r) in positions.iter().zip(&self.rest) {
            for k in 0..3 {
                let d = p[k] - r[k];
                lo[k] = lo[k].min(d);
                hi[k] = hi[k].max(d);
                row.extend_from_slice(&d.to_le_bytes());
            }
        }
        self.scratch
            .write_all(&row)
            .map_err(|source| MeshError::Io {
                file: "morph animation scratch file".to_string(),
                source,
            })?;
        self.names.push(name.to_string());
        self.times.push(time_s);
        self.bounds.push((lo, hi));
        Ok(())
    }

    /// Size of the GLB with `targets` targets and a JSON chunk of `json` bytes.
    fn file_bytes(&self, targets: usize, json: usize) -> u64 {
        let (n, t, k) = (
            self.rest.len() as u64,
            self.triangles.len() as u64,
            targets as u64,
        );
        GLB_OVERHEAD + json as u64 + 12 * n + 12 * t + k * 12 * n + 4 * k + 4 * k * k
    }

    /// Stages the GLB for `path` in `batch` (streamed into its temporary file; it appears when
    /// the batch is committed) and returns its size in bytes.
    ///
    /// Errors: [`MeshError::NoMorphTargets`] when no frame was pushed,
    /// [`MeshError::GlbTooLarge`], and those of [`OutputBatch::add_streamed`].
    pub fn finish(self, batch: &mut OutputBatch, path: &Path) -> Result<u64, MeshError> {
        let k = self.times.len();
        if k == 0 {
            return Err(MeshError::NoMorphTargets);
        }
        let n = self.rest.len();
        let mut json = self.document().to_string().into_bytes();
        super::pad4(&mut json, b' ');
        let bin_len = self.file_bytes(k, 0) - GLB_OVERHEAD;
        let total = GLB_OVERHEAD + json.len() as u64 + bin_len;
        let total32 = u32::try_from(total).map_err(|_| MeshError::GlbTooLarge { bytes: total })?;
        // Invariant: bin_len < total, which fits u32.
        let bin32 = bin_len as u32;
        let MorphAnimationWriter {
            rest,
            triangles,
            times,
            scratch,
            ..
        } = self;
        let scratch_err = |source| MeshError::Io {
            file: "morph animation scratch file".to_string(),
            source,
        };
        let mut scratch = scratch
            .into_inner()
            .map_err(|e| scratch_err(e.into_error()))?;
        scratch.seek(SeekFrom::Start(0)).map_err(scratch_err)?;
        batch.add_streamed(path, |w| {
            w.write_all(b"glTF")?;
            w.write_all(&2u32.to_le_bytes())?;
            w.write_all(&total32.to_le_bytes())?;
            w.write_all(&(json.len() as u32).to_le_bytes())?;
            w.write_all(b"JSON")?;
            w.write_all(&json)?;
            w.write_all(&bin32.to_le_bytes())?;
            w.write_all(b"BIN\0")?;
            for x in rest.as_flattened() {
                w.write_all(&x.to_le_bytes())?;
            }
            for i in triangles.as_flattened() {
                w.write_all(&i.to_le_bytes())?;
            }
            // Exactly the targets' bytes: a short scratch file is an error, not a short GLB.
            let want = (k * n * 12) as u64;
            let copied = std::io::copy(&mut (&mut scratch).take(want), &mut *w)?;
            if copied != want {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::UnexpectedEof,
                    "the scratch file of the morph targets is shorter than written",
                ));
            }
            for t in &times {
                w.write_all(&t.to_le_bytes())?;
            }
            let (one, zero) = (1f32.to_le_bytes(), 0f32.to_le_bytes());
            for key in 0..k {
                for target in 0..k {
                    w.write_all(if key == target { &one } else { &zero })?;
                }
            }
            Ok(())
        })?;
        Ok(total)
    }

    /// The glTF JSON document (module docs), its buffer being the GLB's BIN chunk.
    fn document(&self) -> serde_json::Value {
        let (n, k) = (self.rest.len(), self.times.len());
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for p in &self.rest {
            for c in 0..3 {
                lo[c] = lo[c].min(p[c]);
                hi[c] = hi[c].max(p[c]);
            }
        }
        let pos_len = 12 * n;
        let idx_len = 12 * self.triangles.len();
        let target_off = pos_len + idx_len;
        let times_off = target_off + k * pos_len;
        let weights_off = times_off + 4 * k;
        let mut views = vec![
            json!({"buffer": 0, "byteOffset": 0, "byteLength": pos_len, "target": 34962}),
            json!({"buffer": 0, "byteOffset": pos_len, "byteLength": idx_len, "target": 34963}),
        ];
        let mut accessors = vec![
            json!({"bufferView": 0, "componentType": 5126, "count": n, "type": "VEC3",
                   "min": lo, "max": hi}),
            json!({"bufferView": 1, "componentType": 5125, "count": 3 * self.triangles.len(),
                   "type": "SCALAR"}),
        ];
        let mut targets = Vec::with_capacity(k);
        for (t, (lo, hi)) in self.bounds.iter().enumerate() {
            views.push(json!({"buffer": 0, "byteOffset": target_off + t * pos_len,
                              "byteLength": pos_len, "target": 34962}));
            targets.push(json!({"POSITION": accessors.len()}));
            accessors.push(json!({"bufferView": views.len() - 1, "componentType": 5126,
                                  "count": n, "type": "VEC3", "min": lo, "max": hi}));
        }
        let (t_min, t_max) = (self.times[0], self.times[k - 1]);
        views.push(json!({"buffer": 0, "byteOffset": times_off, "byteLength": 4 * k}));
        let times = accessors.len();
        accessors.push(json!({"bufferView": views.len() - 1, "componentType": 5126,
                              "count": k, "type": "SCALAR", "min": [t_min], "max": [t_max]}));
        views.push(json!({"buffer": 0, "byteOffset": weights_off, "byteLength": 4 * k * k}));
        let weights = accessors.len();
        accessors.push(json!({"bufferView": views.len() - 1, "componentType": 5126,
                              "count": k * k, "type": "SCALAR"}));
        let mut default_weights = vec![0.0f32; k];
        default_weights[0] = 1.0;
        json!({
            "asset": {"version": "2.0", "generator": "symcorr-mesh"},
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "meshes": [{
                "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4,
                                "material": 0, "targets": targets}],
                "weights": default_weights,
                "extras": {"targetNames": self.names},
            }],
            "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
                                                    "metallicFactor": 0.0, "roughnessFactor": 1.0},
                           "doubleSided": true}],
            "animations": [{
                "samplers": [{"input": times, "output": weights,
                              "interpolation": self.interpolation.gltf_name()}],
                "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
            }],
            "buffers": [{"byteLength": self.file_bytes(k, 0) - GLB_OVERHEAD}],
            "bufferViews": views,
            "accessors": accessors,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::Value;

    fn le_u32(b: &[u8], at: usize) -> u32 {
        u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
    }

    fn f32s(b: &[u8]) -> Vec<f32> {
        b.chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    }

    /// A GLB split by hand (not by the reader under test): its JSON and BIN chunks.
    fn chunks(glb: &[u8]) -> (Value, Vec<u8>) {
        assert_eq!(&glb[0..4], b"glTF");
        assert_eq!(le_u32(glb, 4), 2);
        assert_eq!(le_u32(glb, 8) as usize, glb.len());
        let json_len = le_u32(glb, 12) as usize;
        assert_eq!(&glb[16..20], b"JSON");
        assert_eq!(json_len % 4, 0);
        let json = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
        let at = 20 + json_len;
        let bin_len = le_u32(glb, at) as usize;
        assert_eq!(&glb[at + 4..at + 8], b"BIN\0");
        assert_eq!(at + 8 + bin_len, glb.len());
        (json, glb[at + 8..].to_vec())
    }

    /// The floats of accessor `a` (tightly packed f32, as written).
    fn accessor(doc: &Value, bin: &[u8], a: usize) -> Vec<f32> {
        let acc = &doc["accessors"][a];
        assert_eq!(acc["componentType"], 5126);
        let view = &doc["bufferViews"][acc["bufferView"].as_u64().unwrap() as usize];
        let off = view["byteOffset"].as_u64().unwrap() as usize
            + acc["byteOffset"].as_u64().unwrap_or(0) as usize;
        let dims = match acc["type"].as_str().unwrap() {
            "SCALAR" => 1,
            "VEC3" => 3,
            t => panic!("{t}"),
        };
        let len = acc["count"].as_u64().unwrap() as usize * dims * 4;
        assert!(len <= view["byteLength"].as_u64().unwrap() as usize);
        assert_eq!(off % 4, 0);
        f32s(&bin[off..off + len])
    }

    /// glTF requires min/max on POSITION accessors (also a morph target's): they must be the
    /// data's own bounds.
    fn check_bounds(doc: &Value, bin: &[u8], a: usize) {
        let data = accessor(doc, bin, a);
        for c in 0..3 {
            let lo = data
                .iter()
                .skip(c)
                .step_by(3)
                .fold(f32::INFINITY, |m, &x| m.min(x));
            let hi = data
                .iter()
                .skip(c)
                .step_by(3)
                .fold(f32::NEG_INFINITY, |m, &x| m.max(x));
            assert_eq!(doc["accessors"][a]["min"][c].as_f64().unwrap() as f32, lo);
            assert_eq!(doc["accessors"][a]["max"][c].as_f64().unwrap() as f32, hi);
        }
    }

    fn rest() -> TriMesh {
        TriMesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 1.0, 0.5],
            ],
            vec![[0, 1, 2], [1, 3, 2]],
        )
        .unwrap()
    }

    /// Frame `k`: the rest mesh bent and moved, coordinates that f32 cannot hold exactly.
    fn frame(k: usize) -> Vec<[f32; 3]> {
        rest()
            .positions
            .iter()
            .map(|p| {
                let a = k as f64 * 0.37;
                [
                    p[0] * a.cos() + 0.1,
                    p[1] + 1.0 / 3.0,
                    p[2] + a.sin() * p[0] - 2.7,
                ]
                .map(|x| x as f32)
            })
            .collect()
    }

    #[test]
    fn frames_read_back_as_rest_plus_target_with_a_valid_document() {
        let dir = tempfile::tempdir().unwrap();
        let times = [0.0f32, 0.0333, 0.1, 0.1333, 2.5];
        let mut w =
            MorphAnimationWriter::new(&rest(), MorphInterpolation::Step, dir.path()).unwrap();
        for (k, &t) in times.iter().enumerate() {
            w.push(&format!("frame {k}"), t, &frame(k)).unwrap();
        }
        assert_eq!(w.frames(), 5);
        let path = dir.path().join("a.glb");
        let mut batch = OutputBatch::new();
        let size = w.finish(&mut batch, &path).unwrap();
        assert!(!path.exists(), "nothing before the commit");
        batch.commit().unwrap();
        let glb = std::fs::read(&path).unwrap();
        assert_eq!(glb.len() as u64, size);
        // Only the GLB and nothing else is left in the folder (the scratch file is gone).
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);

        // The gltf crate parses and validates the whole document (accessor, view and
        // animation references, target paths, sampler shapes).
        let g = ::gltf::Gltf::from_slice(&glb).unwrap();
        assert_eq!(g.animations().count(), 1);
        let prim = g.meshes().next().unwrap().primitives().next().unwrap();
        assert_eq!(prim.morph_targets().count(), 5);
        // The project's reader sees the rest mesh.
        let read = crate::io::read_from_bytes(&glb, crate::io::Format::Glb).unwrap();
        let rest32: Vec<[f64; 3]> = rest()
            .positions
            .iter()
            .map(|p| p.map(|x| x as f32 as f64))
            .collect();
        assert_eq!(read.mesh.positions, rest32);
        assert_eq!(read.mesh.triangles, rest().triangles);

        let (doc, bin) = chunks(&glb);
        assert_eq!(
            doc["buffers"][0]["byteLength"].as_u64().unwrap() as usize,
            bin.len()
        );
        let prim = &doc["meshes"][0]["primitives"][0];
        let rest_acc = prim["attributes"]["POSITION"].as_u64().unwrap() as usize;
        check_bounds(&doc, &bin, rest_acc);
        let rest_pos = accessor(&doc, &bin, rest_acc);
        let targets = prim["targets"].as_array().unwrap();
        assert_eq!(doc["meshes"][0]["extras"]["targetNames"][4], "frame 4");
        for (k, t) in targets.iter().enumerate() {
            let a = t["POSITION"].as_u64().unwrap() as usize;
            check_bounds(&doc, &bin, a);
            let d = accessor(&doc, &bin, a);
            let want = frame(k);
            for (v, p) in want.iter().enumerate() {
                for c in 0..3 {
                    let got = rest_pos[3 * v + c] + d[3 * v + c];
                    // One f32 rounding of the difference, one of the sum.
                    assert!(
                        (got - p[c]).abs() <= 2.0 * f32::EPSILON * p[c].abs().max(1.0),
                        "frame {k} vertex {v}"
                    );
                }
            }
        }
        let sampler = &doc["animations"][0]["samplers"][0];
        assert_eq!(sampler["interpolation"], "STEP");
        assert_eq!(
            doc["animations"][0]["channels"][0]["target"]["path"],
            "weights"
        );
        let input = accessor(&doc, &bin, sampler["input"].as_u64().unwrap() as usize);
        assert_eq!(input, times);
        assert!(input.windows(2).all(|w| w[0] < w[1]));
        let output = accessor(&doc, &bin, sampler["output"].as_u64().unwrap() as usize);
        assert_eq!(output.len(), 25);
        for (key, row) in output.chunks(5).enumerate() {
            for (target, &x) in row.iter().enumerate() {
                assert_eq!(x, if key == target { 1.0 } else { 0.0 });
            }
        }
    }

    #[test]
    fn bad_frames_are_refused_and_an_empty_animation_is_not_written() {
        let dir = tempfile::tempdir().unwrap();
        let mut w =
            MorphAnimationWriter::new(&rest(), MorphInterpolation::Linear, dir.path()).unwrap();
        let bad =
            |r: Result<(), MeshError>| matches!(r, Err(MeshError::MorphTarget { target: 0, .. }));
        assert!(bad(w.push("x", 0.0, &frame(0)[..3])));
        let mut nan = frame(0);
        nan[2][1] = f32::NAN;
        assert!(bad(w.push("x", 0.0, &nan)));
        assert!(bad(w.push("x", f32::NAN, &frame(0))));
        w.push("a", 1.0, &frame(0)).unwrap();
        assert!(matches!(
            w.push("b", 1.0, &frame(1)),
            Err(MeshError::MorphTarget { target: 1, .. })
        ));
        assert_eq!(w.frames(), 1);
        let w = MorphAnimationWriter::new(&rest(), MorphInterpolation::Linear, dir.path()).unwrap();
        let mut batch = OutputBatch::new();
        assert!(matches!(
            w.finish(&mut batch, &dir.path().join("e.glb")),
            Err(MeshError::NoMorphTargets)
        ));
        drop(batch);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
