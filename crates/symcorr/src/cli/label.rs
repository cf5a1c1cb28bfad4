//! `symcorr label MESH --joints J --out labels.json [--frame N] [--ply coloured.ply]
//! [--glb coloured.glb] [--weights]`: attach the skeleton (symcorr-attach) and write
//! `symcorr.labels/1` plus optional segment-coloured meshes (fixed 17-colour palette).

use super::CliError;
use std::path::PathBuf;
use symcorr::io::{read_mesh, read_skeleton_as};
use symcorr::output::labels_file;
use symcorr_attach::{palette, AttachOptions};
use symcorr_mesh::io::{check_output, OutputBatch};

/// Arguments of `symcorr label`.
#[derive(clap::Args)]
#[command(
    after_help = "Example:\n  symcorr label body.ply --joints body.json --out labels.json --ply labels.ply"
)]
pub struct LabelArgs {
    /// Mesh file (OBJ, OFF, PLY, glTF/GLB).
    pub mesh: PathBuf,
    /// Joints (symcorr.joints/1 JSON, Kinect SDK text, NTU .skeleton; detected from content).
    #[arg(long)]
    pub joints: PathBuf,
    /// Output `symcorr.labels/1` JSON.
    #[arg(long)]
    pub out: PathBuf,
    /// Frame of the joint file (0-based; default the first).
    #[arg(long)]
    pub frame: Option<usize>,
    /// Force the joint file's format instead of detecting it from content:
    /// json, kinect-text, ntu or k4abt.
    #[arg(long, value_name = "FORMAT")]
    pub joints_format: Option<String>,
    /// Also write the mesh coloured by segment as PLY (the extension decides: a path ending
    /// in .glb, .gltf, .obj or .off is written in that format).
    #[arg(long)]
    pub ply: Option<PathBuf>,
    /// Also write the mesh coloured by segment as binary glTF (the extension decides, as for
    /// --ply).
    #[arg(long)]
    pub glb: Option<PathBuf>,
    /// Include the sparse bone-heat weights (`[bone, weight]` pairs per vertex) in the JSON.
    #[arg(long)]
    pub weights: bool,
    /// Refuse (exit 1) instead of fixing a skeleton whose left and right are swapped.
    #[arg(long)]
    pub refuse_mirrored: bool,
    /// Use a skeleton that fails a fit check instead of refusing it (the file's `fit` block
    /// then says `accepted_poor_fit`).
    #[arg(long)]
    pub accept_poor_fit: bool,
    /// Where neighbouring segments end: `joint-planes` (the plane through the shared joint
    /// bisecting the two bones, what `match` uses) or `makehuman` (planes learned from the
    /// MakeHuman rig's skinning: small clavicles, buttocks in the hips, armpits in the torso).
    #[arg(long, value_enum, default_value = "joint-planes")]
    pub boundaries: Boundaries,
}

/// `symcorr label --boundaries`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Boundaries {
    /// Joint planes (symcorr-attach's default).
    JointPlanes,
    /// `symcorr_attach::BoundaryConvention::makehuman()`.
    Makehuman,
}

