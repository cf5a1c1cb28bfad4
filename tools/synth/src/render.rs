//! The virtual Kinect: a posed body seen by a Kinect v1 depth camera.
//!
//! Projection goes through [`symcorr_kinect::Intrinsics::project`] /
//! [`unproject`](symcorr_kinect::Intrinsics::unproject) — the single definition of Kinect
//! camera space (right-handed, metres, +x to the sensor's left, +y up, +z into the scene) and of
//! the pixel grid. The camera is placed in the body (world) frame by a position and a look-at
//! point; world "up" is +y.
//!
//! Rasterisation is a z-buffer over pixel centres with perspective-correct depth (1/z is affine
//! in screen space). Each covered pixel stores the depth z in millimetres (u16, rounded) and the
//! id of the mesh vertex nearest to the surface point it sees (among its triangle's corners).
//!
//! Sensor realism ([`Realism`]), each part switchable, all random parts from one seeded ChaCha8
//! stream (bit-for-bit reproducible):
//! * axial noise: Gaussian with σ_z = 1.5·10⁻³ m⁻¹ · z² (Khoshelham & Elberink 2012: the random
//!   error grows with the square of the distance, ~1.5 mm at 1 m to ~4 cm at 5 m);
//! * quantisation: the Kinect measures disparity d = f·b/z in steps of 1/8 pixel (b = 7.5 cm
//!   baseline, f = fx), so depth is quantised in steps of z²/(8·f·b) (~2.9 mm at 1 m);
//! * missing pixels at grazing angles (angle between the viewing ray and the surface normal
//!   above `grazing_deg`) and at depth edges (a pixel whose 4-neighbour differs by more than
//!   4 cm is dropped with probability ½ — the projector shadow and the flying pixels there);
//! * a floor plane at the body's lowest point and a wall behind the subject (1 m beyond the
//!   look-at point, facing the camera), both with vertex id "none".

use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use symcorr_kinect::Intrinsics;
use symcorr_mesh::TriMesh;

use nalgebra::{Matrix3, Point2, Point3, Vector3};

use crate::math::{normalize, Rigid, V3};
use crate::noise::standard_normal;
use crate::poses::unit_f64;

/// Vertex id of pixels that see no body vertex (background, floor, wall, missing).
pub const NO_VERTEX: u32 = u32::MAX;

/// Kinect v1 stereo baseline (projector–camera), metres.
pub const KINECT_BASELINE_M: f64 = 0.075;

/// A depth camera placed in the world (body) frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Optical centre, world frame, metres.
    pub position: V3,
    /// A point on the optical axis.
    pub look_at: V3,
    /// Intrinsics (default Kinect v1).
    pub intrinsics: Intrinsics,
}

impl Camera {
    /// A Kinect v1 at `position` looking at `look_at`.
    pub fn kinect_v1(position: V3, look_at: V3) -> Camera {
        Camera {
            position,
            look_at,
            intrinsics: Intrinsics::kinect_v1(),
        }
    }

    /// World → Kinect camera space: +z along the viewing direction, +y as close to world up (+y)
    /// as possible, +x = y × z (the sensor's left).
    pub fn world_to_camera(&self) -> Rigid {
        let position = Vector3::from(self.position);
        let z = normalize(Vector3::from(self.look_at) - position);
        let up = if Vector3::y().cross(&z).iter().all(|c| c.abs() < 1e-9) {
            Vector3::z()
        } else {
            Vector3::y()
        };
        let x = normalize(up.cross(&z));
        let y = z.cross(&x);
        // Rows are the camera axes in world coordinates.
        let r = Matrix3::from_rows(&[x.transpose(), y.transpose(), z.transpose()]);
        let t = Vector3::new(-x.dot(&position), -y.dot(&position), -z.dot(&position));
        Rigid { r, t }
    }
}

/// Switchable sensor realism (all off by default: an ideal depth camera).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Realism {
    /// Axial Gaussian noise σ = 1.5e-3 · z².
    pub axial_noise: bool,
    /// Disparity quantisation (1/8 px).
    pub quantise: bool,
    /// Drop pixels seen at more than this angle from the surface normal (degrees); `None` keeps all.
    pub grazing_deg: Option<f64>,
    /// Drop pixels at depth edges (probability ½ within one pixel of a > 4 cm jump).
    pub edge_dropout: bool,
    /// Floor plane at the body's lowest point.
    pub floor: bool,
    /// Wall behind the subject.
    pub wall: bool,
    /// Seed of the noise stream.
    pub seed: u64,
}

