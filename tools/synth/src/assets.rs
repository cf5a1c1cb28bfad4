//! Loading the CC0 MakeHuman / MPFB2 assets (`fixtures/mpfb2/`): base mesh, vertex groups, the
//! `game_engine` rig and its skin weights, shape targets, the mirror map and the poses.

use std::collections::{BTreeMap, HashMap};
use std::io::Read;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::error::{Result, SynthError};
use crate::math::V3;

/// Number of vertices of the base mesh's `body` group (vertices `0..BODY_VERTICES`).
pub const BODY_VERTICES: usize = 13_380;

/// Where a rig joint (bone head or tail) sits, as a function of the base-mesh vertices.
#[derive(Debug, Clone, PartialEq)]
pub enum JointStrategy {
    /// Centroid of a named vertex group (the MakeHuman "joint cubes").
    Cube(String),
    /// Mean of the listed vertices (`MEAN`, and `VERTEX` with one vertex).
    Mean(Vec<u32>),
}

/// One bone of the rig as stored in `rig.game_engine.json`.
#[derive(Debug, Clone)]
pub struct BoneSpec {
    /// Bone name, e.g. `upperarm_l`.
    pub name: String,
    /// Parent bone name (`None` for the root).
    pub parent: Option<String>,
    /// Head placement.
    pub head: JointStrategy,
    /// Tail placement.
    pub tail: JointStrategy,
    /// Blender roll (radians) about the head→tail axis.
    pub roll: f64,
}

/// All assets the generator needs, in MakeHuman units (decimetres, OBJ frame: x = subject's
/// left, y up, z = subject's front).
#[derive(Debug, Clone)]
pub struct Assets {
    /// The folder they came from.
    pub dir: PathBuf,
    /// All 19,158 base-mesh vertices (body, helpers and joint cubes), decimetres.
    pub base_positions: Vec<V3>,
    /// The `body` group's faces, fan-triangulated `(0,1,2),(0,2,3)`, in file order.
    pub body_triangles: Vec<[u32; 3]>,
    /// Named vertex groups.
    pub vertex_groups: HashMap<String, Vec<u32>>,
    /// Bones in file order.
    pub bones: Vec<BoneSpec>,
    /// Skin weights per bone name: `(vertex, weight)`.
    pub weights: HashMap<String, Vec<(u32, f64)>>,
    /// Shape targets by short name (file name without `universal-` and `.target.gz`):
    /// sparse `(vertex, offset in decimetres)`.
    pub targets: BTreeMap<String, Vec<(u32, V3)>>,
    /// Mirror partner of every base-mesh vertex (`hm08.mirror`).
    pub mirror: Vec<u32>,
    /// The T-pose: Blender Euler XYZ rotations per bone.
    pub t_pose: BTreeMap<String, V3>,
    /// The walk cycle's forward-kinematics curves (see [`crate::poses`]), if present.
    pub walk: Option<crate::poses::WalkCurves>,
}

fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| SynthError::io(path, e))
}

fn read_gz(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|e| SynthError::io(path, e))?;
    let mut s = String::new();
    flate2::read::GzDecoder::new(&bytes[..])
        .read_to_string(&mut s)
        .map_err(|e| SynthError::io(path, e))?;
    Ok(s)
}

fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T> {
    let text = read_text(path)?;
    serde_json::from_str(&text).map_err(|e| SynthError::json(path, e))
}

#[derive(Deserialize)]
struct RawJoint {
    strategy: String,
    cube_name: Option<String>,
    vertex_indices: Option<Vec<u32>>,
    vertex_index: Option<u32>,
}

#[derive(Deserialize)]
struct RawBone {
    parent: String,
    head: RawJoint,
    tail: RawJoint,
    roll: f64,
}

#[derive(Deserialize)]
struct RawWeights {
    weights: BTreeMap<String, Vec<(u32, f64)>>,
}

#[derive(Deserialize)]
struct RawPose {
    bone_rotations: BTreeMap<String, V3>,
}

