//! Output files: checked before any work, written through symlinks, committed together.
//!
//! A command that writes several files (a correspondence and its coloured meshes, a scan and
//! its pixel map) stages every file in an [`OutputBatch`] as a temporary file next to its
//! destination; only when all of them were written does [`OutputBatch::commit`] rename them
//! into place. An error before that leaves no output and no temporary file (each temporary is
//! removed when the batch is dropped). A symlink is written through (its target is replaced,
//! not the link); an existing device or FIFO (`/dev/null`, `/dev/stdout`, a named pipe) is
//! written in place, never replaced by a regular file; a directory is refused.

use crate::MeshError;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Where an output path leads once symlinks are followed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Destination {
    /// A regular file (existing or new): replaced atomically by a rename.
    File(PathBuf),
    /// An existing device, FIFO or socket: written in place (it cannot be replaced).
    Special(PathBuf),
}

impl Destination {
    /// The resolved path.
    pub fn path(&self) -> &Path {
        match self {
            Destination::File(p) | Destination::Special(p) => p,
        }
    }
}

/// Symlinks followed at most (the kernel's own limit is 40).
const MAX_LINKS: usize = 40;

fn io_err(path: &Path, source: std::io::Error) -> MeshError {
    MeshError::Io {
        file: path.display().to_string(),
        source,
    }
}

/// Resolves an output path: follows symlinks (also a dangling one, to the file it names),
/// refuses a directory and tells a regular file from a device or FIFO.
///
/// Errors: [`MeshError::OutputIsDirectory`]; [`MeshError::Io`] for a symlink loop or a path
/// that cannot be inspected.
pub fn resolve_output(path: &Path) -> Result<Destination, MeshError> {
    let mut p = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        let meta = match std::fs::symlink_metadata(&p) {
            Ok(m) => m,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                return Ok(Destination::File(p));
            }
            Err(e) => return Err(io_err(path, e)),
        };
        let kind = meta.file_type();
        if kind.is_symlink() {
            let target = std::fs::read_link(&p).map_err(|e| io_err(path, e))?;
            p = match p.parent() {
                Some(dir) if target.is_relative() => dir.join(target),
                _ => target,
            };
        } else if kind.is_dir() {
            return Err(MeshError::OutputIsDirectory {
                file: path.display().to_string(),
            });
        } else if kind.is_file() {
            return Ok(Destination::File(p));
        } else {
            return Ok(Destination::Special(p));
        }
    }
    Err(io_err(
        path,
        std::io::Error::other("too many levels of symbolic links"),
    ))
}

/// Checks an output path before any work: it must not be a directory, its directory must exist,
/// and it must not lead (through symlinks or another spelling) to one of `inputs`.
///
/// Errors: [`MeshError::OutputIsDirectory`], [`MeshError::OutputIsInput`], [`MeshError::Io`]
/// (the directory does not exist).
///
/// ```
/// use symcorr_mesh::io::check_output;
/// let dir = tempfile::tempdir().unwrap();
/// let input = dir.path().join("body.off");
/// std::fs::write(&input, "OFF\n0 0 0\n").unwrap();
/// assert!(check_output(&dir.path().join("out.json"), &[&input]).is_ok());
/// assert!(check_output(&input, &[&input]).is_err()); // would destroy the input
/// assert!(check_output(dir.path(), &[&input]).is_err()); // a directory
/// ```
pub fn check_output(path: &Path, inputs: &[&Path]) -> Result<Destination, MeshError> {
    let dest = resolve_output(path)?;
    if let Destination::File(p) = &dest {
        let dir = match p.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        if !dir.is_dir() {
            return Err(io_err(
                path,
                std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    format!("output directory {} does not exist", dir.display()),
                ),
            ));
        }
    }
    // The same file under another name: compare canonical paths (the output exists) or the
    // canonical directory plus file name (it does not yet).
    let canonical = |p: &Path| -> Option<PathBuf> {
        std::fs::canonicalize(p).ok().or_else(|| {
            let dir = p.parent().filter(|d| !d.as_os_str().is_empty());
            let dir = std::fs::canonicalize(dir.unwrap_or(Path::new("."))).ok()?;
            Some(dir.join(p.file_name()?))
        })
    };
    let out = canonical(dest.path());
    for input in inputs {
        if out.is_some() && canonical(input) == out {
            return Err(MeshError::OutputIsInput {
                file: path.display().to_string(),
                input: input.display().to_string(),
            });
        }
    }
    Ok(dest)
}

/// One staged output of an [`OutputBatch`].
#[derive(Debug)]
enum Staged {
    /// Written to a temporary file next to the destination, renamed over it on commit.
    Temp(tempfile::NamedTempFile, PathBuf),
    /// The bytes for a device or FIFO, written in place on commit.
    InPlace(Vec<u8>, PathBuf),
}

