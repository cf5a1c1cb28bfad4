//! The `symcorr` Python package: a thin pyo3 layer over the symcorr crates. It converts numpy
//! arrays to the library's types at the boundary, checks them (dtype, shape, finite values,
//! face indices in range) and delegates; all logic stays in the Rust crates.
//!
//! * `read_mesh`, `read_joints`: symcorr's readers (`symcorr::io`), the file's vertex order kept.
//! * `label`: `symcorr::label::label_mesh`, what `symcorr label` runs.
//! * `match`, `Prepared`: `symcorr::Pipeline` (prepare both meshes, then `Pipeline::run`);
//!   `Prepared` keeps one prepared template for many targets.
//! * `scan`: `symcorr_kinect::scan_mesh` on a depth image.
//! * `track`: `symcorr::track::Tracker::run` over a recording, one frame per iteration, run on
//!   a worker thread that owns the prepared template (observing the next frame while this one
//!   is matched, as `symcorr track` does).
//!
//! Every heavy call releases the GIL. Errors: `OSError` (or `FileNotFoundError`) for files that
//! cannot be read, `ValueError` for everything else, with the library's one-line message; a
//! bad array is refused before any Rust code sees it, never a crash.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArrayDyn};
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyStopIteration, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::mpsc::{sync_channel, Receiver};
use std::sync::{Arc, Mutex};
use std::time::Instant;
use symcorr::track::{FrameOutcome, TrackOptions, TrackedFrame, Tracker};
use symcorr::{Method, Mode, Pipeline, PipelineError, PipelineOptions, PreparedMesh};
use symcorr_attach::{BoundaryConvention, PoorFitPolicy, Segment};
use symcorr_kinect::clock::JointOffset;
use symcorr_kinect::{DepthFrame, DepthSource, Intrinsics, JointTrack, KinectError, ScanOptions};
use symcorr_mesh::{MeshError, TriMesh};
use symcorr_skeleton::{Joint, Skeleton};

// ------------------------------------------------------------------------------------------
// Errors
// ------------------------------------------------------------------------------------------

/// An I/O error as `OSError` (`FileNotFoundError` for a missing file), else `ValueError`.
fn io_kind(e: &PipelineError) -> Option<std::io::ErrorKind> {
    match e {
        PipelineError::Mesh(MeshError::Io { source, .. })
        | PipelineError::Joints(KinectError::Io { source, .. }) => Some(source.kind()),
        _ => None,
    }
}

/// The library's error as a Python exception with its one-line message, prefixed by
/// `context` (which input it concerns) when given.
fn py_err(e: PipelineError, context: Option<&str>) -> PyErr {
    let message = match context {
        Some(c) => format!("{c}: {e}"),
        None => e.to_string(),
    };
    match io_kind(&e) {
        Some(std::io::ErrorKind::NotFound) => PyFileNotFoundError::new_err(message),
        Some(_) => PyOSError::new_err(message),
        None => PyValueError::new_err(message),
    }
}

fn kinect_err(e: KinectError) -> PyErr {
    py_err(PipelineError::Joints(e), None)
}

fn value_err(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

// ------------------------------------------------------------------------------------------
// Arrays in
// ------------------------------------------------------------------------------------------

/// `obj` as a C-contiguous numpy array of `dtype`, converting only from the dtype kinds
/// `kinds` (numpy's `dtype.kind` letters); anything else is a `ValueError` naming `what`.
fn numpy_array<'py>(
    obj: &Bound<'py, PyAny>,
    what: &str,
    kinds: &str,
    dtype: &str,
    expected: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let py = obj.py();
    let np = py.import("numpy")?;
    let a = np
        .call_method1("asarray", (obj,))
        .map_err(|e| value_err(format!("{what}: expected {expected}: {e}")))?;
    let dt = a.getattr("dtype")?;
    let kind: String = dt.getattr("kind")?.extract()?;
    if !kinds.contains(kind.as_str()) {
        let name: String = dt.getattr("name")?.extract()?;
        return Err(value_err(format!(
            "{what}: expected {expected}, got dtype {name}"
        )));
    }
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", dtype)?;
    np.getattr("ascontiguousarray")?.call((a,), Some(&kwargs))
}

/// The array's shape, checked to be `(any, cols)` (`cols = None`: one dimension).
fn check_shape(a: &Bound<'_, PyAny>, what: &str, cols: Option<usize>) -> PyResult<Vec<usize>> {
    let shape: Vec<usize> = a.getattr("shape")?.extract()?;
    let ok = match cols {
        Some(c) => shape.len() == 2 && shape[1] == c,
        None => shape.len() == 1,
    };
    if !ok {
        let want = match cols {
            Some(c) => format!("(n, {c})"),
            None => "(n,)".to_string(),
        };
        return Err(value_err(format!(
            "{what}: expected shape {want}, got {}",
            shape_text(&shape)
        )));
    }
    Ok(shape)
}

fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// A contiguous float64 array's values.
fn f64_values(a: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    let r: PyReadonlyArrayDyn<'_, f64> = a.extract()?;
    Ok(r.as_slice().map_err(|e| value_err(e.to_string()))?.to_vec())
}

/// A contiguous int64 array's values.
fn i64_values(a: &Bound<'_, PyAny>) -> PyResult<Vec<i64>> {
    let r: PyReadonlyArrayDyn<'_, i64> = a.extract()?;
    Ok(r.as_slice().map_err(|e| value_err(e.to_string()))?.to_vec())
}

/// `(n, 3)` float vertices (any float or integer dtype), every coordinate finite.
fn vertices_in(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f64; 3]>> {
    let a = numpy_array(obj, what, "fiu", "float64", "a float array of shape (n, 3)")?;
    check_shape(&a, what, Some(3))?;
    let v = f64_values(&a)?;
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(value_err(format!(
            "{what}: vertex {} has a non-finite coordinate",
            i / 3
        )));
    }
    Ok(v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
}

/// `(m, 3)` integer faces, every index in `0..vertices`.
fn faces_in(obj: &Bound<'_, PyAny>, what: &str, vertices: usize) -> PyResult<Vec<[u32; 3]>> {
    let a = numpy_array(obj, what, "iu", "int64", "an integer array of shape (m, 3)")?;
    check_shape(&a, what, Some(3))?;
    let f = i64_values(&a)?;
    if let Some(i) = f
        .iter()
        .position(|&x| x < 0 || usize::try_from(x).map_or(true, |x| x >= vertices))
    {
        return Err(value_err(format!(
            "{what}: face {} has vertex index {}, out of range (the mesh has {vertices} vertices)",
            i / 3,
            f[i]
        )));
    }
    // In range of `vertices` (a usize of a Vec's length), so each fits u32 when the mesh does.
    let index =
        |x: i64| u32::try_from(x).map_err(|_| value_err(format!("{what}: index {x} too large")));
    f.chunks_exact(3)
        .map(|c| Ok([index(c[0])?, index(c[1])?, index(c[2])?]))
        .collect()
}

/// A mesh from vertices and faces, checked by `TriMesh::new` as well.
fn mesh_in(v: &Bound<'_, PyAny>, f: &Bound<'_, PyAny>, side: &str) -> PyResult<TriMesh> {
    let vertices = vertices_in(v, &format!("{side}vertices"))?;
    let faces = faces_in(f, &format!("{side}faces"), vertices.len())?;
    TriMesh::new(vertices, faces).map_err(|e| {
        py_err(
            e.into(),
            (!side.is_empty()).then(|| side.trim_end_matches(' ')),
        )
    })
}

