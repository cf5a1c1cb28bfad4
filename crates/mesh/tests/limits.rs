//! Input limits: the size cap on every read (regular files, devices) and the confinement of
//! glTF external buffers to the glTF file's folder, with `byteLength` respected.

use std::path::Path;

use serde_json::json;
use symcorr_mesh::io::{self, Format, ReadOptions, DEFAULT_MAX_INPUT_BYTES};
use symcorr_mesh::MeshError;

const OFF: &str = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";

fn limited(max_input_bytes: u64) -> ReadOptions {
    ReadOptions {
        max_input_bytes,
        ..ReadOptions::default()
    }
}

#[test]
fn regular_file_over_the_limit_is_refused_with_a_hint() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tri.off");
    std::fs::write(&path, OFF).unwrap();
    let n = OFF.len() as u64;
    // Exactly at the limit reads; one byte less is refused.
    assert_eq!(
        io::read_with_options(&path, &limited(n))
            .unwrap()
            .mesh
            .num_triangles(),
        1
    );
    let e = io::read_with_options(&path, &limited(n - 1)).unwrap_err();
    assert!(
        matches!(&e, MeshError::InputTooLarge { file, limit } if *limit == n - 1 && file.ends_with("tri.off")),
        "{e:?}"
    );
    let msg = e.to_string();
    assert!(msg.contains("tri.off"), "{msg}");
    assert!(
        msg.contains(&format!("{} bytes input limit", n - 1)),
        "{msg}"
    );
    assert!(msg.contains("--max-input-size"), "{msg}");
    // The default limit reads it, and is named in whole units.
    assert_eq!(DEFAULT_MAX_INPUT_BYTES, 1 << 30);
    assert!(io::read(&path).is_ok());
    let e = MeshError::InputTooLarge {
        file: "big.ply".into(),
        limit: DEFAULT_MAX_INPUT_BYTES,
    };
    assert_eq!(
        e.to_string(),
        "big.ply: is larger than the 1 GiB input limit; pass --max-input-size to read it"
    );
    // The format may be given with the limit.
    let other = dir.path().join("tri.txt");
    std::fs::write(&other, OFF).unwrap();
    let opts = ReadOptions {
        format: Some(Format::Off),
        max_input_bytes: n,
    };
    assert!(io::read_with_options(&other, &opts).is_ok());
}

/// A character device has no length in its metadata: the read itself stops one byte past the
/// limit (a 4 KiB limit allocates a few KiB, not the 2 GB an unbounded read would).
#[cfg(unix)]
#[test]
fn endless_device_is_cut_at_the_limit() {
    let zero = Path::new("/dev/zero");
    if !zero.exists() {
        return;
    }
    let opts = ReadOptions {
        format: Some(Format::Ply),
        max_input_bytes: 4096,
    };
    let e = io::read_with_options(zero, &opts).unwrap_err();
    assert!(
        matches!(&e, MeshError::InputTooLarge { limit: 4096, .. }),
        "{e:?}"
    );
    assert!(e.to_string().contains("4 KiB input limit"), "{e}");
}

/// One triangle (36 bytes of f32 positions) in buffer 0, with the given uri and byteLength.
fn triangle_gltf(uri: &str, byte_length: usize) -> String {
    json!({
        "asset": {"version": "2.0"},
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"uri": uri, "byteLength": byte_length}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}]
    })
    .to_string()
}

fn triangle_bin() -> Vec<u8> {
    [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect()
}

/// Writes `scene/s.gltf` naming `uri` and returns its path.
fn gltf_in(root: &Path, uri: &str, byte_length: usize) -> std::path::PathBuf {
    let scene = root.join("scene");
    std::fs::create_dir_all(&scene).unwrap();
    let path = scene.join("s.gltf");
    std::fs::write(&path, triangle_gltf(uri, byte_length)).unwrap();
    path
}

/// The refusal message of an [`MeshError::ExternalBuffer`], after checking it names both the
/// glTF file and the uri.
fn refusal(e: MeshError, uri: &str) -> String {
    match &e {
        MeshError::ExternalBuffer {
            file,
            uri: u,
            message,
        } => {
            assert!(file.ends_with("s.gltf"), "{e}");
            assert_eq!(u, uri);
            assert!(e.to_string().contains(uri), "{e}");
            message.clone()
        }
        other => panic!("expected ExternalBuffer for {uri:?}, got {other:?}"),
    }
}

#[test]
fn external_buffers_inside_the_folder_are_read() {
    let root = tempfile::tempdir().unwrap();
    let scene = root.path().join("scene");
    std::fs::create_dir_all(scene.join("data")).unwrap();
    std::fs::write(scene.join("data/tri.bin"), triangle_bin()).unwrap();
    for uri in ["data/tri.bin", "./data/tri.bin", "data/../data/tri.bin"] {
        let path = gltf_in(root.path(), uri, 36);
        let m = io::read(&path).unwrap_or_else(|e| panic!("{uri}: {e}"));
        assert_eq!(m.mesh.num_triangles(), 1);
        assert_eq!(m.mesh.positions[1], [1.0, 0.0, 0.0]);
    }
    // A file longer than byteLength: only byteLength bytes belong to the buffer.
    let mut long = triangle_bin();
    long.extend_from_slice(&[0xff; 1000]);
    std::fs::write(scene.join("long.bin"), &long).unwrap();
    let path = gltf_in(root.path(), "long.bin", 36);
    assert_eq!(io::read(&path).unwrap().mesh.num_vertices(), 3);
    // A symlink that stays inside the folder is fine.
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("data/tri.bin", scene.join("alias.bin")).unwrap();
        let path = gltf_in(root.path(), "alias.bin", 36);
        assert!(io::read(&path).is_ok());
    }
}

