//! NumPy `.npy` files (format version 1.0) written row by row: what `symcorr track` streams its
//! per-frame correspondence and confidence into, and what numpy users load directly
//! (`numpy.load`, or `numpy.load(..., mmap_mode="r")` for a long session).
//!
//! The header fixes the shape, so a file is created for a known number of rows; rows are
//! appended as they complete, and [`NpyWriter::resume`] reopens a file after its last complete
//! row (an interrupted run). Format: the magic `\x93NUMPY`, version `1.0`, a little-endian `u16`
//! header length, the header — a Python dict literal `{'descr': '<i4', 'fortran_order': False,
//! 'shape': (R, C), }` padded with spaces and ended by `\n` so that the data starts at a multiple
//! of 64 bytes — then the values in C order, little-endian. A row may itself be an array
//! ([`NpyWriter::create_shaped`]: `posed.npy` is frames × vertices × 3), and [`NpyReader`] reads
//! the rows of such a file back one at a time.

use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Element types written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NpyType {
    /// `<i4`.
    I32,
    /// `<f4`.
    F32,
}

impl NpyType {
    fn descr(self) -> &'static str {
        match self {
            NpyType::I32 => "<i4",
            NpyType::F32 => "<f4",
        }
    }
}

/// Errors of [`NpyWriter`], naming the file.
#[derive(Debug, thiserror::Error)]
pub enum NpyError {
    /// Reading or writing failed.
    #[error("{file}: {source}")]
    Io {
        /// The file.
        file: String,
        /// The error.
        source: std::io::Error,
    },
    /// A row of another length than the file's columns, or more rows than its shape.
    #[error("{file}: {message}")]
    Shape {
        /// The file.
        file: String,
        /// What did not fit.
        message: String,
    },
    /// The file to resume is not the one this writer would create.
    #[error("{file}: cannot resume: {message}")]
    Resume {
        /// The file.
        file: String,
        /// Why.
        message: String,
    },
}

/// The header bytes of a `(rows, cols)` array of `ty` (module docs).
///
/// ```
/// use symcorr::npy::{header, NpyType};
/// let h = header(NpyType::I32, 2, 3);
/// assert_eq!(h.len() % 64, 0);
/// assert!(h.starts_with(b"\x93NUMPY\x01\x00"));
/// assert!(String::from_utf8_lossy(&h).contains("'shape': (2, 3), }"));
/// ```
pub fn header(ty: NpyType, rows: usize, cols: usize) -> Vec<u8> {
    header_shaped(ty, rows, &[cols])
}

/// The header bytes of an array of `rows` rows, each of shape `row_shape` (`&[]`: a 1-D array
/// of `rows` values), of `ty`.
///
/// ```
/// use symcorr::npy::{header_shaped, NpyType};
/// let h = header_shaped(NpyType::F32, 4, &[13380, 3]);
/// assert_eq!(h.len() % 64, 0);
/// assert!(String::from_utf8_lossy(&h).contains("'shape': (4, 13380, 3), }"));
/// assert!(String::from_utf8_lossy(&header_shaped(NpyType::F32, 4, &[])).contains("(4,)"));
/// ```
pub fn header_shaped(ty: NpyType, rows: usize, row_shape: &[usize]) -> Vec<u8> {
    // A Python tuple: `(4,)` for one dimension, `(4, 5, 3)` for more.
    let mut shape = rows.to_string();
    match row_shape {
        [] => shape.push(','),
        dims => {
            for d in dims {
                shape.push_str(&format!(", {d}"));
            }
        }
    }
    let dict = format!(
        "{{'descr': '{}', 'fortran_order': False, 'shape': ({shape}), }}",
        ty.descr()
    );
    // magic (6) + version (2) + length (2) + dict + padding + '\n' ≡ 0 (mod 64).
    let unpadded = 10 + dict.len() + 1;
    let pad = (64 - unpadded % 64) % 64;
    let len = dict.len() + pad + 1;
    let mut out = Vec::with_capacity(10 + len);
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    // Invariant: the dict of a few usize numbers is far below 65,535 bytes.
    out.extend_from_slice(&(len as u16).to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out.extend(std::iter::repeat_n(b' ', pad));
    out.push(b'\n');
    out
}

/// A `.npy` file of a fixed `(rows, cols)` shape (or `(rows, …row shape)`,
/// [`NpyWriter::create_shaped`]) filled row by row: a file of its own (`W = File`: created,
/// resumed, synced) or any writer ([`NpyWriter::streaming`]).
pub struct NpyWriter<W = File> {
    file: W,
    /// The file's name, for errors.
    path: PathBuf,
    ty: NpyType,
    rows: usize,
    /// Values per row (the product of the row's shape).
    cols: usize,
    written: usize,
}

impl<W> std::fmt::Debug for NpyWriter<W> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NpyWriter")
            .field("path", &self.path)
            .field("ty", &self.ty)
            .field("rows", &self.rows)
            .field("cols", &self.cols)
            .field("written", &self.written)
            .finish_non_exhaustive()
    }
}