/// Joints: a dict joint name → xyz (all 20 Kinect v1 joints) or a `(20, 3)` array in Kinect v1
/// order. Every joint counts as tracked (confidence 1).
fn skeleton_in(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Skeleton> {
    let mut xyz = [[0.0; 3]; Joint::COUNT];
    if let Ok(d) = obj.cast::<PyDict>() {
        for key in d.keys() {
            let name: String = key
                .extract()
                .map_err(|_| value_err(format!("{what}: keys must be joint names (str)")))?;
            if Joint::from_name(&name).is_none() {
                return Err(value_err(format!(
                    "{what}: unknown joint {name:?}; the names are symcorr.JOINT_NAMES"
                )));
            }
        }
        let missing: Vec<&str> = Joint::ALL
            .iter()
            .map(|j| j.name())
            .filter(|n| !d.contains(*n).unwrap_or(false))
            .collect();
        if !missing.is_empty() {
            return Err(value_err(format!(
                "{what}: missing joint(s) {}; all 20 Kinect v1 joints are needed",
                missing.join(", ")
            )));
        }
        for j in Joint::ALL {
            let item = d
                .get_item(j.name())?
                .ok_or_else(|| value_err(format!("{what}: missing joint {}", j.name())))?;
            let p = vertices_in(&item, &format!("{what}[{:?}]", j.name())).or_else(|_| {
                let a = numpy_array(&item, what, "fiu", "float64", "three coordinates")?;
                check_shape(&a, &format!("{what}[{:?}]", j.name()), None)?;
                let v = f64_values(&a)?;
                match v.as_slice() {
                    [x, y, z] => Ok(vec![[*x, *y, *z]]),
                    _ => Err(value_err(format!(
                        "{what}[{:?}]: expected three coordinates, got {}",
                        j.name(),
                        v.len()
                    ))),
                }
            })?;
            match p.as_slice() {
                [p] if p.iter().all(|c| c.is_finite()) => xyz[j.index()] = *p,
                [_] => {
                    return Err(value_err(format!(
                        "{what}[{:?}]: non-finite coordinate",
                        j.name()
                    )))
                }
                _ => {
                    return Err(value_err(format!(
                        "{what}[{:?}]: expected three coordinates",
                        j.name()
                    )))
                }
            }
        }
    } else {
        let a = numpy_array(
            obj,
            what,
            "fiu",
            "float64",
            "a dict joint name → xyz or a (20, 3) float array in Kinect v1 order",
        )?;
        let shape = check_shape(&a, what, Some(3))?;
        if shape[0] != Joint::COUNT {
            return Err(value_err(format!(
                "{what}: expected shape (20, 3) (Kinect v1 order), got {}",
                shape_text(&shape)
            )));
        }
        let v = f64_values(&a)?;
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(value_err(format!(
                "{what}: joint {} ({}) has a non-finite coordinate",
                i / 3,
                Joint::ALL[i / 3].name()
            )));
        }
        for (k, c) in v.chunks_exact(3).enumerate() {
            xyz[k] = [c[0], c[1], c[2]];
        }
    }
    Ok(Skeleton::from_arrays(xyz))
}

// ------------------------------------------------------------------------------------------
// Arrays out
// ------------------------------------------------------------------------------------------

fn rows3<'py, T: numpy::Element + Copy>(
    py: Python<'py>,
    rows: &[[T; 3]],
) -> PyResult<Bound<'py, PyArray2<T>>> {
    let flat: Vec<T> = rows.iter().flatten().copied().collect();
    let a = Array2::from_shape_vec((rows.len(), 3), flat).map_err(|e| value_err(e.to_string()))?;
    Ok(a.into_pyarray(py))
}

/// Vertices `float64 (n, 3)` and faces `int64 (m, 3)`.
type MeshArrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>);

fn vertices_out<'py>(py: Python<'py>, m: &TriMesh) -> PyResult<Bound<'py, PyArray2<f64>>> {
    rows3(py, &m.positions)
}

fn faces_out<'py>(py: Python<'py>, m: &TriMesh) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let t: Vec<[i64; 3]> = m.triangles.iter().map(|t| t.map(i64::from)).collect();
    rows3(py, &t)
}

fn joints_dict<'py>(py: Python<'py>, s: &Skeleton) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for j in Joint::ALL {
        let p = s.position(j);
        d.set_item(j.name(), (p.x, p.y, p.z))?;
    }
    Ok(d)
}

// ------------------------------------------------------------------------------------------
// Inputs: bodies and methods
// ------------------------------------------------------------------------------------------

/// A body: a mesh (vertices `float64 (n, 3)`, faces `int64 (m, 3)`) and its skeleton's 20 joints,
/// checked once.
///
/// Example::
///
///     V, F = symcorr.read_mesh("fixtures/synth/bodies/meshes/s0_rest.ply")
///     J = symcorr.read_joints("fixtures/synth/bodies/joints/s0_rest.json")
///     body = symcorr.Body(V, F, J)
#[pyclass(module = "symcorr", frozen, from_py_object)]
#[derive(Clone)]
struct Body {
    mesh: Arc<TriMesh>,
    skeleton: Skeleton,
}

#[pymethods]
impl Body {
    #[new]
    fn new(
        vertices: &Bound<'_, PyAny>,
        faces: &Bound<'_, PyAny>,
        joints: &Bound<'_, PyAny>,
    ) -> PyResult<Body> {
        Ok(Body {
            mesh: Arc::new(mesh_in(vertices, faces, "")?),
            skeleton: skeleton_in(joints, "joints")?,
        })
    }

    /// The vertices, `float64 (n, 3)` (a copy).
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        vertices_out(py, &self.mesh)
    }

    /// The faces, `int64 (m, 3)` (a copy).
    #[getter]
    fn faces<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        faces_out(py, &self.mesh)
    }

    /// The 20 joints, `float64 (20, 3)` in Kinect v1 order (`symcorr.JOINT_NAMES`).
    #[getter]
    fn joints<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        rows3(py, &self.skeleton.to_arrays())
    }

    fn __getnewargs__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(
            py,
            [
                self.vertices(py)?.into_any(),
                self.faces(py)?.into_any(),
                self.joints(py)?.into_any(),
            ],
        )
    }

    fn __repr__(&self) -> String {
        format!(
            "Body(vertices={}, faces={})",
            self.mesh.num_vertices(),
            self.mesh.num_triangles()
        )
    }
}

/// A `Body` or a `(vertices, faces, joints)` tuple.
fn body_in(obj: &Bound<'_, PyAny>, side: &str) -> PyResult<Body> {
    if let Ok(b) = obj.cast::<Body>() {
        return Ok(b.get().clone());
    }
    let t: (Bound<'_, PyAny>, Bound<'_, PyAny>, Bound<'_, PyAny>) =
        obj.extract().map_err(|_| {
            value_err(format!(
                "{side}: expected a symcorr.Body or a (vertices, faces, joints) tuple"
            ))
        })?;
    Ok(Body {
        mesh: Arc::new(mesh_in(&t.0, &t.1, &format!("{side} "))?),
        skeleton: skeleton_in(&t.2, &format!("{side} joints"))?,
    })
}

fn method_in(name: &str) -> PyResult<Method> {
    match name {
        "articulated" => Ok(Method::Articulated),
        "refined" => Ok(Method::Refined),
        "paper" => Ok(Method::Paper),
        _ => Err(value_err(format!(
            "method {name:?}: expected \"articulated\", \"refined\" or \"paper\""
        ))),
    }
}

fn method_name(m: Method) -> &'static str {
    match m {
        Method::Articulated => "articulated",
        Method::Refined => "refined",
        Method::Paper => "paper",
    }
}