#[test]
fn external_buffers_outside_the_folder_are_refused() {
    let root = tempfile::tempdir().unwrap();
    std::fs::write(root.path().join("x.bin"), triangle_bin()).unwrap();
    let outside = root.path().join("x.bin");

    for uri in ["../x.bin", "data/../../x.bin", "..%2Fx.bin"] {
        let path = gltf_in(root.path(), uri, 36);
        let msg = refusal(io::read(&path).unwrap_err(), uri);
        assert!(msg.contains("leads out"), "{uri}: {msg}");
    }
    let abs = outside.display().to_string();
    let path = gltf_in(root.path(), &abs, 36);
    let msg = refusal(io::read(&path).unwrap_err(), &abs);
    assert!(msg.contains("absolute"), "{msg}");
    let path = gltf_in(root.path(), "file:///etc/hostname", 36);
    refusal(io::read(&path).unwrap_err(), "file:///etc/hostname");
}

#[cfg(unix)]
#[test]
fn symlinks_out_and_devices_are_refused() {
    let root = tempfile::tempdir().unwrap();
    std::fs::write(root.path().join("x.bin"), triangle_bin()).unwrap();
    let path = gltf_in(root.path(), "link.bin", 36);
    let scene = path.parent().unwrap().to_path_buf();
    std::os::unix::fs::symlink(root.path().join("x.bin"), scene.join("link.bin")).unwrap();
    let msg = refusal(io::read(&path).unwrap_err(), "link.bin");
    assert!(msg.contains("leads out"), "{msg}");
    // A symlinked folder leading out, too.
    std::os::unix::fs::symlink(root.path(), scene.join("up")).unwrap();
    let path = gltf_in(root.path(), "up/x.bin", 36);
    let msg = refusal(io::read(&path).unwrap_err(), "up/x.bin");
    assert!(msg.contains("leads out"), "{msg}");
    // /dev/zero: absolute, or through a symlink, is outside the folder.
    let path = gltf_in(root.path(), "/dev/zero", 36);
    refusal(io::read(&path).unwrap_err(), "/dev/zero");
    if Path::new("/dev/zero").exists() {
        std::os::unix::fs::symlink("/dev/zero", scene.join("zero.bin")).unwrap();
        let path = gltf_in(root.path(), "zero.bin", 36);
        refusal(io::read(&path).unwrap_err(), "zero.bin");
    }
    // Not a regular file inside the folder: a directory, a FIFO (refused before opening,
    // which would wait for a writer).
    std::fs::create_dir(scene.join("dir.bin")).unwrap();
    let path = gltf_in(root.path(), "dir.bin", 36);
    let msg = refusal(io::read(&path).unwrap_err(), "dir.bin");
    assert!(msg.contains("not a regular file"), "{msg}");
    let made_fifo = std::process::Command::new("mkfifo")
        .arg(scene.join("fifo.bin"))
        .status()
        .is_ok_and(|s| s.success());
    if made_fifo {
        let path = gltf_in(root.path(), "fifo.bin", 36);
        let msg = refusal(io::read(&path).unwrap_err(), "fifo.bin");
        assert!(msg.contains("not a regular file"), "{msg}");
    }
}

#[test]
fn short_buffer_files_and_the_size_limit() {
    let root = tempfile::tempdir().unwrap();
    let path = gltf_in(root.path(), "tri.bin", 36);
    let scene = path.parent().unwrap().to_path_buf();
    // Shorter than byteLength.
    std::fs::write(scene.join("tri.bin"), &triangle_bin()[..20]).unwrap();
    let msg = refusal(io::read(&path).unwrap_err(), "tri.bin");
    assert!(
        msg.contains("20 bytes") && msg.contains("byteLength is 36"),
        "{msg}"
    );
    // The buffer counts against the input limit together with the .gltf itself.
    std::fs::write(scene.join("tri.bin"), triangle_bin()).unwrap();
    let json_len = std::fs::metadata(&path).unwrap().len();
    assert!(io::read_with_options(&path, &limited(json_len + 36)).is_ok());
    let e = io::read_with_options(&path, &limited(json_len + 35)).unwrap_err();
    match &e {
        MeshError::InputTooLarge { file, limit } => {
            assert_eq!(*limit, json_len + 35);
            assert!(file.contains("s.gltf") && file.contains("tri.bin"), "{e}");
        }
        other => panic!("expected InputTooLarge, got {other:?}"),
    }
    // A byteLength far beyond the file is refused as short, without reading or allocating it.
    let path = gltf_in(root.path(), "tri.bin", 1 << 40);
    let msg = refusal(io::read(&path).unwrap_err(), "tri.bin");
    assert!(msg.contains("byteLength"), "{msg}");
}
