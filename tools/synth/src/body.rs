//! The body model: shape blending, the rig placed on the shaped mesh, and linear blend skinning.

use std::collections::{BTreeMap, HashMap};

use nalgebra::{Point3, Vector3};
use symcorr_mesh::TriMesh;

use crate::assets::{Assets, JointStrategy, BODY_VERTICES};
use crate::error::{Result, SynthError};
use crate::math::{blender_to_obj, euler_xyz, obj_to_blender, vec_roll_to_mat3, Rigid, V3};

/// MakeHuman units are decimetres; everything symcorr-synth writes is in metres.
pub const DM_TO_M: f64 = 0.1;

/// A body shape: weights in [0, 1] for macro targets, by short name (e.g.
/// `male-young-maxmuscle-maxweight`, the target file name without `universal-`/`.target.gz`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Shape {
    /// Target name → weight.
    pub weights: BTreeMap<String, f64>,
}

impl Shape {
    /// Parses `name=w,name=w` (an empty string is the base shape).
    pub fn parse(s: &str) -> Result<Shape> {
        let mut weights = BTreeMap::new();
        for item in s.split(',').map(str::trim).filter(|x| !x.is_empty()) {
            let (name, w) = item.split_once('=').ok_or_else(|| {
                SynthError::Invalid(format!("shape item `{item}`: expected name=weight"))
            })?;
            let w: f64 = w
                .trim()
                .parse()
                .ok()
                .filter(|w: &f64| (0.0..=1.0).contains(w))
                .ok_or_else(|| {
                    SynthError::Invalid(format!("shape item `{item}`: weight must be in [0, 1]"))
                })?;
            weights.insert(name.trim().to_string(), w);
        }
        Ok(Shape { weights })
    }
}

/// A pose: Blender `XYZ` Euler rotations (radians) per rig bone, in the bone's rest frame
/// (local +Y along the bone, X/Z set by the bone's roll), exactly as Blender's pose-bone
/// `rotation_euler`. Missing bones stay at rest.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Pose {
    /// Bone name → Euler angles.
    pub rotations: BTreeMap<String, V3>,
}

/// One bone of the rig placed on a shaped body (Blender frame, metres).
#[derive(Debug, Clone)]
pub struct RigBone {
    /// Bone name.
    pub name: String,
    /// Parent index (parents come before children).
    pub parent: Option<usize>,
    /// Head position (Blender frame, metres).
    pub head: V3,
    /// Tail position (Blender frame, metres).
    pub tail: V3,
    /// Rest transform: bone-local frame → armature frame (rotation from head/tail/roll,
    /// translation = head).
    pub rest: Rigid,
}

/// The shared, shape-independent part of the model: rig topology and skin weights.
#[derive(Debug, Clone)]
pub struct Model {
    /// The loaded assets.
    pub assets: Assets,
    /// Bone order: indices into `assets.bones`, parents before children.
    order: Vec<usize>,
    /// Per body vertex: `(bone index in rig order, normalised weight)`.
    weights: Vec<Vec<(usize, f64)>>,
}

/// A shaped body in its rest pose with its rig.
#[derive(Debug, Clone)]
pub struct Body<'a> {
    /// The model it came from.
    pub model: &'a Model,
    /// Rest-pose body mesh, metres, OBJ frame (x = subject's left, y up, z = front).
    pub rest: TriMesh,
    /// Bones in rig order (parents first).
    pub bones: Vec<RigBone>,
    /// Bone name → index.
    pub bone_index: HashMap<String, usize>,
    /// Rest positions in the Blender frame (metres), for skinning.
    rest_blender: Vec<V3>,
}

/// A posed body: mesh and per-bone skinning transforms (Blender frame).
#[derive(Debug, Clone)]
pub struct Posed {
    /// The posed mesh (metres, OBJ frame, same vertex order as the rest mesh).
    pub mesh: TriMesh,
    /// Per bone: rest armature space → posed armature space (Blender frame).
    pub skin: Vec<Rigid>,
}