/// The pipeline `symcorr match` builds from the same options.
fn pipeline_for(
    method: &str,
    dense: bool,
    samples: i64,
    accept_poor_fit: bool,
) -> PyResult<Pipeline> {
    let samples = usize::try_from(samples)
        .map_err(|_| value_err(format!("samples {samples}: must be at least 1")))?;
    let mut o = PipelineOptions {
        method: method_in(method)?,
        mode: if dense {
            Mode::Dense
        } else {
            Mode::Sparse { samples }
        },
        ..PipelineOptions::default()
    };
    if accept_poor_fit {
        o.prepare.attach.poor_fit = PoorFitPolicy::Accept;
    }
    o.check()
        .map_err(|e| py_err(PipelineError::Option(e), None))?;
    Ok(Pipeline::new(o))
}

// ------------------------------------------------------------------------------------------
// Results
// ------------------------------------------------------------------------------------------

/// A correspondence: `pairs` (`int64 (k, 2)`: template vertex, target vertex — the ids of the
/// arrays or files given), `confidence` (`float64 (k,)`), `no_counterpart` (`int64` template
/// vertices a partial target such as a single-view scan does not show; `None` for a whole
/// target), `timings` (seconds per stage), `method` and `coverage` (fraction of target vertices
/// hit; `None` for the paper's method); the articulated method adds the matches as points of
/// the target's surface, `surface_corners` (`int64 (k, 3)`, a triangle's corners, target ids)
/// and `surface_weights` (`float64 (k, 3)`, barycentric), `None` for the other methods. On a
/// single-view target (articulated method), `view_held` is the fraction of the template points
/// the fit shows the camera that lie on the scan (`None` elsewhere), and `turned_about_spine`
/// says that the target's joints faced away from the camera and were turned half a turn about
/// their spine before the match (as ``symcorr match`` does; a fit that holds under half of its
/// view either way is a ``ValueError``, and so is a view on which neither fit holds clearly
/// more: which way the body faces is then unknown).
#[pyclass(module = "symcorr", frozen, get_all)]
struct Correspondence {
    pairs: Py<PyAny>,
    confidence: Py<PyAny>,
    no_counterpart: Py<PyAny>,
    timings: Py<PyAny>,
    method: String,
    coverage: Option<f64>,
    surface_corners: Py<PyAny>,
    surface_weights: Py<PyAny>,
    view_held: Option<f64>,
    turned_about_spine: bool,
}

#[pymethods]
impl Correspondence {
    #[new]
    #[pyo3(signature = (pairs, confidence, no_counterpart, timings, method, coverage, surface_corners=None, surface_weights=None, view_held=None, turned_about_spine=false))]
    #[allow(clippy::too_many_arguments)] // the attributes, in order, as pickling passes them
    fn new(
        py: Python<'_>,
        pairs: Py<PyAny>,
        confidence: Py<PyAny>,
        no_counterpart: Py<PyAny>,
        timings: Py<PyAny>,
        method: String,
        coverage: Option<f64>,
        surface_corners: Option<Py<PyAny>>,
        surface_weights: Option<Py<PyAny>>,
        view_held: Option<f64>,
        turned_about_spine: bool,
    ) -> Self {
        Correspondence {
            pairs,
            confidence,
            no_counterpart,
            timings,
            method,
            coverage,
            surface_corners: surface_corners.unwrap_or_else(|| py.None()),
            surface_weights: surface_weights.unwrap_or_else(|| py.None()),
            view_held,
            turned_about_spine,
        }
    }

    fn __getnewargs__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        (
            self.pairs.clone_ref(py),
            self.confidence.clone_ref(py),
            self.no_counterpart.clone_ref(py),
            self.timings.clone_ref(py),
            self.method.clone(),
            self.coverage,
            self.surface_corners.clone_ref(py),
            self.surface_weights.clone_ref(py),
            self.view_held,
            self.turned_about_spine,
        )
            .into_pyobject(py)
    }

    fn __len__(&self, py: Python<'_>) -> PyResult<usize> {
        self.pairs.bind(py).len()
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let unseen = match self.no_counterpart.bind(py) {
            n if n.is_none() => String::new(),
            n => format!(", no_counterpart={}", n.len()?),
        };
        Ok(format!(
            "Correspondence(method={:?}, pairs={}{unseen})",
            self.method,
            self.__len__(py)?
        ))
    }
}

fn correspondence_out(
    py: Python<'_>,
    template: &PreparedMesh,
    matched: (&PreparedMesh, &symcorr::ViewMatch),
    method: Method,
    timings: Vec<(String, f64)>,
) -> PyResult<Correspondence> {
    let (target, corr) = (matched.1.target(matched.0), &matched.1.correspondence);
    // The ids of the inputs, as the correspondence file writes them; template points a partial
    // target does not show are listed apart.
    let shown = corr.has_counterpart();
    let surface = corr.surface_points(target);
    let mut pairs = Vec::with_capacity(corr.pairs.len());
    let mut confidence = Vec::with_capacity(corr.pairs.len());
    let mut unseen = Vec::new();
    let (mut corners, mut weights) = (Vec::new(), Vec::new());
    for (i, m) in corr.pairs.iter().enumerate() {
        let t = i64::from(template.input_id(m.template));
        if shown.is_some_and(|h| !h[i]) {
            unseen.push(t);
        } else {
            pairs.push(t);
            pairs.push(i64::from(target.input_id(m.target)));
            confidence.push(m.confidence);
            if let Some(p) = surface.as_ref().and_then(|s| s.get(i)) {
                corners.extend(p.corners.map(|c| i64::from(target.input_id(c))));
                weights.extend(p.weights);
            }
        }
    }
    let k = confidence.len();
    let pairs = Array2::from_shape_vec((k, 2), pairs).map_err(|e| value_err(e.to_string()))?;
    let (surface_corners, surface_weights) = match surface {
        Some(_) => (
            Array2::from_shape_vec((k, 3), corners)
                .map_err(|e| value_err(e.to_string()))?
                .into_pyarray(py)
                .into_any()
                .unbind(),
            Array2::from_shape_vec((k, 3), weights)
                .map_err(|e| value_err(e.to_string()))?
                .into_pyarray(py)
                .into_any()
                .unbind(),
        ),
        None => (py.None(), py.None()),
    };
    let t = PyDict::new(py);
    for (name, s) in timings {
        t.set_item(name, s)?;
    }
    Ok(Correspondence {
        pairs: pairs.into_pyarray(py).into_any().unbind(),
        confidence: PyArray1::from_vec(py, confidence).into_any().unbind(),
        no_counterpart: match shown {
            Some(_) => PyArray1::from_vec(py, unseen).into_any().unbind(),
            None => py.None(),
        },
        timings: t.into_any().unbind(),
        method: method_name(method).to_string(),
        coverage: corr.coverage(),
        surface_corners,
        surface_weights,
        view_held: corr.view_held(),
        turned_about_spine: matched.1.turned_target.is_some(),
    })
}