/// Output files committed together (module docs): stage each with [`OutputBatch::add`], then
/// [`OutputBatch::commit`]. Dropping a batch without committing removes its temporary files.
///
/// ```
/// use symcorr_mesh::io::OutputBatch;
/// let dir = tempfile::tempdir().unwrap();
/// let (a, b) = (dir.path().join("a.txt"), dir.path().join("b.txt"));
/// let mut batch = OutputBatch::new();
/// batch.add(&a, b"first").unwrap();
/// assert!(!a.exists()); // nothing appears before the commit
/// // A second file that cannot be written: the batch is dropped, `a` never appears.
/// assert!(batch.add(&dir.path().join("missing/b.txt"), b"x").is_err());
/// drop(batch);
/// assert!(!a.exists());
/// let mut batch = OutputBatch::new();
/// batch.add(&a, b"first").unwrap();
/// batch.add(&b, b"second").unwrap();
/// assert_eq!(batch.commit().unwrap(), vec![a.clone(), b.clone()]);
/// assert_eq!(std::fs::read(&b).unwrap(), b"second");
/// ```
#[derive(Debug, Default)]
pub struct OutputBatch {
    staged: Vec<(PathBuf, Staged)>,
}

impl OutputBatch {
    /// An empty batch.
    pub fn new() -> OutputBatch {
        OutputBatch::default()
    }

    /// Stages `bytes` for `path` (as given; symlinks are followed, see the module docs).
    ///
    /// Errors: [`MeshError::Io`] naming `path` (directory missing or not writable, disk full),
    /// [`MeshError::OutputIsDirectory`], [`MeshError::DuplicateOutput`] when the batch already
    /// writes that file.
    pub fn add(&mut self, path: &Path, bytes: &[u8]) -> Result<(), MeshError> {
        self.add_streamed(path, |w| w.write_all(bytes))
    }

    /// Stages what `write` writes for `path`, as [`OutputBatch::add`] but without the bytes in
    /// memory: a large output (an animated GLB of hundreds of MB) is streamed into its
    /// temporary file. Only a device or FIFO destination is collected in memory first (it is
    /// written in place on commit).
    ///
    /// Errors: as [`OutputBatch::add`]; an error `write` returns is [`MeshError::Io`] naming
    /// `path`, and nothing is staged.
    ///
    /// ```
    /// use symcorr_mesh::io::OutputBatch;
    /// use std::io::Write as _;
    /// let dir = tempfile::tempdir().unwrap();
    /// let path = dir.path().join("n.txt");
    /// let mut batch = OutputBatch::new();
    /// batch
    ///     .add_streamed(&path, |w| (0..3).try_for_each(|i| write!(w, "{i}")))
    ///     .unwrap();
    /// batch.commit().unwrap();
    /// assert_eq!(std::fs::read_to_string(&path).unwrap(), "012");
    /// ```
    pub fn add_streamed(
        &mut self,
        path: &Path,
        write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    ) -> Result<(), MeshError> {
        let dest = resolve_output(path)?;
        if self.staged.iter().any(|(_, s)| match s {
            Staged::Temp(_, d) | Staged::InPlace(_, d) => d == dest.path(),
        }) {
            return Err(MeshError::DuplicateOutput {
                file: path.display().to_string(),
            });
        }
        let err = |e| io_err(path, e);
        let staged = match dest {
            Destination::Special(d) => {
                let mut bytes = Vec::new();
                write(&mut bytes).map_err(err)?;
                Staged::InPlace(bytes, d)
            }
            Destination::File(d) => {
                let dir = match d.parent() {
                    Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
                    _ => PathBuf::from("."),
                };
                let mut builder = tempfile::Builder::new();
                builder.prefix(".symcorr-tmp-");
                // Temporary files are created 0600; the output should get the usual mode
                // (0666 minus the umask, applied by the OS at creation), like a file written
                // directly.
                #[cfg(unix)]
                {
                    use std::os::unix::fs::PermissionsExt;
                    builder.permissions(std::fs::Permissions::from_mode(0o666));
                }
                let mut tmp = builder.tempfile_in(&dir).map_err(err)?;
                {
                    let mut w = std::io::BufWriter::new(tmp.as_file_mut());
                    write(&mut w).map_err(err)?;
                    w.flush().map_err(err)?;
                }
                tmp.as_file().sync_all().map_err(err)?;
                Staged::Temp(tmp, d)
            }
        };
        self.staged.push((path.to_path_buf(), staged));
        Ok(())
    }