fn strategy(path: &Path, bone: &str, j: RawJoint) -> Result<JointStrategy> {
    match j.strategy.as_str() {
        "CUBE" => j
            .cube_name
            .map(JointStrategy::Cube)
            .ok_or_else(|| SynthError::json(path, format!("bone {bone}: CUBE without cube_name"))),
        "MEAN" | "VERTEX" => {
            let v = j
                .vertex_indices
                .or(j.vertex_index.map(|v| vec![v]))
                .filter(|v| !v.is_empty())
                .ok_or_else(|| {
                    SynthError::json(
                        path,
                        format!("bone {bone}: {} without vertices", j.strategy),
                    )
                })?;
            Ok(JointStrategy::Mean(v))
        }
        s => Err(SynthError::json(
            path,
            format!("bone {bone}: unknown strategy {s}"),
        )),
    }
}

/// Reads `base.obj`: every vertex, and the faces of group `body` fan-triangulated.
fn read_obj(path: &Path) -> Result<(Vec<V3>, Vec<[u32; 3]>)> {
    let text = read_text(path)?;
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut in_body = false;
    for (i, line) in text.lines().enumerate() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let mut p = [0.0; 3];
                for c in &mut p {
                    *c = it
                        .next()
                        .and_then(|s| s.parse().ok())
                        .filter(|x: &f64| x.is_finite())
                        .ok_or_else(|| SynthError::parse(path, i + 1, "expected 3 coordinates"))?;
                }
                positions.push(p);
            }
            Some("g") => in_body = it.next() == Some("body"),
            Some("f") if in_body => {
                let idx: Vec<u32> = it
                    .map(|t| {
                        t.split('/')
                            .next()
                            .and_then(|s| s.parse::<u32>().ok())
                            .filter(|&v| v >= 1)
                            .map(|v| v - 1)
                            .ok_or_else(|| SynthError::parse(path, i + 1, "bad face index"))
                    })
                    .collect::<Result<_>>()?;
                if idx.len() < 3 {
                    return Err(SynthError::parse(path, i + 1, "face with < 3 vertices"));
                }
                for k in 1..idx.len() - 1 {
                    triangles.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
            _ => {}
        }
    }
    if positions.len() < BODY_VERTICES {
        return Err(SynthError::parse(
            path,
            0,
            format!("{} vertices, expected ≥ {BODY_VERTICES}", positions.len()),
        ));
    }
    if let Some(t) = triangles
        .iter()
        .position(|t| t.iter().any(|&v| v as usize >= BODY_VERTICES))
    {
        return Err(SynthError::parse(
            path,
            0,
            format!("body triangle {t} uses a vertex outside 0..{BODY_VERTICES}"),
        ));
    }
    Ok((positions, triangles))
}

fn read_target(path: &Path, n: usize) -> Result<Vec<(u32, V3)>> {
    let text = read_gz(path)?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let f: Vec<&str> = line.split_whitespace().collect();
        let parsed = (f.len() == 4)
            .then(|| {
                let v = f[0].parse::<u32>().ok()?;
                let d = [f[1].parse().ok()?, f[2].parse().ok()?, f[3].parse().ok()?];
                Some((v, d))
            })
            .flatten()
            .filter(|(v, d): &(u32, V3)| (*v as usize) < n && d.iter().all(|x| x.is_finite()));
        out.push(parsed.ok_or_else(|| {
            SynthError::parse(
                path,
                i + 1,
                "expected `vertex dx dy dz` with vertex in range",
            )
        })?);
    }
    Ok(out)
}

fn read_mirror(path: &Path, n: usize) -> Result<Vec<u32>> {
    let text = read_text(path)?;
    let mut mirror = vec![u32::MAX; n];
    for (i, line) in text.lines().enumerate() {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.is_empty() {
            continue;
        }
        let pair = (f.len() >= 2)
            .then(|| Some((f[0].parse::<usize>().ok()?, f[1].parse::<u32>().ok()?)))
            .flatten()
            .filter(|(a, b)| *a < n && (*b as usize) < n);
        let (a, b) = pair.ok_or_else(|| {
            SynthError::parse(path, i + 1, "expected `vertex mirror side` in range")
        })?;
        mirror[a] = b;
    }
    if let Some(v) = mirror.iter().position(|&m| m == u32::MAX) {
        return Err(SynthError::parse(
            path,
            0,
            format!("vertex {v} has no mirror entry"),
        ));
    }
    Ok(mirror)
}