impl Realism {
    /// Everything on: noise, quantisation, dropout at > 78°, edge dropout, floor and wall.
    pub fn kinect(seed: u64) -> Realism {
        Realism {
            axial_noise: true,
            quantise: true,
            grazing_deg: Some(78.0),
            edge_dropout: true,
            floor: true,
            wall: true,
            seed,
        }
    }
}

/// A rendered depth frame with per-pixel ground truth.
#[derive(Debug, Clone, PartialEq)]
pub struct Rendering {
    /// Width and height in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Depth z per pixel in millimetres, row-major; 0 = no measurement.
    pub depth_mm: Vec<u16>,
    /// Nearest body vertex per pixel ([`NO_VERTEX`] where no body is seen).
    pub vertex_id: Vec<u32>,
}

impl Rendering {
    /// The depth image as a `symcorr_kinect::DepthFrame`.
    pub fn depth_frame(&self) -> symcorr_kinect::DepthFrame {
        symcorr_kinect::DepthFrame {
            width: self.width,
            height: self.height,
            data_mm: self.depth_mm.clone(),
        }
    }

    /// Vertex ids as a 16-bit image (`id + 1`, 0 = none) — fits the 13,380-vertex body.
    pub fn vertex_id_frame(&self) -> symcorr_kinect::DepthFrame {
        symcorr_kinect::DepthFrame {
            width: self.width,
            height: self.height,
            data_mm: self
                .vertex_id
                .iter()
                .map(|&v| {
                    if v == NO_VERTEX {
                        0
                    } else {
                        (v + 1).min(u16::MAX as u32) as u16
                    }
                })
                .collect(),
        }
    }
}