/// Segment labels of a mesh: `segments` (`int64 (n,)`, an index into `names`, −1 for a vertex in
/// a component no bone reaches), `names` (the 17 segment names), `joints` (the joints as the
/// attachment refined them, name → xyz), `fit_score` and `corrections` (what was corrected:
/// `turned_triangles`, `mirrored_fixed`, `joint_moves` as (joint, distance, reason),
/// `repaired_joints` as (joint, repair), `accepted_poor_fit`, `unreached_vertices`).
#[pyclass(module = "symcorr", frozen, get_all)]
struct Labels {
    segments: Py<PyAny>,
    names: Py<PyAny>,
    joints: Py<PyAny>,
    fit_score: f64,
    corrections: Py<PyAny>,
}

#[pymethods]
impl Labels {
    #[new]
    fn new(
        segments: Py<PyAny>,
        names: Py<PyAny>,
        joints: Py<PyAny>,
        fit_score: f64,
        corrections: Py<PyAny>,
    ) -> Self {
        Labels {
            segments,
            names,
            joints,
            fit_score,
            corrections,
        }
    }

    fn __getnewargs__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        (
            self.segments.clone_ref(py),
            self.names.clone_ref(py),
            self.joints.clone_ref(py),
            self.fit_score,
            self.corrections.clone_ref(py),
        )
            .into_pyobject(py)
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!(
            "Labels(vertices={}, fit_score={:.3})",
            self.segments.bind(py).len()?,
            self.fit_score
        ))
    }
}

fn segment_names(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    PyList::new(py, Segment::ALL.iter().map(|s| s.name()))
}

// ------------------------------------------------------------------------------------------
// Functions
// ------------------------------------------------------------------------------------------

/// Reads a mesh file (OBJ, OFF, PLY, glTF/GLB, by extension) in the file's vertex order:
/// vertices ``float64 (n, 3)`` and faces ``int64 (m, 3)``. Nothing is repaired.
///
/// Raises ``OSError`` (``FileNotFoundError``) when the file cannot be read and ``ValueError``
/// for a malformed one, with the message of ``symcorr`` on the command line.
///
/// Example::
///
///     V, F = symcorr.read_mesh("fixtures/synth/bodies/meshes/s0_rest.ply")
///     V.shape, F.shape   # ((13380, 3), (26756, 3))
#[pyfunction]
fn read_mesh<'py>(py: Python<'py>, path: PathBuf) -> PyResult<MeshArrays<'py>> {
    let mesh = py
        .detach(|| symcorr::io::read_mesh(&path, symcorr_mesh::io::DEFAULT_MAX_INPUT_BYTES))
        .map_err(|e| py_err(e, None))?;
    Ok((vertices_out(py, &mesh)?, faces_out(py, &mesh)?))
}

/// Reads a joint file (symcorr.joints/1, NiTE, Kinect v2, Kinect SDK text, NTU .skeleton;
/// detected from the content) and returns one frame (``None``: the first) as the 20 Kinect v1
/// joints, name → (x, y, z), in ``symcorr.JOINT_NAMES`` order. Joints the format lacks are
/// interpolated along their chain, as everywhere in symcorr.
///
/// Example::
///
///     J = symcorr.read_joints("fixtures/synth/bodies/joints/s0_rest.json")
///     J["head"]          # (x, y, z)
///     np.array([J[n] for n in symcorr.JOINT_NAMES])   # (20, 3)
#[pyfunction]
#[pyo3(signature = (path, frame=None))]
fn read_joints<'py>(
    py: Python<'py>,
    path: PathBuf,
    frame: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let s = py
        .detach(|| symcorr::io::read_skeleton(&path, frame))
        .map_err(|e| py_err(e, None))?;
    joints_dict(py, &s)
}

/// Labels every vertex with one of the 17 body segments, as ``symcorr label`` does: the
/// triangles are oriented consistently, the skeleton is attached (bone heat) and its fit
/// checked (a skeleton of another body or pose is refused with ``ValueError`` naming the failed
/// check, unless ``accept_poor_fit``). ``boundaries`` is ``"joint-planes"`` or ``"makehuman"``.
/// ``joints`` is a dict joint name → xyz or a ``(20, 3)`` array in Kinect v1 order.
///
/// Example::
///
///     V, F = symcorr.read_mesh("fixtures/synth/bodies/meshes/s0_walk-10.ply")
///     labels = symcorr.label(V, F, symcorr.read_joints("fixtures/synth/bodies/joints/s0_walk-10.json"))
///     labels.names[labels.segments[0]]   # e.g. 'head'
#[pyfunction]
#[pyo3(signature = (vertices, faces, joints, *, boundaries="joint-planes", accept_poor_fit=false))]
fn label<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
    joints: &Bound<'py, PyAny>,
    boundaries: &str,
    accept_poor_fit: bool,
) -> PyResult<Labels> {
    let mesh = mesh_in(vertices, faces, "")?;
    let skeleton = skeleton_in(joints, "joints")?;
    let convention = match boundaries {
        "joint-planes" => None,
        "makehuman" => Some(BoundaryConvention::makehuman()),
        other => {
            return Err(value_err(format!(
                "boundaries {other:?}: expected \"joint-planes\" or \"makehuman\""
            )))
        }
    };
    let options = symcorr_attach::AttachOptions {
        poor_fit: if accept_poor_fit {
            PoorFitPolicy::Accept
        } else {
            PoorFitPolicy::Refuse
        },
        convention,
        ..symcorr_attach::AttachOptions::default()
    };
    let l = py
        .detach(|| symcorr::label::label_mesh(&mesh, &skeleton, &options))
        .map_err(|e| py_err(e, None))?;
    let segments: Vec<i64> = l
        .segments()
        .iter()
        .map(|s| s.map_or(-1, |x| x as i64))
        .collect();
    let d = &l.attachment.diagnostics;
    let c = PyDict::new(py);
    c.set_item("turned_triangles", l.turned_triangles)?;
    c.set_item("mirrored_fixed", d.mirror.swapped)?;
    c.set_item("limbs_swapped", d.mirror.swapped_limbs.map(|p| p.name()))?;
    let moves: Vec<(String, f64, String)> = d
        .joint_moves
        .iter()
        .map(|m| {
            (
                m.joint.name().to_string(),
                m.distance(),
                m.reason.to_string(),
            )
        })
        .collect();
    c.set_item("joint_moves", moves)?;
    let repaired: Vec<(String, String)> = d
        .repaired_joints
        .iter()
        .map(|(j, r)| (j.name().to_string(), format!("{r:?}").to_lowercase()))
        .collect();
    c.set_item("repaired_joints", repaired)?;
    c.set_item("accepted_poor_fit", d.fit.accepted_poor_fit)?;
    c.set_item("unreached_vertices", d.fit.unreached.len())?;
    Ok(Labels {
        segments: PyArray1::from_vec(py, segments).into_any().unbind(),
        names: segment_names(py)?.into_any().unbind(),
        joints: joints_dict(py, &l.attachment.joints)?.into_any().unbind(),
        fit_score: d.fit.score,
        corrections: c.into_any().unbind(),
    })
}