impl NpyWriter {
    /// Creates (or truncates) `path` with the header of a `(rows, cols)` array of `ty`. Until
    /// every row is written the file is shorter than its header says (numpy refuses it); an
    /// interrupted file is completed through [`NpyWriter::resume`].
    ///
    /// ```
    /// use symcorr::npy::{NpyType, NpyWriter};
    /// let dir = tempfile::tempdir().unwrap();
    /// let path = dir.path().join("c.npy");
    /// let mut w = NpyWriter::create(&path, NpyType::I32, 2, 3).unwrap();
    /// w.push_i32(&[1, -1, 7]).unwrap();
    /// w.push_i32(&[0, 2, 3]).unwrap();
    /// assert_eq!(std::fs::metadata(&path).unwrap().len(), 128 + 24);
    /// ```
    pub fn create(
        path: &Path,
        ty: NpyType,
        rows: usize,
        cols: usize,
    ) -> Result<NpyWriter, NpyError> {
        NpyWriter::create_shaped(path, ty, rows, &[cols])
    }

    /// [`NpyWriter::create`] for rows that are arrays of shape `row_shape`, pushed flattened in
    /// C order (`posed.npy`: rows of shape `[vertices, 3]`, each pushed as `3 × vertices`
    /// values).
    ///
    /// ```
    /// use symcorr::npy::{NpyType, NpyWriter};
    /// let dir = tempfile::tempdir().unwrap();
    /// let path = dir.path().join("p.npy");
    /// let mut w = NpyWriter::create_shaped(&path, NpyType::F32, 1, &[2, 3]).unwrap();
    /// w.push_f32([[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]].as_flattened()).unwrap();
    /// assert_eq!(std::fs::metadata(&path).unwrap().len(), 128 + 24);
    /// ```
    pub fn create_shaped(
        path: &Path,
        ty: NpyType,
        rows: usize,
        row_shape: &[usize],
    ) -> Result<NpyWriter, NpyError> {
        let io = |source| NpyError::Io {
            file: path.display().to_string(),
            source,
        };
        let mut file = File::create(path).map_err(io)?;
        file.write_all(&header_shaped(ty, rows, row_shape))
            .map_err(io)?;
        Ok(NpyWriter::at(
            file,
            path,
            ty,
            [rows, row_shape.iter().product()],
            0,
        ))
    }

    /// Reopens `path`, written by [`NpyWriter::create`] with the same type and shape, to continue
    /// after its first `rows_done` rows (a partly written row after them is overwritten).
    ///
    /// Errors: [`NpyError::Resume`] when the header differs or the file holds fewer rows.
    pub fn resume(
        path: &Path,
        ty: NpyType,
        rows: usize,
        cols: usize,
        rows_done: usize,
    ) -> Result<NpyWriter, NpyError> {
        NpyWriter::resume_shaped(path, ty, rows, &[cols], rows_done)
    }

    /// [`NpyWriter::resume`] of a file written by [`NpyWriter::create_shaped`].
    pub fn resume_shaped(
        path: &Path,
        ty: NpyType,
        rows: usize,
        row_shape: &[usize],
        rows_done: usize,
    ) -> Result<NpyWriter, NpyError> {
        let name = path.display().to_string();
        let io = |source| NpyError::Io {
            file: name.clone(),
            source,
        };
        let cols: usize = row_shape.iter().product();
        let want = header_shaped(ty, rows, row_shape);
        let bytes_done = (want.len() + rows_done * cols * 4) as u64;
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)
            .map_err(io)?;
        let mut head = vec![0u8; want.len()];
        let same = file.read_exact(&mut head).is_ok() && head == want;
        if !same {
            return Err(NpyError::Resume {
                file: name,
                message: format!(
                    "its header is not that of a {rows} × {row_shape:?} {} array",
                    ty.descr()
                ),
            });
        }
        let len = file.metadata().map_err(io)?.len();
        if len < bytes_done || rows_done > rows {
            return Err(NpyError::Resume {
                file: name,
                message: format!("it holds fewer than the {rows_done} rows to keep"),
            });
        }
        file.seek(SeekFrom::Start(bytes_done)).map_err(io)?;
        Ok(NpyWriter::at(file, path, ty, [rows, cols], rows_done))
    }

    /// Flushes the rows to the disk (`fsync`): after it they survive a crash.
    pub fn sync(&mut self) -> Result<(), NpyError> {
        self.file.sync_data().map_err(|source| NpyError::Io {
            file: self.path.display().to_string(),
            source,
        })
    }
}