impl Model {
    /// Prepares rig order and normalised skin weights.
    ///
    /// ```no_run
    /// use symcorr_synth::{Assets, Model, Shape, Pose};
    /// let model = Model::new(Assets::load(&Assets::default_dir())?)?;
    /// let body = model.body(&Shape::default())?;
    /// let posed = body.pose(&Pose::default())?;
    /// assert_eq!(posed.mesh.num_vertices(), 13_380);
    /// # Ok::<(), symcorr_synth::SynthError>(())
    /// ```
    pub fn new(assets: Assets) -> Result<Model> {
        let by_name: HashMap<&str, usize> = assets
            .bones
            .iter()
            .enumerate()
            .map(|(i, b)| (b.name.as_str(), i))
            .collect();
        // Topological order: repeatedly take bones whose parent is placed; ties in file order.
        let mut placed = vec![false; assets.bones.len()];
        let mut order = Vec::new();
        while order.len() < assets.bones.len() {
            let before = order.len();
            for (i, b) in assets.bones.iter().enumerate() {
                if placed[i] {
                    continue;
                }
                let ready = match &b.parent {
                    None => true,
                    Some(p) => match by_name.get(p.as_str()) {
                        Some(&pi) => placed[pi],
                        None => {
                            return Err(SynthError::Invalid(format!(
                                "rig: bone {} has unknown parent {p}",
                                b.name
                            )))
                        }
                    },
                };
                if ready {
                    placed[i] = true;
                    order.push(i);
                }
            }
            if order.len() == before {
                return Err(SynthError::Invalid("rig: parent cycle".into()));
            }
        }
        let rank: HashMap<&str, usize> = order
            .iter()
            .enumerate()
            .map(|(r, &i)| (assets.bones[i].name.as_str(), r))
            .collect();
        let mut weights: Vec<Vec<(usize, f64)>> = vec![Vec::new(); BODY_VERTICES];
        // Iterate bones in rig order so that the weight lists are in a fixed order.
        for &bi in &order {
            let name = &assets.bones[bi].name;
            for &(v, w) in assets.weights.get(name).map(Vec::as_slice).unwrap_or(&[]) {
                if (v as usize) < BODY_VERTICES && w > 0.0 {
                    weights[v as usize].push((rank[name.as_str()], w));
                }
            }
        }
        for (v, ws) in weights.iter_mut().enumerate() {
            let total: f64 = ws.iter().map(|x| x.1).sum();
            if total <= 0.0 {
                return Err(SynthError::Invalid(format!(
                    "weights: body vertex {v} has no skin weight"
                )));
            }
            for x in ws.iter_mut() {
                x.1 /= total;
            }
        }
        Ok(Model {
            assets,
            order,
            weights,
        })
    }

    /// Per body vertex, `(bone index in rig order, weight)`, weights summing to 1.
    pub fn weights(&self) -> &[Vec<(usize, f64)>] {
        &self.weights
    }

    /// Names of the rig bones in rig order.
    pub fn bone_names(&self) -> Vec<&str> {
        self.order
            .iter()
            .map(|&i| self.assets.bones[i].name.as_str())
            .collect()
    }