impl Assets {
    /// The assets committed with the project (`fixtures/mpfb2/`), found from this crate's
    /// source folder, so the tool works on a fresh clone.
    pub fn default_dir() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/mpfb2")
    }

    /// Loads everything from `dir` (the layout of MPFB2's `data/` folder).
    pub fn load(dir: &Path) -> Result<Assets> {
        let (base_positions, body_triangles) = read_obj(&dir.join("3dobjs/base.obj"))?;
        let n = base_positions.len();

        let groups_path = dir.join("mesh_metadata/basemesh_vertex_groups.json");
        let raw_groups: HashMap<String, Vec<(u32, u32)>> = read_json(&groups_path)?;
        let mut vertex_groups = HashMap::new();
        for (name, ranges) in raw_groups {
            let mut v = Vec::new();
            for (a, b) in ranges {
                if a > b || b as usize >= n {
                    return Err(SynthError::json(
                        &groups_path,
                        format!("group {name}: bad range [{a}, {b}]"),
                    ));
                }
                v.extend(a..=b);
            }
            vertex_groups.insert(name, v);
        }

        let rig_path = dir.join("rigs/rig.game_engine.json");
        let raw_rig: BTreeMap<String, RawBone> = read_json(&rig_path)?;
        let mut bones = Vec::new();
        for (name, b) in raw_rig {
            let head = strategy(&rig_path, &name, b.head)?;
            let tail = strategy(&rig_path, &name, b.tail)?;
            for s in [&head, &tail] {
                let ok = match s {
                    JointStrategy::Cube(c) => vertex_groups.get(c).is_some_and(|g| !g.is_empty()),
                    JointStrategy::Mean(v) => v.iter().all(|&i| (i as usize) < n),
                };
                if !ok {
                    return Err(SynthError::json(
                        &rig_path,
                        format!("bone {name}: joint {s:?} names no base-mesh vertices"),
                    ));
                }
            }
            bones.push(BoneSpec {
                parent: (!b.parent.is_empty()).then_some(b.parent),
                name,
                head,
                tail,
                roll: b.roll,
            });
        }

        let weights_path = dir.join("rigs/weights.game_engine.json");
        let raw_weights: RawWeights = read_json(&weights_path)?;
        let weights: HashMap<String, Vec<(u32, f64)>> = raw_weights.weights.into_iter().collect();

        let mut targets = BTreeMap::new();
        let tdir = dir.join("targets");
        let mut entries: Vec<PathBuf> = std::fs::read_dir(&tdir)
            .map_err(|e| SynthError::io(&tdir, e))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.to_string_lossy().ends_with(".target.gz"))
            .collect();
        entries.sort();
        for p in entries {
            let file = p
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_default();
            let short = file
                .trim_end_matches(".target.gz")
                .trim_start_matches("universal-")
                .to_string();
            targets.insert(short, read_target(&p, n)?);
        }

        let mirror = read_mirror(&dir.join("mesh_metadata/hm08.mirror"), n)?;
        let t_pose: RawPose = read_json(&dir.join("poses/t-pose.json"))?;
        let walk_path = dir.join("walkcycles/crappy_experimental_female.json");
        let walk = if walk_path.exists() {
            Some(crate::poses::WalkCurves::load(&walk_path)?)
        } else {
            None
        };

        Ok(Assets {
            dir: dir.to_path_buf(),
            base_positions,
            body_triangles,
            vertex_groups,
            bones,
            weights,
            targets,
            mirror,
            t_pose: t_pose.bone_rotations,
            walk,
        })
    }

    /// The mirror map restricted to the body vertices. Errors if a body vertex's partner is not
    /// a body vertex.
    pub fn body_mirror(&self) -> Result<Vec<u32>> {
        let m = &self.mirror[..BODY_VERTICES];
        if let Some(v) = m.iter().position(|&x| x as usize >= BODY_VERTICES) {
            return Err(SynthError::Invalid(format!(
                "hm08.mirror maps body vertex {v} to non-body vertex {}",
                m[v]
            )));
        }
        Ok(m.to_vec())
    }
}