/// Matches template vertices to target vertices without mapping a left limb onto a right one,
/// as ``symcorr match`` does (same pipeline, same pairs). ``template`` and ``target`` are
/// ``symcorr.Body`` objects or ``(vertices, faces, joints)`` tuples (vertices ``float64 (n, 3)``,
/// faces ``int (m, 3)``, joints a dict name → xyz or a ``(20, 3)`` array in Kinect v1 order).
/// ``method``: ``"articulated"`` (default), ``"refined"`` or ``"paper"``; ``dense=False`` matches
/// a farthest-point sample of ``samples`` template points. A single-view scan as the target
/// lists the template points it does not show under ``no_counterpart``. Both meshes are
/// prepared in the call; to match one template against many targets use ``symcorr.Prepared``.
/// Returns a ``symcorr.Correspondence`` (pairs, confidence, no_counterpart, timings).
///
/// Example::
///
///     d = "fixtures/synth/bodies"
///     body = lambda n: (*symcorr.read_mesh(f"{d}/meshes/{n}.ply"), symcorr.read_joints(f"{d}/joints/{n}.json"))
///     c = symcorr.match(body("s0_rest"), body("s1_t-pose"))
///     c.pairs[:3], c.confidence[:3], c.timings["total"]
#[pyfunction(name = "match")]
#[pyo3(signature = (template, target, method="articulated", dense=true, *, samples=1000, accept_poor_fit=false))]
fn match_<'py>(
    py: Python<'py>,
    template: &Bound<'py, PyAny>,
    target: &Bound<'py, PyAny>,
    method: &str,
    dense: bool,
    samples: i64,
    accept_poor_fit: bool,
) -> PyResult<Correspondence> {
    let start = Instant::now();
    let pipeline = pipeline_for(method, dense, samples, accept_poor_fit)?;
    let a = body_in(template, "template")?;
    let b = body_in(target, "target")?;
    let out = py.detach(|| {
        let (pa, pb) = rayon::join(
            || pipeline.prepare((*a.mesh).clone(), &a.skeleton),
            || pipeline.prepare((*b.mesh).clone(), &b.skeleton),
        );
        let pa = pa.map_err(|e| (e, Some("template")))?;
        let pb = pb.map_err(|e| (e, Some("target")))?;
        let matched = pipeline.run_on_view(&pa, &pb).map_err(|e| (e, None))?;
        Ok::<_, (PipelineError, Option<&str>)>((pa, pb, matched))
    });
    let (pa, pb, matched) = out.map_err(|(e, side)| py_err(e, side))?;
    let mut timings =
        symcorr::output::pair_timings(&pa, matched.target(&pb), &matched.correspondence);
    timings.push(("total".into(), start.elapsed().as_secs_f64()));
    correspondence_out(py, &pa, (&pb, &matched), pipeline.options.method, timings)
}

/// A template prepared once (repair, skeleton attachment, and the spectral data the method
/// needs) and matched against many targets with ``match``; results equal ``symcorr.match``'s.
///
/// Example::
///
///     p = symcorr.Prepared(body("s0_rest"))
///     for name in ["s1_t-pose", "s1_walk-60"]:
///         c = p.match(body(name))
#[pyclass(module = "symcorr", frozen)]
struct Prepared {
    pipeline: Pipeline,
    template: Arc<PreparedMesh>,
    body: Body,
}

#[pymethods]
impl Prepared {
    #[new]
    #[pyo3(signature = (template, method="articulated", dense=true, *, samples=1000, accept_poor_fit=false))]
    fn new(
        py: Python<'_>,
        template: &Bound<'_, PyAny>,
        method: &str,
        dense: bool,
        samples: i64,
        accept_poor_fit: bool,
    ) -> PyResult<Prepared> {
        let pipeline = pipeline_for(method, dense, samples, accept_poor_fit)?;
        let body = body_in(template, "template")?;
        let prepared = py
            .detach(|| pipeline.prepare((*body.mesh).clone(), &body.skeleton))
            .map_err(|e| py_err(e, Some("template")))?;
        Ok(Prepared {
            pipeline,
            template: Arc::new(prepared),
            body,
        })
    }

    /// Matches the prepared template onto ``target`` (a ``symcorr.Body`` or a
    /// ``(vertices, faces, joints)`` tuple); only the target is prepared.
    #[pyo3(name = "match")]
    fn match_(&self, py: Python<'_>, target: &Bound<'_, PyAny>) -> PyResult<Correspondence> {
        let start = Instant::now();
        let b = body_in(target, "target")?;
        let (pb, matched) = py
            .detach(|| {
                let pb = self
                    .pipeline
                    .prepare((*b.mesh).clone(), &b.skeleton)
                    .map_err(|e| (e, Some("target")))?;
                let matched = self
                    .pipeline
                    .run_on_view(&self.template, &pb)
                    .map_err(|e| (e, None))?;
                Ok::<_, (PipelineError, Option<&str>)>((pb, matched))
            })
            .map_err(|(e, side)| py_err(e, side))?;
        let mut timings: Vec<(String, f64)> = matched.target(&pb).timings.clone();
        timings.extend(matched.correspondence.timings.iter().cloned());
        timings.push(("total".into(), start.elapsed().as_secs_f64()));
        correspondence_out(
            py,
            &self.template,
            (&pb, &matched),
            self.pipeline.options.method,
            timings,
        )
    }

    /// The matching method.
    #[getter]
    fn method(&self) -> &'static str {
        method_name(self.pipeline.options.method)
    }

    /// The template as given.
    #[getter]
    fn template(&self) -> Body {
        self.body.clone()
    }

    /// Segment index per template vertex (−1: removed by the repair or unreached).
    #[getter]
    fn segments<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let l: Vec<Option<i64>> = self
            .template
            .labels()
            .iter()
            .map(|s| Some(s.index() as i64))
            .collect();
        let l: Vec<i64> = self
            .template
            .to_input(&l, None)
            .into_iter()
            .map(|x| x.unwrap_or(-1))
            .collect();
        PyArray1::from_vec(py, l)
    }

    fn __repr__(&self) -> String {
        format!(
            "Prepared(method={:?}, vertices={})",
            self.method(),
            self.template.input_mesh().num_vertices()
        )
    }
}