    /// The body with `shape` applied, in its rest pose, with the rig fitted to it.
    pub fn body(&self, shape: &Shape) -> Result<Body<'_>> {
        let mut all = self.assets.base_positions.clone();
        for (name, &w) in &shape.weights {
            let target = self.assets.targets.get(name).ok_or_else(|| {
                SynthError::Invalid(format!(
                    "unknown shape target `{name}` (known: {})",
                    self.assets
                        .targets
                        .keys()
                        .cloned()
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            })?;
            for &(v, d) in target {
                let p = &mut all[v as usize];
                for k in 0..3 {
                    p[k] += w * d[k];
                }
            }
        }
        let joint = |s: &JointStrategy| -> V3 {
            let idx: &[u32] = match s {
                // Presence checked in Assets::load.
                JointStrategy::Cube(c) => self
                    .assets
                    .vertex_groups
                    .get(c)
                    .map(Vec::as_slice)
                    .unwrap_or(&[]),
                JointStrategy::Mean(v) => v,
            };
            let m = idx
                .iter()
                .fold(Vector3::zeros(), |m, &i| m + Vector3::from(all[i as usize]));
            obj_to_blender((m * (DM_TO_M / idx.len().max(1) as f64)).into())
        };
        let mut bones = Vec::with_capacity(self.order.len());
        let mut bone_index = HashMap::new();
        for &bi in &self.order {
            let spec = &self.assets.bones[bi];
            let head = joint(&spec.head);
            let tail = joint(&spec.tail);
            let r = vec_roll_to_mat3(Point3::from(tail) - Point3::from(head), spec.roll);
            let parent = spec
                .parent
                .as_ref()
                .and_then(|p| bone_index.get(p).copied());
            bone_index.insert(spec.name.clone(), bones.len());
            bones.push(RigBone {
                name: spec.name.clone(),
                parent,
                head,
                tail,
                rest: Rigid {
                    r,
                    t: Vector3::from(head),
                },
            });
        }
        let positions: Vec<V3> = all[..BODY_VERTICES]
            .iter()
            .map(|&p| (Vector3::from(p) * DM_TO_M).into())
            .collect();
        let rest_blender = positions.iter().map(|&p| obj_to_blender(p)).collect();
        let rest = TriMesh::new(positions, self.assets.body_triangles.clone())?;
        Ok(Body {
            model: self,
            rest,
            bones,
            bone_index,
            rest_blender,
        })
    }
}

impl Body<'_> {
    /// Per-bone skinning transforms for `pose`: forward kinematics in rig order (parent before
    /// child), each bone rotated about its head in its own rest frame.
    pub fn skin_transforms(&self, pose: &Pose) -> Result<Vec<Rigid>> {
        for name in pose.rotations.keys() {
            if !self.bone_index.contains_key(name) {
                return Err(SynthError::Invalid(format!(
                    "pose names unknown bone `{name}`"
                )));
            }
        }
        let mut global: Vec<Rigid> = Vec::with_capacity(self.bones.len());
        for b in &self.bones {
            let local = Rigid {
                r: euler_xyz(pose.rotations.get(&b.name).copied().unwrap_or([0.0; 3])),
                t: Vector3::zeros(),
            };
            let g = match b.parent {
                // posed(b) = posed(parent) · rest(parent)⁻¹ · rest(b) · local
                Some(p) => global[p]
                    .compose(&self.bones[p].rest.inverse())
                    .compose(&b.rest)
                    .compose(&local),
                None => b.rest.compose(&local),
            };
            global.push(g);
        }
        Ok(global
            .iter()
            .zip(&self.bones)
            .map(|(g, b)| g.compose(&b.rest.inverse()))
            .collect())
    }

    /// Poses the body by linear blend skinning.
    pub fn pose(&self, pose: &Pose) -> Result<Posed> {
        let skin = self.skin_transforms(pose)?;
        let positions = self
            .rest_blender
            .iter()
            .zip(self.model.weights())
            .map(|(&p, ws)| {
                let mut q = Vector3::zeros();
                for &(b, w) in ws {
                    q += Vector3::from(skin[b].apply(p)) * w;
                }
                blender_to_obj(q.into())
            })
            .collect();
        let mesh = TriMesh::new(positions, self.rest.triangles.clone())?;
        Ok(Posed { mesh, skin })
    }

    /// Bone index by name.
    pub fn bone(&self, name: &str) -> Result<usize> {
        self.bone_index
            .get(name)
            .copied()
            .ok_or_else(|| SynthError::Invalid(format!("rig has no bone `{name}`")))
    }

    /// A rest-pose point (Blender frame) carried rigidly by bone `b`, in the posed OBJ frame.
    pub fn carry(&self, skin: &[Rigid], b: usize, rest_point_blender: V3) -> V3 {
        blender_to_obj(skin[b].apply(rest_point_blender))
    }

    /// Posed head and tail of bone `b` (OBJ frame, metres).
    pub fn posed_bone(&self, skin: &[Rigid], b: usize) -> (V3, V3) {
        let bone = &self.bones[b];
        (
            self.carry(skin, b, bone.head),
            self.carry(skin, b, bone.tail),
        )
    }

    /// The bone's local axes (columns X, Y, Z) expressed in the OBJ frame — handy to see which
    /// Euler component bends a joint which way.
    pub fn rest_axes_obj(&self, b: usize) -> [V3; 3] {
        let r = &self.bones[b].rest.r;
        [0, 1, 2].map(|k| blender_to_obj(r.column(k).into_owned().into()))
    }
}