/// Twice the signed area of the image-plane triangle `a, b, p`.
fn edge(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> f64 {
    let a = Point2::from(a);
    (Point2::from(b) - a).perp(&(Point2::from(p) - a))
}

/// Renders `mesh` (world frame) with `camera`. `stream` separates the noise of different frames
/// that share a seed.
pub fn render(mesh: &TriMesh, camera: &Camera, realism: &Realism, stream: u64) -> Rendering {
    let k = &camera.intrinsics;
    let (w, h) = (k.width as usize, k.height as usize);
    let to_cam = camera.world_to_camera();
    let cam: Vec<V3> = mesh.positions.iter().map(|&p| to_cam.apply(p)).collect();
    let near = 0.05;
    let mut zbuf = vec![f64::INFINITY; w * h];
    let mut vid = vec![NO_VERTEX; w * h];
    let mut cos_view = vec![1.0f64; w * h];
    for t in &mesh.triangles {
        let p = t.map(|v| cam[v as usize]);
        if p.iter().any(|q| q[2] <= near) {
            continue;
        }
        let s = p.map(|q| k.project(&q.into()));
        let area = edge(s[0], s[1], s[2]);
        if area.abs() < 1e-12 {
            continue;
        }
        let umin = s
            .iter()
            .map(|q| q[0])
            .fold(f64::INFINITY, f64::min)
            .ceil()
            .max(0.0) as usize;
        let umax = s
            .iter()
            .map(|q| q[0])
            .fold(f64::NEG_INFINITY, f64::max)
            .floor();
        let vmin = s
            .iter()
            .map(|q| q[1])
            .fold(f64::INFINITY, f64::min)
            .ceil()
            .max(0.0) as usize;
        let vmax = s
            .iter()
            .map(|q| q[1])
            .fold(f64::NEG_INFINITY, f64::max)
            .floor();
        if umax < 0.0 || vmax < 0.0 {
            continue;
        }
        let umax = (umax as usize).min(w - 1);
        let vmax = (vmax as usize).min(h - 1);
        let [p0, p1, p2] = p.map(Point3::from);
        let n = normalize((p1 - p0).cross(&(p2 - p0)));
        for v in vmin..=vmax {
            for u in umin..=umax {
                let q = [u as f64, v as f64];
                let b = [
                    edge(s[1], s[2], q) / area,
                    edge(s[2], s[0], q) / area,
                    edge(s[0], s[1], q) / area,
                ];
                if b.iter().any(|&x| x < 0.0) {
                    continue;
                }
                let inv_z = Vector3::from(b)
                    .component_div(&Vector3::new(p0.z, p1.z, p2.z))
                    .sum();
                let z = 1.0 / inv_z;
                let i = v * w + u;
                if z < zbuf[i] {
                    zbuf[i] = z;
                    let x = k.unproject(q[0], q[1], z);
                    let mut best = (0, f64::INFINITY);
                    for (c, pc) in [p0, p1, p2].iter().enumerate() {
                        let d = (x - pc).norm_squared();
                        if d < best.1 {
                            best = (c, d);
                        }
                    }
                    vid[i] = t[best.0];
                    cos_view[i] = n.dot(&normalize(x.coords)).abs();
                }
            }
        }
    }
    // Background planes (world frame), intersected with each pixel's ray.
    let rt = to_cam.r.transpose();
    let mut planes: Vec<(Vector3<f64>, f64)> = Vec::new(); // (unit normal n, offset c): n·x = c
    if realism.floor {
        let floor_y = mesh
            .positions
            .iter()
            .map(|p| p[1])
            .fold(f64::INFINITY, f64::min);
        planes.push((Vector3::y(), floor_y));
    }
    if realism.wall {
        let mut f = Vector3::from(camera.look_at) - Vector3::from(camera.position);
        f.y = 0.0;
        let f = normalize(f);
        let c = f.dot(&Vector3::from(camera.look_at)) + 1.0;
        planes.push((f, c));
    }
    if !planes.is_empty() {
        for v in 0..h {
            for u in 0..w {
                let dc = k.unproject(u as f64, v as f64, 1.0).coords; // z = 1
                let dw = rt * dc;
                for &(n, c) in &planes {
                    let denom = n.dot(&dw);
                    if denom.abs() < 1e-12 {
                        continue;
                    }
                    let t = (c - n.dot(&Vector3::from(camera.position))) / denom;
                    let i = v * w + u;
                    if t > near && t < zbuf[i] {
                        zbuf[i] = t;
                        vid[i] = NO_VERTEX;
                        cos_view[i] = (denom / dw.norm()).abs();
                    }
                }
            }
        }
    }
    let mut rng = ChaCha8Rng::seed_from_u64(realism.seed);
    rng.set_stream(stream);
    let fb = k.fx * KINECT_BASELINE_M;
    let mut depth = vec![0u16; w * h];
    for i in 0..w * h {
        let mut z = zbuf[i];
        if !z.is_finite() {
            continue;
        }
        if let Some(max_deg) = realism.grazing_deg {
            if cos_view[i] < max_deg.to_radians().cos() {
                vid[i] = NO_VERTEX;
                continue;
            }
        }
        if realism.axial_noise {
            z += 1.5e-3 * z * z * standard_normal(&mut rng);
        }
        if realism.quantise && z > 0.0 {
            let d = (fb / z * 8.0).round() / 8.0;
            z = if d > 0.0 { fb / d } else { 0.0 };
        }
        let mm = (z * 1000.0).round();
        if mm >= 1.0 && mm <= u16::MAX as f64 {
            depth[i] = mm as u16;
        } else {
            vid[i] = NO_VERTEX;
        }
    }
    if realism.edge_dropout {
        // Edges are found on the ideal depth, so that noise alone does not create them.
        for v in 0..h {
            for u in 0..w {
                let i = v * w + u;
                if depth[i] == 0 {
                    continue;
                }
                let jump = [(0i64, 1i64), (0, -1), (1, 0), (-1, 0)]
                    .iter()
                    .any(|&(du, dv)| {
                        let (uu, vv) = (u as i64 + du, v as i64 + dv);
                        if uu < 0 || vv < 0 || uu >= w as i64 || vv >= h as i64 {
                            return false;
                        }
                        let o = zbuf[vv as usize * w + uu as usize];
                        !o.is_finite() || (o - zbuf[i]).abs() > 0.04
                    });
                if jump && unit_f64(&mut rng) < 0.5 {
                    depth[i] = 0;
                    vid[i] = NO_VERTEX;
                }
            }
        }
    }
    Rendering {
        width: k.width,
        height: k.height,
        depth_mm: depth,
        vertex_id: vid,
    }
}