/// Turns a depth image (``uint16 (h, w)``, millimetres, 0 = no depth) into a scan mesh of the
/// body, as ``symcorr scan --depth`` does: floor and background removed with the skeleton, the
/// components near the bones kept. ``intrinsics`` is a dict with ``fx``, ``fy``, ``cx``, ``cy``
/// (pixels; ``width``/``height`` optional, and then must match the image; ``mirrored``
/// optional, ``False`` for an image as the lens forms it, not mirrored as the Kinect SDK's;
/// ``distortion`` optional, OpenCV's ``distCoeffs``: 4, 5 or 8 numbers ``k1, k2, p1, p2[, k3[,
/// k4, k5, k6]]``) or the path of a symcorr.intrinsics/1 file; ``joints`` a dict name → xyz or
/// a ``(20, 3)`` array in camera space, metres. Returns vertices ``float64 (n, 3)`` (camera
/// space, metres), faces ``int64 (m, 3)`` and per vertex its pixel id ``v * w + u``
/// (``int64 (n,)``).
///
/// Example::
///
///     depth = symcorr.read_depth("fixtures/synth/scan/depth.png")
///     V, F, px = symcorr.scan(depth, "fixtures/synth/scan/intrinsics.json",
///                             symcorr.read_joints("fixtures/synth/scan/joints.json"))
#[pyfunction]
#[pyo3(signature = (depth, intrinsics, joints, *, discontinuity=0.05, keep_floor=false))]
#[allow(clippy::type_complexity)]
fn scan<'py>(
    py: Python<'py>,
    depth: &Bound<'py, PyAny>,
    intrinsics: &Bound<'py, PyAny>,
    joints: &Bound<'py, PyAny>,
    discontinuity: f64,
    keep_floor: bool,
) -> PyResult<(
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<i64>>,
    Bound<'py, PyArray1<i64>>,
)> {
    let frame = depth_in(depth)?;
    let k = intrinsics_in(intrinsics, frame.width, frame.height)?;
    let skeleton = skeleton_in(joints, "joints")?;
    if !(discontinuity.is_finite() && discontinuity > 0.0) {
        return Err(value_err(format!(
            "discontinuity {discontinuity:?}: expected a finite length > 0 (metres)"
        )));
    }
    let opts = ScanOptions {
        discontinuity_m: discontinuity,
        remove_floor: !keep_floor,
        ..ScanOptions::default()
    };
    symcorr_kinect::scan::check_mirroring(&frame, &k, &skeleton).map_err(kinect_err)?;
    let s = py
        .detach(|| symcorr_kinect::scan_mesh(&frame, &k, Some(&skeleton), &opts))
        .map_err(kinect_err)?;
    symcorr_kinect::scan::check_scale(&s.mesh, &skeleton, &k).map_err(kinect_err)?;
    let ids: Vec<i64> = s.pixel_ids.iter().map(|&p| i64::from(p)).collect();
    Ok((
        vertices_out(py, &s.mesh)?,
        faces_out(py, &s.mesh)?,
        PyArray1::from_vec(py, ids),
    ))
}

/// Reads a 16-bit greyscale PNG depth image (millimetres, 0 = no depth) as ``uint16 (h, w)``,
/// the input of ``scan``.
///
/// Example::
///
///     depth = symcorr.read_depth("fixtures/synth/scan/depth.png")
#[pyfunction]
fn read_depth<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyArray2<u16>>> {
    let f = py
        .detach(|| symcorr_kinect::read_depth_png16(&path))
        .map_err(kinect_err)?;
    let a = Array2::from_shape_vec((f.height as usize, f.width as usize), f.data_mm)
        .map_err(|e| value_err(e.to_string()))?;
    Ok(a.into_pyarray(py))
}

fn depth_in(obj: &Bound<'_, PyAny>) -> PyResult<DepthFrame> {
    let np = obj.py().import("numpy")?;
    let a = np.call_method1("asarray", (obj,)).map_err(|e| {
        value_err(format!(
            "depth: expected a uint16 array of shape (h, w): {e}"
        ))
    })?;
    let name: String = a.getattr("dtype")?.getattr("name")?.extract()?;
    if name != "uint16" {
        return Err(value_err(format!(
            "depth: expected a uint16 array of shape (h, w) in millimetres, got dtype {name}"
        )));
    }
    let shape: Vec<usize> = a.getattr("shape")?.extract()?;
    let [h, w] = shape[..] else {
        return Err(value_err(format!(
            "depth: expected shape (h, w), got {}",
            shape_text(&shape)
        )));
    };
    let a = np.call_method1("ascontiguousarray", (a,))?;
    let r: PyReadonlyArrayDyn<'_, u16> = a.extract()?;
    let data = r.as_slice().map_err(|e| value_err(e.to_string()))?.to_vec();
    let side =
        |x: usize| u32::try_from(x).map_err(|_| value_err(format!("depth: side {x} too large")));
    DepthFrame::new(side(w)?, side(h)?, data).map_err(kinect_err)
}

/// Intrinsics from a dict or a symcorr.intrinsics/1 path, for an image of `width × height`.
fn intrinsics_in(obj: &Bound<'_, PyAny>, width: u32, height: u32) -> PyResult<Intrinsics> {
    let k = if let Ok(d) = obj.cast::<PyDict>() {
        let get = |key: &str| -> PyResult<Option<Bound<'_, PyAny>>> { d.get_item(key) };
        let number = |key: &str| -> PyResult<f64> {
            get(key)?
                .ok_or_else(|| value_err(format!("intrinsics: missing {key:?}")))?
                .extract::<f64>()
                .map_err(|_| value_err(format!("intrinsics: {key:?} must be a number")))
        };
        // As the JSON form: an unknown key (a misspelt "mirrored") is refused, not ignored.
        const KEYS: [&str; 9] = [
            "format",
            "width",
            "height",
            "fx",
            "fy",
            "cx",
            "cy",
            "mirrored",
            "distortion",
        ];
        for key in d.keys() {
            let name: String = key
                .extract()
                .map_err(|_| value_err("intrinsics: keys must be strings"))?;
            if !KEYS.contains(&name.as_str()) {
                return Err(value_err(format!(
                    "intrinsics: unknown key {name:?} (expected {})",
                    KEYS.join(", ")
                )));
            }
        }
        for key in ["width", "height"] {
            if let Some(v) = get(key)? {
                let v: u64 = v
                    .extract()
                    .map_err(|_| value_err(format!("intrinsics: {key:?} must be an integer")))?;
                let image = if key == "width" { width } else { height };
                if v != u64::from(image) {
                    return Err(value_err(format!(
                        "intrinsics: {key} = {v} but the depth image's {key} is {image}"
                    )));
                }
            }
        }
        Intrinsics {
            width,
            height,
            fx: number("fx")?,
            fy: number("fy")?,
            cx: number("cx")?,
            cy: number("cy")?,
            mirroring: match get("mirrored")? {
                None => symcorr_kinect::Mirroring::Mirrored,
                Some(m) => match m.extract::<bool>() {
                    Ok(true) => symcorr_kinect::Mirroring::Mirrored,
                    Ok(false) => symcorr_kinect::Mirroring::Direct,
                    Err(_) => return Err(value_err("intrinsics: \"mirrored\" must be a bool")),
                },
            },
            distortion: match get("distortion")? {
                None => None,
                Some(c) => {
                    let c: Vec<f64> = c.extract().map_err(|_| {
                        value_err("intrinsics: \"distortion\" must be a sequence of numbers")
                    })?;
                    let d = symcorr_kinect::Distortion::from_opencv(&c)
                        .map_err(|e| value_err(format!("intrinsics: {e}")))?;
                    Some(d)
                }
            },
        }
    } else {
        let path: PathBuf = obj.extract().map_err(|_| {
            value_err("intrinsics: expected a dict with fx, fy, cx, cy or a symcorr.intrinsics/1 file path")
        })?;
        let k = Intrinsics::read(&path).map_err(kinect_err)?;
        if (k.width, k.height) != (width, height) {
            return Err(value_err(format!(
                "{}: intrinsics for {}×{} but the depth image is {}×{}",
                path.display(),
                k.width,
                k.height,
                width,
                height
            )));
        }
        k
    };
    k.validate().map_err(kinect_err)?;
    Ok(k)
}

// ------------------------------------------------------------------------------------------
// Recorded sessions
// ------------------------------------------------------------------------------------------