impl<W: Write> NpyWriter<W> {
    /// Writes the header of a `ty` array of `rows` rows of shape `row_shape` into `out`, then
    /// takes its rows as [`NpyWriter::create_shaped`]'s file does; `name` is the file the bytes
    /// are for, named in errors. [`NpyWriter::finish`] checks that every row came.
    ///
    /// ```
    /// use symcorr::npy::{header, NpyType, NpyWriter};
    /// let mut bytes = Vec::new();
    /// let mut w = NpyWriter::streaming(&mut bytes, "c.npy".as_ref(), NpyType::I32, 1, &[2]).unwrap();
    /// w.push_i32(&[7, -1]).unwrap();
    /// w.finish().unwrap();
    /// assert_eq!(bytes.len(), header(NpyType::I32, 1, 2).len() + 8);
    /// ```
    pub fn streaming(
        mut out: W,
        name: &Path,
        ty: NpyType,
        rows: usize,
        row_shape: &[usize],
    ) -> Result<NpyWriter<W>, NpyError> {
        out.write_all(&header_shaped(ty, rows, row_shape))
            .map_err(|source| NpyError::Io {
                file: name.display().to_string(),
                source,
            })?;
        Ok(NpyWriter::at(
            out,
            name,
            ty,
            [rows, row_shape.iter().product()],
            0,
        ))
    }

    /// Flushes the writer and gives it back, once every row of the shape was written.
    ///
    /// Errors: [`NpyError::Shape`] when rows are missing (the bytes are not a whole array);
    /// [`NpyError::Io`].
    pub fn finish(mut self) -> Result<W, NpyError> {
        if self.written != self.rows {
            return Err(NpyError::Shape {
                file: self.path.display().to_string(),
                message: format!("{} of its {} rows written", self.written, self.rows),
            });
        }
        self.file.flush().map_err(|source| NpyError::Io {
            file: self.path.display().to_string(),
            source,
        })?;
        Ok(self.file)
    }

    /// A writer on `file`, positioned after `written` rows of a `shape` array.
    fn at(file: W, path: &Path, ty: NpyType, shape: [usize; 2], written: usize) -> NpyWriter<W> {
        NpyWriter {
            file,
            path: path.to_path_buf(),
            ty,
            rows: shape[0],
            cols: shape[1],
            written,
        }
    }

    fn check(&self, ty: NpyType, len: usize) -> Result<(), NpyError> {
        let err = |message: String| {
            Err(NpyError::Shape {
                file: self.path.display().to_string(),
                message,
            })
        };
        if ty != self.ty {
            return err(format!(
                "a {} row into a {} file",
                ty.descr(),
                self.ty.descr()
            ));
        }
        if len != self.cols {
            return err(format!(
                "a row of {len} values, the file has {} columns",
                self.cols
            ));
        }
        if self.written >= self.rows {
            return err(format!("more than the {} rows of its shape", self.rows));
        }
        Ok(())
    }

    fn push_bytes(&mut self, bytes: &[u8]) -> Result<(), NpyError> {
        self.file.write_all(bytes).map_err(|source| NpyError::Io {
            file: self.path.display().to_string(),
            source,
        })?;
        self.written += 1;
        Ok(())
    }

    /// Appends a row of an `I32` file.
    pub fn push_i32(&mut self, row: &[i32]) -> Result<(), NpyError> {
        self.check(NpyType::I32, row.len())?;
        let bytes: Vec<u8> = row.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.push_bytes(&bytes)
    }

    /// Appends a row of an `F32` file.
    pub fn push_f32(&mut self, row: &[f32]) -> Result<(), NpyError> {
        self.check(NpyType::F32, row.len())?;
        let bytes: Vec<u8> = row.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.push_bytes(&bytes)
    }

    /// Rows written so far.
    pub fn rows_written(&self) -> usize {
        self.written
    }
}

/// Reads the rows of a `.npy` file written by [`NpyWriter`] one at a time (a long session's
/// file is never read whole). Only the writer's own layout is accepted: the header must be
/// exactly the one [`header_shaped`] gives for the expected type and shape.
#[derive(Debug)]
pub struct NpyReader {
    file: File,
    path: PathBuf,
    ty: NpyType,
    rows: usize,
    cols: usize,
    data_start: u64,
}