    /// The temporary file holding what is staged for `path` (as given to
    /// [`OutputBatch::add`]), readable until the commit: an output derived from another one of
    /// the same batch is built from its staged bytes, not from an older file at `path`. `None`
    /// when `path` is not staged, or is a device or FIFO (its bytes wait in memory).
    ///
    /// ```
    /// use symcorr_mesh::io::OutputBatch;
    /// let dir = tempfile::tempdir().unwrap();
    /// let path = dir.path().join("a.txt");
    /// let mut batch = OutputBatch::new();
    /// batch.add(&path, b"staged").unwrap();
    /// let tmp = batch.staged_file(&path).unwrap();
    /// assert_eq!(std::fs::read(tmp).unwrap(), b"staged");
    /// assert!(batch.staged_file(&dir.path().join("b.txt")).is_none());
    /// ```
    pub fn staged_file(&self, path: &Path) -> Option<&Path> {
        self.staged.iter().find_map(|(given, s)| match s {
            Staged::Temp(tmp, _) if given == path => Some(tmp.path()),
            _ => None,
        })
    }

    /// Stages a mesh (and optional per-vertex colours) for `path`, in the format its extension
    /// names (PLY binary little-endian), like [`crate::io::write`].
    ///
    /// Errors: as [`crate::io::write`] and [`OutputBatch::add`].
    pub fn add_mesh(
        &mut self,
        path: &Path,
        mesh: &crate::TriMesh,
        colors: Option<&[[u8; 3]]>,
    ) -> Result<(), MeshError> {
        let format = super::Format::from_path_or_err(path)?;
        let bytes = super::write_to_bytes(mesh, colors, format, super::PlyEncoding::default())
            .map_err(|e| MeshError::InFile {
                file: path.display().to_string(),
                source: Box::new(e),
            })?;
        self.add(path, &bytes)
    }

    /// Moves every staged file into place (regular files by rename, then devices and FIFOs
    /// written in place) and returns the paths as given to [`OutputBatch::add`].
    ///
    /// Errors: [`MeshError::Io`] naming the file whose rename or write failed (the files
    /// before it are in place; the temporaries of those after it are removed).
    pub fn commit(self) -> Result<Vec<PathBuf>, MeshError> {
        let (files, special): (Vec<_>, Vec<_>) = self
            .staged
            .into_iter()
            .partition(|(_, s)| matches!(s, Staged::Temp(..)));
        let mut order = Vec::with_capacity(files.len() + special.len());
        for (given, staged) in files.into_iter().chain(special) {
            match staged {
                Staged::Temp(tmp, dest) => {
                    tmp.persist(&dest).map_err(|e| io_err(&given, e.error))?;
                }
                Staged::InPlace(bytes, dest) => {
                    let mut f = std::fs::OpenOptions::new()
                        .write(true)
                        .open(&dest)
                        .map_err(|e| io_err(&given, e))?;
                    f.write_all(&bytes).map_err(|e| io_err(&given, e))?;
                }
            }
            order.push(given);
        }
        Ok(order)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(unix)]
    #[test]
    fn a_symlink_is_written_through_and_stays_a_link() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("target.txt");
        std::fs::write(&target, "old").unwrap();
        let link = dir.path().join("link.txt");
        std::os::unix::fs::symlink("target.txt", &link).unwrap();
        let mut b = OutputBatch::new();
        b.add(&link, b"new").unwrap();
        b.commit().unwrap();
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "new");
        // A dangling link: the file it names is created.
        let dangling = dir.path().join("dangling");
        std::os::unix::fs::symlink("created.txt", &dangling).unwrap();
        let mut b = OutputBatch::new();
        b.add(&dangling, b"x").unwrap();
        b.commit().unwrap();
        assert_eq!(
            std::fs::read_to_string(dir.path().join("created.txt")).unwrap(),
            "x"
        );
        // An input reached through a link is refused.
        let input = dir.path().join("target.txt");
        assert!(matches!(
            check_output(&link, &[&input]),
            Err(MeshError::OutputIsInput { .. })
        ));
    }

    #[cfg(unix)]
    #[test]
    fn dev_null_is_written_in_place_not_replaced() {
        let null = Path::new("/dev/null");
        assert_eq!(
            resolve_output(null).unwrap(),
            Destination::Special(null.to_path_buf())
        );
        let mut b = OutputBatch::new();
        b.add(null, b"discarded").unwrap();
        b.commit().unwrap();
        let kind = std::fs::metadata(null).unwrap().file_type();
        assert!(!kind.is_file());
    }

    #[test]
    fn directories_duplicates_and_failed_batches_leave_nothing() {
        let dir = tempfile::tempdir().unwrap();
        assert!(matches!(
            check_output(dir.path(), &[]),
            Err(MeshError::OutputIsDirectory { .. })
        ));
        let a = dir.path().join("a.txt");
        let mut b = OutputBatch::new();
        b.add(&a, b"1").unwrap();
        assert!(matches!(
            b.add(&a, b"2"),
            Err(MeshError::DuplicateOutput { .. })
        ));
        drop(b);
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert!(left.is_empty(), "{left:?}");
        // The same input under another spelling is recognised.
        std::fs::write(&a, "input").unwrap();
        let other = dir.path().join(".").join("a.txt");
        assert!(matches!(
            check_output(&other, &[&a]),
            Err(MeshError::OutputIsInput { .. })
        ));
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "input");
    }
}