/// One frame of ``symcorr.track``: ``index`` and ``time_s`` in the recording, ``status``
/// (``"ok"`` or ``"skipped"``, with ``reason``), and for a matched frame ``target_of``
/// (``int32 (n,)``: per template vertex the scan vertex it matches, −1 where the frame does not
/// show it), ``confidence`` (``float32 (n,)``), ``posed`` (``float32 (n, 3)``: the template
/// posed onto the frame, camera space, metres), ``scan`` (``(V, F)`` of the frame's scan),
/// ``corrections``, ``coverage``, ``mean_confidence``, ``fit_score``, ``warm``, ``timings`` and
/// ``view_held`` (the fraction of the template points the fit shows the camera that lie on the
/// scan) (``None`` for a skipped frame).
#[pyclass(module = "symcorr", frozen, get_all)]
struct Frame {
    index: usize,
    time_s: f64,
    status: String,
    reason: Option<String>,
    target_of: Py<PyAny>,
    confidence: Py<PyAny>,
    posed: Py<PyAny>,
    scan: Py<PyAny>,
    corrections: Py<PyAny>,
    coverage: Option<f64>,
    mean_confidence: Option<f64>,
    fit_score: Option<f64>,
    warm: Option<bool>,
    timings: Py<PyAny>,
    view_held: Option<f64>,
}

#[pymethods]
impl Frame {
    #[new]
    #[allow(clippy::too_many_arguments)]
    fn new(
        index: usize,
        time_s: f64,
        status: String,
        reason: Option<String>,
        target_of: Py<PyAny>,
        confidence: Py<PyAny>,
        posed: Py<PyAny>,
        scan: Py<PyAny>,
        corrections: Py<PyAny>,
        coverage: Option<f64>,
        mean_confidence: Option<f64>,
        fit_score: Option<f64>,
        warm: Option<bool>,
        timings: Py<PyAny>,
        view_held: Option<f64>,
    ) -> Self {
        Frame {
            index,
            time_s,
            status,
            reason,
            target_of,
            confidence,
            posed,
            scan,
            corrections,
            coverage,
            mean_confidence,
            fit_score,
            warm,
            timings,
            view_held,
        }
    }

    fn __getnewargs__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let items: Vec<Bound<'py, PyAny>> = vec![
            self.index.into_pyobject(py)?.into_any(),
            self.time_s.into_pyobject(py)?.into_any(),
            self.status.clone().into_pyobject(py)?.into_any(),
            self.reason.clone().into_pyobject(py)?,
            self.target_of.bind(py).clone(),
            self.confidence.bind(py).clone(),
            self.posed.bind(py).clone(),
            self.scan.bind(py).clone(),
            self.corrections.bind(py).clone(),
            self.coverage.into_pyobject(py)?,
            self.mean_confidence.into_pyobject(py)?,
            self.fit_score.into_pyobject(py)?,
            self.warm.into_pyobject(py)?.into_any(),
            self.timings.bind(py).clone(),
            self.view_held.into_pyobject(py)?,
        ];
        PyTuple::new(py, items)
    }

    fn __repr__(&self) -> String {
        match &self.reason {
            Some(r) => format!(
                "Frame(index={}, status='skipped', reason={r:?})",
                self.index
            ),
            None => format!(
                "Frame(index={}, status='ok', coverage={:.3})",
                self.index,
                self.coverage.unwrap_or(0.0)
            ),
        }
    }
}

/// The iterator ``symcorr.track`` returns; frames are computed on a worker thread one ahead of
/// the consumer, and the thread stops when the iterator is dropped.
#[pyclass(module = "symcorr")]
struct FrameIterator {
    rx: Mutex<Option<Receiver<TrackedFrame>>>,
    len: usize,
}

#[pymethods]
impl FrameIterator {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __len__(&self) -> usize {
        self.len
    }

    fn __next__(&self, py: Python<'_>) -> PyResult<Frame> {
        // The receiver is taken out for the wait (the GIL released), then put back.
        let taken = self
            .rx
            .lock()
            .map_err(|_| value_err("the tracking thread failed"))?
            .take();
        let next = match taken {
            Some(rx) => {
                let (rx, next) = py.detach(move || {
                    let next = rx.recv().ok();
                    (rx, next)
                });
                if next.is_some() {
                    if let Ok(mut g) = self.rx.lock() {
                        *g = Some(rx);
                    }
                }
                next
            }
            None => None,
        };
        match next {
            Some(r) => frame_out(py, r),
            None => Err(PyStopIteration::new_err(())),
        }
    }
}

fn frame_out(py: Python<'_>, r: TrackedFrame) -> PyResult<Frame> {
    let skipped = |reason: String| Frame {
        index: r.index,
        time_s: r.time_s,
        status: "skipped".into(),
        reason: Some(reason),
        target_of: py.None(),
        confidence: py.None(),
        posed: py.None(),
        scan: py.None(),
        corrections: py.None(),
        coverage: None,
        mean_confidence: None,
        fit_score: None,
        warm: None,
        timings: py.None(),
        view_held: None,
    };
    let m = match r.outcome {
        FrameOutcome::Skipped(reason) => return Ok(skipped(reason)),
        FrameOutcome::Matched(m) => m,
    };
    let timings = PyDict::new(py);
    for (name, s) in &m.timings {
        timings.set_item(name, s)?;
    }
    let scan = (
        vertices_out(py, &m.scan.mesh)?,
        faces_out(py, &m.scan.mesh)?,
    );
    Ok(Frame {
        index: r.index,
        time_s: r.time_s,
        status: "ok".into(),
        reason: None,
        target_of: PyArray1::from_vec(py, m.target_of).into_any().unbind(),
        confidence: PyArray1::from_vec(py, m.confidence).into_any().unbind(),
        posed: match &m.posed {
            Some(p) => rows3(py, p)?.into_any().unbind(),
            None => py.None(),
        },
        scan: scan.into_pyobject(py)?.into_any().unbind(),
        corrections: PyList::new(py, m.corrections.iter().map(|c| c.name()))?
            .into_any()
            .unbind(),
        coverage: Some(m.coverage),
        mean_confidence: Some(m.mean_confidence),
        fit_score: Some(m.fit_score),
        warm: Some(m.warm),
        timings: timings.into_any().unbind(),
        view_held: m.view_held,
    })
}