impl NpyReader {
    /// Opens `path`, expected to hold a `ty` array of `rows` rows of shape `row_shape`.
    ///
    /// Errors: [`NpyError::Io`]; [`NpyError::Shape`] when the header is another one.
    ///
    /// ```
    /// use symcorr::npy::{NpyReader, NpyType, NpyWriter};
    /// let dir = tempfile::tempdir().unwrap();
    /// let path = dir.path().join("p.npy");
    /// let mut w = NpyWriter::create_shaped(&path, NpyType::F32, 2, &[1, 3]).unwrap();
    /// w.push_f32(&[1.0, 2.0, 3.0]).unwrap();
    /// w.push_f32(&[4.0, 5.0, 6.0]).unwrap();
    /// let mut r = NpyReader::open(&path, NpyType::F32, 2, &[1, 3]).unwrap();
    /// let mut row = Vec::new();
    /// r.read_f32(1, &mut row).unwrap();
    /// assert_eq!(row, [4.0, 5.0, 6.0]);
    /// assert!(r.read_f32(2, &mut row).is_err());
    /// ```
    pub fn open(
        path: &Path,
        ty: NpyType,
        rows: usize,
        row_shape: &[usize],
    ) -> Result<NpyReader, NpyError> {
        let name = path.display().to_string();
        let mut file = File::open(path).map_err(|source| NpyError::Io {
            file: name.clone(),
            source,
        })?;
        let want = header_shaped(ty, rows, row_shape);
        let mut head = vec![0u8; want.len()];
        if file.read_exact(&mut head).is_err() || head != want {
            return Err(NpyError::Shape {
                file: name,
                message: format!(
                    "expected a {rows} × {row_shape:?} {} array written by symcorr",
                    ty.descr()
                ),
            });
        }
        Ok(NpyReader {
            file,
            path: path.to_path_buf(),
            ty,
            rows,
            cols: row_shape.iter().product(),
            data_start: want.len() as u64,
        })
    }

    /// Reads row `row` of an `F32` file into `out` (replacing its contents).
    ///
    /// Errors: [`NpyError::Shape`] for a row past the shape or another type, [`NpyError::Io`]
    /// when the file ends before the row (not written yet).
    pub fn read_f32(&mut self, row: usize, out: &mut Vec<f32>) -> Result<(), NpyError> {
        let bytes = self.read_row(NpyType::F32, row)?;
        out.clear();
        out.extend(
            bytes
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        );
        Ok(())
    }

    /// Reads row `row` of an `I32` file into `out` (replacing its contents).
    ///
    /// Errors: as [`NpyReader::read_f32`].
    pub fn read_i32(&mut self, row: usize, out: &mut Vec<i32>) -> Result<(), NpyError> {
        let bytes = self.read_row(NpyType::I32, row)?;
        out.clear();
        out.extend(
            bytes
                .chunks_exact(4)
                .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        );
        Ok(())
    }