/// Runs `symcorr label`.
pub fn run(a: LabelArgs, max_input_bytes: u64) -> Result<(), CliError> {
    // Every output is checked before any work (not a directory, not an input, its directory
    // exists).
    for out in [Some(&a.out), a.ply.as_ref(), a.glb.as_ref()]
        .into_iter()
        .flatten()
    {
        check_output(out, &[&a.mesh, &a.joints]).map_err(|e| CliError(e.to_string()))?;
    }
    let mesh = read_mesh(&a.mesh, max_input_bytes).map_err(|e| CliError(e.to_string()))?;
    let format = super::joints_format(a.joints_format.as_deref())?;
    let skeleton =
        read_skeleton_as(&a.joints, a.frame, format).map_err(|e| CliError(e.to_string()))?;
    let options = AttachOptions {
        poor_fit: if a.accept_poor_fit {
            symcorr_attach::PoorFitPolicy::Accept
        } else {
            symcorr_attach::PoorFitPolicy::Refuse
        },
        mirror: if a.refuse_mirrored {
            symcorr_attach::MirrorPolicy::Refuse
        } else {
            symcorr_attach::MirrorPolicy::Fix
        },
        convention: (a.boundaries == Boundaries::Makehuman)
            .then(symcorr_attach::BoundaryConvention::makehuman),
        ..AttachOptions::default()
    };
    // Triangles turned to a consistent orientation first (vertex ids stay the input's).
    let labelled = symcorr::label::label_mesh(&mesh, &skeleton, &options)
        .map_err(|e| super::match_cmd::blame(&a.mesh, &a.joints, e))?;
    let turned = labelled.turned_triangles;
    let (mesh, att) = (labelled.mesh, labelled.attachment);
    let boundaries = match a.boundaries {
        Boundaries::JointPlanes => "joint-planes",
        Boundaries::Makehuman => "makehuman",
    };
    let doc = labels_file(
        &a.mesh.display().to_string(),
        mesh.num_vertices(),
        &att,
        boundaries,
        a.weights,
    );
    // All outputs are staged, then committed together: an error leaves none of them.
    let cli = |e: symcorr_mesh::MeshError| CliError(e.to_string());
    let mut batch = OutputBatch::new();
    batch.add(&a.out, doc.to_json().as_bytes()).map_err(cli)?;
    let d = &att.diagnostics;
    let al = &d.alignment;
    let colours: Vec<[u8; 3]> = att.labels.iter().map(|&s| palette::colour(s)).collect();
    for path in [&a.ply, &a.glb].into_iter().flatten() {
        batch.add_mesh(path, &mesh, Some(&colours)).map_err(cli)?;
    }
    batch.commit().map_err(cli)?;
    eprintln!(
        "labelled {} vertices ({} triangles turned to a consistent orientation, {} joints moved, alignment scale {}, mirrored fixed: {}{}, fit score {:.2}{}, {} component(s), {} fallback, {} unreached vertices)",
        mesh.num_vertices(),
        turned,
        d.joint_moves.len(),
        al.scale,
        d.mirror.swapped,
        d.mirror
            .swapped_limbs
            .map_or(String::new(), |p| format!(", {}' sides swapped back", p.name())),
        d.fit.score,
        if d.fit.accepted_poor_fit {
            " (poor fit accepted)"
        } else {
            ""
        },
        d.components.len(),
        d.components.iter().filter(|c| c.fallback).count(),
        d.fit.unreached.len()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    /// [`run`] with the default input limit.
    fn run_default(a: LabelArgs) -> Result<(), CliError> {
        run(a, symcorr_mesh::io::DEFAULT_MAX_INPUT_BYTES)
    }

    use super::*;
    use serde_json::{json, Map, Value};
    use symcorr_skeleton::Joint;

    #[test]
    fn label_writes_json_and_coloured_meshes() {
        let dir = tempfile::tempdir().unwrap();
        let sk = symcorr_attach::testbody::t_pose(1.0);
        let (mesh, _) = symcorr_attach::testbody::capsule_body(&sk, 0.04);
        let mesh_path = dir.path().join("body.ply");
        symcorr_mesh::io::write(&mesh_path, &mesh, None).unwrap();
        let mut joints = Map::new();
        for j in Joint::ALL {
            joints.insert(j.name().into(), json!(sk.position(j)));
        }
        let jdoc = json!({"format": "symcorr.joints/1", "skeleton": "kinect_v1", "units": "m",
                          "frames": [{"time_s": 0.0, "joints": joints}]});
        let joints_path = dir.path().join("body.json");
        std::fs::write(&joints_path, jdoc.to_string()).unwrap();
        let out = dir.path().join("labels.json");
        let ply = dir.path().join("labels.ply");
        let glb = dir.path().join("labels.glb");
        run_default(LabelArgs {
            mesh: mesh_path.clone(),
            joints: joints_path.clone(),
            out: out.clone(),
            frame: None,
            joints_format: Some("json".into()),
            ply: Some(ply.clone()),
            glb: Some(glb.clone()),
            weights: true,
            refuse_mirrored: false,
            accept_poor_fit: false,
            boundaries: Boundaries::JointPlanes,
        })
        .unwrap();
        let v: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        assert_eq!(v["format"], "symcorr.labels/1");
        assert_eq!(v["labels"].as_array().unwrap().len(), mesh.num_vertices());
        assert_eq!(v["segments"].as_array().unwrap().len(), 17);
        assert_eq!(v["weights"].as_array().unwrap().len(), mesh.num_vertices());
        assert!(v["joints"]["elbow_left"].is_array());
        let back = symcorr_mesh::io::read(&ply).unwrap();
        let colours = back.colors.unwrap();
        let labels = v["labels"].as_array().unwrap();
        for (c, l) in colours.iter().zip(labels) {
            assert_eq!(*c, palette::PALETTE[l.as_u64().unwrap() as usize]);
        }
        assert!(symcorr_mesh::io::read(&glb).is_ok());
        // --boundaries makehuman: the same file layout, boundaries moved.
        let rig = dir.path().join("rig.json");
        run_default(LabelArgs {
            mesh: mesh_path.clone(),
            joints: joints_path.clone(),
            out: rig.clone(),
            frame: None,
            joints_format: None,
            ply: None,
            glb: None,
            weights: false,
            refuse_mirrored: false,
            accept_poor_fit: false,
            boundaries: Boundaries::Makehuman,
        })
        .unwrap();
        let r: Value = serde_json::from_str(&std::fs::read_to_string(&rig).unwrap()).unwrap();
        assert_eq!(r["diagnostics"]["boundaries"], "makehuman");
        assert!(r["diagnostics"]["convention_changes"].as_u64().unwrap() > 0);
        assert_eq!(v["diagnostics"]["boundaries"], "joint-planes");
        assert!(v["diagnostics"]["convention_changes"].is_null());
        let moved = r["labels"]
            .as_array()
            .unwrap()
            .iter()
            .zip(labels)
            .filter(|(a, b)| a != b)
            .count();
        assert!(moved > 0 && moved * 4 < labels.len(), "{moved}");
        // A frame the file does not have is a user error, and nothing is written.
        let out2 = dir.path().join("none.json");
        let e = run_default(LabelArgs {
            mesh: mesh_path.clone(),
            joints: joints_path.clone(),
            out: out2.clone(),
            frame: Some(3),
            joints_format: None,
            ply: None,
            glb: None,
            weights: false,
            refuse_mirrored: false,
            accept_poor_fit: false,
            boundaries: Boundaries::JointPlanes,
        })
        .err()
        .unwrap();
        assert!(e.to_string().contains("frame 3"), "{e}");
        assert!(!out2.exists());
        // --joints-format forces the parser: a JSON file read as a Kinect SDK text dump, or an
        // unknown format name, is a user error, and nothing is written.
        for format in ["kinect-text", "bvh"] {
            let e = run_default(LabelArgs {
                mesh: mesh_path.clone(),
                joints: joints_path.clone(),
                out: out2.clone(),
                frame: None,
                joints_format: Some(format.into()),
                ply: None,
                glb: None,
                weights: false,
                refuse_mirrored: false,
                accept_poor_fit: false,
                boundaries: Boundaries::JointPlanes,
            })
            .err()
            .unwrap();
            assert!(!e.to_string().contains('\n'), "{e}");
            assert!(!out2.exists(), "{format}");
        }
    }

    #[test]
    fn labels_files_match_the_golden_files_byte_for_byte() {
        let dir = tempfile::tempdir().unwrap();
        let sk = symcorr_attach::testbody::t_pose(1.0);
        let (mesh, _) = symcorr_attach::testbody::capsule_body(&sk, 0.08);
        let mesh_path = dir.path().join("body.ply");
        symcorr_mesh::io::write(&mesh_path, &mesh, None).unwrap();
        let mut joints = Map::new();
        for j in Joint::ALL {
            joints.insert(j.name().into(), json!(sk.position(j)));
        }
        let jdoc = json!({"format": "symcorr.joints/1", "skeleton": "kinect_v1", "units": "m",
                          "frames": [{"time_s": 0.0, "joints": joints}]});
        let joints_path = dir.path().join("body.json");
        std::fs::write(&joints_path, jdoc.to_string()).unwrap();
        let golden =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/formats");
        for (name, weights, boundaries) in [
            ("labels_weights", true, Boundaries::JointPlanes),
            ("labels_makehuman", false, Boundaries::Makehuman),
        ] {
            let out = dir.path().join("labels.json");
            run_default(LabelArgs {
                mesh: mesh_path.clone(),
                joints: joints_path.clone(),
                out: out.clone(),
                frame: None,
                joints_format: None,
                ply: None,
                glb: None,
                weights,
                refuse_mirrored: false,
                accept_poor_fit: false,
                boundaries,
            })
            .unwrap();
            let text = std::fs::read_to_string(&out).unwrap();
            let quoted = serde_json::to_string(&mesh_path.display().to_string()).unwrap();
            let text = text.replace(&quoted, "\"body.ply\"");
            // Written by the json!-built writer this one replaced, from the same inputs.
            let expected = std::fs::read_to_string(golden.join(format!("{name}.json"))).unwrap();
            assert_eq!(text, expected, "{name}");
            let back = symcorr::formats::LabelsFile::read(&out).unwrap();
            assert_eq!(back.weights.is_some(), weights);
            assert_eq!(back.labels.len(), mesh.num_vertices());
        }
    }
}