/// Matches the frames of a recorded session one by one against one template, as
/// ``symcorr track`` does (joints read at each depth frame's time, limb swaps fixed, smoothing,
/// the frame's scan matched warm-started from the previous frame). ``recording`` is a recording
/// folder (intrinsics.json, depth/NNNNNN.png, depth_times.txt); ``joints`` the skeleton
/// tracker's joint log (a path); ``template`` a ``symcorr.Body``, a ``(vertices, faces, joints)``
/// tuple or a ``symcorr.Prepared`` (dense). ``frames`` is an iterable of frame indices (default:
/// all, in order); ``joint_offset`` the seconds added to each depth frame's time before the
/// log is read (default 0), or ``"auto"``: estimated from the frames, as ``symcorr track
/// --joint-offset auto`` does. Yields one ``symcorr.Frame`` per frame; frames are computed on a
/// worker thread, without the GIL. First, as ``symcorr track`` does, a few frames are observed
/// and a joint log that does not belong to the frames (no log frame near any depth frame's
/// time: another clock; its joints on no depth frame: another unit; its bones sticking out of
/// the body the camera sees: another recording or clock, x mirrored, or depth not mirrored as
/// the Kinect SDK's without ``"mirrored": false`` in intrinsics.json) raises ``ValueError``;
/// ``check_log=False`` skips that check. ``intrinsics`` (a dict or a symcorr.intrinsics/1 path,
/// as for ``scan``) replaces the recording's, as ``symcorr track --intrinsics`` does.
///
/// Example::
///
///     rec = "fixtures/synth/recording"
///     for f in symcorr.track(rec, f"{rec}/joints.json", body("s0_rest"), frames=range(0, 60, 10)):
///         print(f.index, f.status, f.coverage)
#[pyfunction]
#[pyo3(signature = (recording, joints, template, *, frames=None, joint_offset=None, check_log=true, intrinsics=None))]
#[allow(clippy::too_many_arguments)]
fn track(
    py: Python<'_>,
    recording: PathBuf,
    joints: PathBuf,
    template: &Bound<'_, PyAny>,
    frames: Option<&Bound<'_, PyAny>>,
    joint_offset: Option<&Bound<'_, PyAny>>,
    check_log: bool,
    intrinsics: Option<&Bound<'_, PyAny>>,
) -> PyResult<FrameIterator> {
    // Seconds (None: 0), or "auto": estimated once the log is read.
    let joint_offset = match joint_offset {
        None => JointOffset::Seconds(0.0),
        Some(o) if o.extract::<String>().is_ok_and(|s| s == "auto") => JointOffset::Auto,
        Some(o) => match o.extract::<f64>() {
            Ok(x) if x.is_finite() => JointOffset::Seconds(x),
            _ => {
                return Err(value_err(format!(
                    "joint_offset {o}: expected a finite number of seconds or \"auto\""
                )))
            }
        },
    };
    let mut source = py
        .detach(|| DepthSource::open(&recording))
        .map_err(kinect_err)?;
    if let Some(obj) = intrinsics {
        let now = source.intrinsics();
        let k = intrinsics_in(obj, now.width, now.height)?;
        source.set_intrinsics(k).map_err(kinect_err)?;
    }
    let len = source.len();
    let list: Vec<usize> = match frames {
        None => (0..len).collect(),
        Some(f) => {
            let mut out = Vec::new();
            for item in f.try_iter()? {
                let i: i64 = item?
                    .extract()
                    .map_err(|_| value_err("frames: expected frame indices (int)"))?;
                match usize::try_from(i) {
                    Ok(i) if i < len => out.push(i),
                    _ => {
                        return Err(value_err(format!(
                            "frames: frame {i} is not in the recording, which has frames 0..{len}"
                        )))
                    }
                }
            }
            out
        }
    };
    let log = py
        .detach(|| symcorr_kinect::read_joints(&joints))
        .map_err(kinect_err)?;
    let track =
        JointTrack::new(log, 0.0).map_err(|e| value_err(format!("{}: {e}", joints.display())))?;
    let (pipeline, prepared) = if let Ok(p) = template.cast::<Prepared>() {
        let p = p.get();
        if p.pipeline.options.mode != Mode::Dense {
            return Err(value_err(
                "template: track needs a dense Prepared (dense=True)",
            ));
        }
        (p.pipeline.clone(), p.template.clone())
    } else {
        let pipeline = pipeline_for("articulated", true, 1, false)?;
        let body = body_in(template, "template")?;
        let prepared = py
            .detach(|| pipeline.prepare((*body.mesh).clone(), &body.skeleton))
            .map_err(|e| py_err(e, Some("template")))?;
        (pipeline, Arc::new(prepared))
    };
    let joint_offset = py
        .detach(|| joint_offset.resolve(&mut source, &track))
        .map_err(|e| value_err(format!("joint_offset \"auto\": {e}")))?;
    let options = TrackOptions {
        joint_offset_s: joint_offset,
        ..TrackOptions::default()
    };
    if check_log {
        // As `symcorr track`: a log that does not belong to the frames is refused first.
        let check = py.detach(|| {
            symcorr::track::log_check::check_log(
                &pipeline,
                &prepared,
                &mut source,
                &track,
                &options,
                &list,
                symcorr::track::log_check::LOG_CHECK_FRAMES,
            )
        });
        check.verdict().map_err(|e| {
            value_err(format!(
                "{}: {e} (check_log=False runs anyway)",
                joints.display()
            ))
        })?;
    }
    let n = list.len();
    let (tx, rx) = sync_channel::<TrackedFrame>(1);
    let intrinsics = *source.intrinsics();
    std::thread::Builder::new()
        .name("symcorr-track".into())
        .spawn(move || {
            let mut tracker = Tracker::new(&pipeline, &prepared, intrinsics, track, options);
            // Observed one frame ahead of the match, as `symcorr track` runs; a send fails
            // once the iterator is dropped, which ends the run.
            let _ = tracker.run(&mut source, &list, &AtomicBool::new(false), |f| tx.send(f));
        })
        .map_err(|e| PyOSError::new_err(format!("cannot start the tracking thread: {e}")))?;
    Ok(FrameIterator {
        rx: Mutex::new(Some(rx)),
        len: n,
    })
}

// ------------------------------------------------------------------------------------------
// The module
// ------------------------------------------------------------------------------------------

/// Skeleton-aware human shape correspondence: dense matches between body meshes and depth
/// scans that never map a left limb onto a right one.
///
/// Functions: read_mesh, read_joints, read_depth, label, match, scan, track; classes: Body, Prepared,
/// Correspondence, Labels, Frame. Arrays are numpy arrays (vertices float64 (n, 3), faces
/// int (m, 3), joints a dict name → xyz or a (20, 3) array in Kinect v1 order, JOINT_NAMES).
/// Errors: OSError for files, ValueError for bad input, with the messages of the symcorr
/// command line.
#[pymodule(name = "symcorr")]
fn symcorr_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_function(wrap_pyfunction!(read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(read_joints, m)?)?;
    m.add_function(wrap_pyfunction!(label, m)?)?;
    m.add_function(wrap_pyfunction!(match_, m)?)?;
    m.add_function(wrap_pyfunction!(scan, m)?)?;
    m.add_function(wrap_pyfunction!(read_depth, m)?)?;
    m.add_function(wrap_pyfunction!(track, m)?)?;
    m.add_class::<Body>()?;
    m.add_class::<Prepared>()?;
    m.add_class::<Correspondence>()?;
    m.add_class::<Labels>()?;
    m.add_class::<Frame>()?;
    m.add_class::<FrameIterator>()?;
    m.add(
        "JOINT_NAMES",
        PyTuple::new(py, Joint::ALL.iter().map(|j| j.name()))?,
    )?;
    m.add(
        "SEGMENT_NAMES",
        PyTuple::new(py, Segment::ALL.iter().map(|s| s.name()))?,
    )?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add(
        "__all__",
        PyTuple::new(
            py,
            [
                "read_mesh",
                "read_joints",
                "label",
                "match",
                "scan",
                "read_depth",
                "track",
                "Body",
                "Prepared",
                "Correspondence",
                "Labels",
                "Frame",
                "JOINT_NAMES",
                "SEGMENT_NAMES",
            ],
        )?,
    )?;
    Ok(())
}