    /// The bytes of row `row`, checked to be a `ty` row of the shape.
    fn read_row(&mut self, ty: NpyType, row: usize) -> Result<Vec<u8>, NpyError> {
        if self.ty != ty || row >= self.rows {
            return Err(NpyError::Shape {
                file: self.path.display().to_string(),
                message: format!(
                    "no {} row {row} in a {} array of {} rows",
                    ty.descr(),
                    self.ty.descr(),
                    self.rows
                ),
            });
        }
        let io = |source| NpyError::Io {
            file: self.path.display().to_string(),
            source,
        };
        let at = self.data_start + (row * self.cols * 4) as u64;
        self.file.seek(SeekFrom::Start(at)).map_err(io)?;
        let mut bytes = vec![0u8; self.cols * 4];
        self.file.read_exact(&mut bytes).map_err(io)?;
        Ok(bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The header of the NumPy format specification's layout, written out by hand for one shape.
    #[test]
    fn the_header_is_the_specifications() {
        let h = header(NpyType::F32, 3, 13380);
        let dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (3, 13380), }";
        let mut want = b"\x93NUMPY\x01\x00".to_vec();
        let total = 64 * (10 + dict.len() + 1).div_ceil(64);
        let len = (total - 10) as u16;
        want.extend_from_slice(&len.to_le_bytes());
        want.extend_from_slice(dict.as_bytes());
        want.extend(std::iter::repeat_n(b' ', total - 10 - dict.len() - 1));
        want.push(b'\n');
        assert_eq!(h, want);
        assert_eq!(h.len(), 128);
    }

    #[test]
    fn rows_are_little_endian_in_c_order_and_resume_overwrites_a_partial_row() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.npy");
        let mut w = NpyWriter::create(&path, NpyType::I32, 3, 2).unwrap();
        w.push_i32(&[1, -1]).unwrap();
        assert!(w.push_i32(&[1, 2, 3]).is_err());
        assert!(w.push_f32(&[1.0, 2.0]).is_err());
        w.push_i32(&[0x0102_0304, 5]).unwrap();
        drop(w);
        // A third row cut short by a crash.
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(&[9, 9, 9]).unwrap();
        drop(f);
        let mut w = NpyWriter::resume(&path, NpyType::I32, 3, 2, 2).unwrap();
        w.push_i32(&[7, 8]).unwrap();
        assert!(w.push_i32(&[7, 8]).is_err(), "past the shape");
        drop(w);
        let bytes = std::fs::read(&path).unwrap();
        let h = header(NpyType::I32, 3, 2).len();
        assert_eq!(bytes.len(), h + 3 * 2 * 4);
        let data = &bytes[h..];
        assert_eq!(&data[0..4], &1i32.to_le_bytes());
        assert_eq!(&data[4..8], &(-1i32).to_le_bytes());
        assert_eq!(&data[8..12], &[4, 3, 2, 1]);
        assert_eq!(&data[16..24], &[7, 0, 0, 0, 8, 0, 0, 0]);
        // Another shape, or fewer rows than claimed, is refused.
        assert!(NpyWriter::resume(&path, NpyType::I32, 4, 2, 1).is_err());
        assert!(NpyWriter::resume(&path, NpyType::F32, 3, 2, 1).is_err());
        let short = dir.path().join("s.npy");
        NpyWriter::create(&short, NpyType::I32, 3, 2).unwrap();
        assert!(NpyWriter::resume(&short, NpyType::I32, 3, 2, 1).is_err());
    }

    #[test]
    fn shaped_rows_resume_and_read_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.npy");
        let mut w = NpyWriter::create_shaped(&path, NpyType::F32, 3, &[2, 3]).unwrap();
        w.push_f32(&[0.0, 1.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
        assert!(w.push_f32(&[0.0; 3]).is_err(), "a row is 2 × 3 values");
        drop(w);
        let mut w = NpyWriter::resume_shaped(&path, NpyType::F32, 3, &[2, 3], 1).unwrap();
        w.push_f32(&[f32::NAN; 6]).unwrap();
        drop(w);
        assert!(NpyWriter::resume_shaped(&path, NpyType::F32, 3, &[3, 2], 1).is_err());
        let mut r = NpyReader::open(&path, NpyType::F32, 3, &[2, 3]).unwrap();
        let mut row = Vec::new();
        r.read_f32(0, &mut row).unwrap();
        assert_eq!(row, [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
        r.read_f32(1, &mut row).unwrap();
        assert!(row.iter().all(|x| x.is_nan()));
        assert!(r.read_f32(2, &mut row).is_err(), "not written yet");
        assert!(NpyReader::open(&path, NpyType::F32, 3, &[6]).is_err());
        assert!(NpyReader::open(&path, NpyType::I32, 3, &[2, 3]).is_err());
    }

    /// A streamed array is byte for byte the file [`NpyWriter::create`] writes, its rows read
    /// back by type; a stream missing rows is refused at the end.
    #[test]
    fn streamed_rows_are_the_files_and_missing_rows_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.npy");
        let rows = [[1, -1, 7], [i32::MIN, 0, i32::MAX]];
        let mut w = NpyWriter::create(&path, NpyType::I32, 2, 3).unwrap();
        let mut bytes = Vec::new();
        let mut s = NpyWriter::streaming(&mut bytes, &path, NpyType::I32, 2, &[3]).unwrap();
        for r in &rows {
            w.push_i32(r).unwrap();
            s.push_i32(r).unwrap();
        }
        drop(w);
        s.finish().unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), bytes);
        let mut r = NpyReader::open(&path, NpyType::I32, 2, &[3]).unwrap();
        let mut row = Vec::new();
        r.read_i32(1, &mut row).unwrap();
        assert_eq!(row, rows[1]);
        assert!(r.read_f32(0, &mut Vec::new()).is_err(), "an i32 file");
        let mut short = NpyWriter::streaming(Vec::new(), &path, NpyType::F32, 2, &[1]).unwrap();
        short.push_f32(&[1.0]).unwrap();
        assert!(matches!(short.finish(), Err(NpyError::Shape { .. })));
    }
}
