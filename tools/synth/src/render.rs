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
//! Sensor realism ([`Realism`]), each part switchable, all random parts from seeded ChaCha8
//! streams (bit-for-bit reproducible):
//! * axial noise: Gaussian with σ_z = c · z² (Khoshelham & Elberink 2012: the random error grows
//!   with the square of the distance); c = 1.5·10⁻³ m⁻¹ in [`Realism::kinect`], their fitted
//!   1.425·10⁻³ m⁻¹ in [`Realism::kinect_v1`];
//! * quantisation: the Kinect measures disparity d = f·b/z in steps of 1/8 pixel (b = 7.5 cm
//!   baseline, f the focal length at its native 640 pixels across, whatever size the image is
//!   delivered at: [`KINECT_NATIVE_WIDTH`]), so depth is quantised in steps of z²/(8·f·b)
//!   (~2.9 mm at 1 m, ~2.2 cm at 2.8 m — Khoshelham & Elberink's 2.85·10⁻³·z²);
//! * missing pixels at grazing angles (angle between the viewing ray and the surface normal
//!   above `grazing_deg`) and at depth edges (a pixel whose 4-neighbour differs by more than
//!   4 cm is dropped with probability ½);
//! * ([`Realism::kinect_v1`]) the IR shadow: the projector sits 7.5 cm to the sensor's right
//!   (−x) of the depth camera, so a surface point it cannot light — one hidden from the projector
//!   by a nearer surface — gives no reading; found with a depth map rendered from the projector
//!   (a shadow map), so the band's side (+x of occluding edges) and width
//!   (f·b·(1/z_near − 1/z_far) pixels) follow from the geometry;
//! * ([`Realism::kinect_v1`]) flying pixels at silhouettes: a pixel whose 3×3 neighbourhood
//!   spans more than `silhouette_jump_m` is either lost (probability ½) or reads a depth mixed
//!   between the nearest and farthest surface of its neighbourhood (the stereo-matching window
//!   straddles both);
//! * ([`Realism::kinect_v1`]) random dropout: each reading is lost with probability
//!   `random_dropout` (speckle the matcher fails on);
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

/// Width, pixels, of the image a Kinect v1 computes its disparity on (its depth stream's
/// VGA mode; QVGA and smaller streams are that image scaled down).
pub const KINECT_NATIVE_WIDTH: f64 = 640.0;

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
    /// Axial Gaussian noise σ = c · z² (c = `axial_coeff`).
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
    /// The axial noise coefficient c in m⁻¹; `None` = 1.5·10⁻³ (the `kinect` preset's).
    pub axial_coeff: Option<f64>,
    /// Flying pixels and dropouts where a pixel's 3×3 neighbourhood spans more than this depth
    /// (metres); `None` = off.
    pub silhouette_jump_m: Option<f64>,
    /// Probability that any reading is lost (0 = off).
    pub random_dropout: f64,
    /// No reading where the projector (7.5 cm to the sensor's right) cannot light the surface.
    pub ir_shadow: bool,
}

/// [`Realism::axial_coeff`] when unset, m⁻¹.
pub const KINECT_AXIAL_COEFF: f64 = 1.5e-3;

/// Khoshelham & Elberink's (2012) fitted axial noise coefficient of the Kinect v1, m⁻¹
/// (σ_z = 1.425·10⁻³ · z²).
pub const KINECT_V1_AXIAL_COEFF: f64 = 1.425e-3;

/// Where [`Realism::kinect_v1`] puts flying pixels: neighbourhoods spanning more than 8 cm.
pub const KINECT_V1_SILHOUETTE_JUMP_M: f64 = 0.08;

/// [`Realism::kinect_v1`]'s random dropout.
pub const KINECT_V1_RANDOM_DROPOUT: f64 = 0.01;

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
            ..Realism::default()
        }
    }

    /// At least as harsh as a real Kinect v1: [`Realism::kinect`] with Khoshelham & Elberink's
    /// noise coefficient (1.425·10⁻³), plus the IR shadow, flying pixels at silhouettes
    /// (neighbourhoods spanning > 8 cm) and 1 % random dropout.
    pub fn kinect_v1(seed: u64) -> Realism {
        Realism {
            axial_coeff: Some(KINECT_V1_AXIAL_COEFF),
            silhouette_jump_m: Some(KINECT_V1_SILHOUETTE_JUMP_M),
            random_dropout: KINECT_V1_RANDOM_DROPOUT,
            ir_shadow: true,
            ..Realism::kinect(seed)
        }
    }

    /// Parses a preset name: `ideal`, `kinect` or `kinect-v1`.
    pub fn preset(name: &str, seed: u64) -> Option<Realism> {
        match name {
            "ideal" => Some(Realism {
                seed,
                ..Realism::default()
            }),
            "kinect" => Some(Realism::kinect(seed)),
            "kinect-v1" => Some(Realism::kinect_v1(seed)),
            _ => None,
        }
    }

    /// Whether any of the [`Realism::kinect_v1`] terms beyond [`Realism::kinect`]'s is set.
    pub fn has_v1_terms(&self) -> bool {
        self.axial_coeff.is_some()
            || self.silhouette_jump_m.is_some()
            || self.random_dropout > 0.0
            || self.ir_shadow
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

/// Z-buffers the triangles of `cam` (points in a camera frame with intrinsics `k`) over pixel
/// centres; `on_nearer(pixel, z, triangle, corners, unit normal, pixel centre)` is called each
/// time a pixel gets a nearer surface.
fn rasterise(
    cam: &[V3],
    triangles: &[[u32; 3]],
    k: &Intrinsics,
    zbuf: &mut [f64],
    mut on_nearer: impl FnMut(usize, f64, &[u32; 3], [Point3<f64>; 3], Vector3<f64>, [f64; 2]),
) {
    let (w, h) = (k.width as usize, k.height as usize);
    for t in triangles {
        let p = t.map(|v| cam[v as usize]);
        if p.iter().any(|q| q[2] <= NEAR_M) {
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
                    on_nearer(i, z, t, [p0, p1, p2], n, q);
                }
            }
        }
    }
}

/// Surfaces nearer than this to the camera are not rendered, metres.
const NEAR_M: f64 = 0.05;

/// How far in front of a point a surface must be, as seen from the projector, to shadow it
/// (metres): absorbs the shadow map's sampling on the point's own surface.
const SHADOW_TOLERANCE_M: f64 = 0.005;

/// Where the IR projector cannot light the point each pixel sees (`zbuf`, camera depth).
///
/// The projector is the camera moved by [`KINECT_BASELINE_M`] along −x (the sensor's right; from
/// the front the Kinect v1 shows, left to right, projector, colour camera, depth camera) with
/// the same orientation, so a point keeps its depth z in the projector's frame. The mesh is
/// rendered from there into a depth map with the camera's intrinsics; a pixel is shadowed when
/// all four projector pixels around its point's projection see a surface nearer than the point
/// by more than [`SHADOW_TOLERANCE_M`] (the point's own surface straddles them otherwise).
/// Points outside the projector's image count as lit.
fn projector_shadow(cam: &[V3], triangles: &[[u32; 3]], k: &Intrinsics, zbuf: &[f64]) -> Vec<bool> {
    let (w, h) = (k.width as usize, k.height as usize);
    let shift = Vector3::new(KINECT_BASELINE_M, 0.0, 0.0);
    let proj: Vec<V3> = cam
        .iter()
        .map(|&p| (Vector3::from(p) + shift).into())
        .collect();
    let mut pz = vec![f64::INFINITY; w * h];
    rasterise(&proj, triangles, k, &mut pz, |_, _, _, _, _, _| {});
    let mut shadow = vec![false; w * h];
    for (i, s) in shadow.iter_mut().enumerate() {
        let z = zbuf[i];
        if !z.is_finite() {
            continue;
        }
        let x = k.unproject((i % w) as f64, (i / w) as f64, z).coords + shift;
        let [up, vp] = k.project(&x.into());
        let (u0, v0) = (up.floor(), vp.floor());
        if u0 < 0.0 || v0 < 0.0 || u0 + 1.0 >= w as f64 || v0 + 1.0 >= h as f64 {
            continue;
        }
        let (u0, v0) = (u0 as usize, v0 as usize);
        *s = [(0, 0), (1, 0), (0, 1), (1, 1)]
            .iter()
            .all(|&(du, dv)| pz[(v0 + dv) * w + u0 + du] < z - SHADOW_TOLERANCE_M);
    }
    shadow
}

/// Salt of the kinect-v1 terms' random stream (its seed is the realism seed XOR this).
const V1_STREAM_SALT: u64 = 0x6b69_6e65_6374_7631;

/// The pixel's vertex id is kept when its flying depth stays this close to its surface, metres.
const FLYING_KEEP_ID_M: f64 = 0.02;

/// Flying pixels and dropouts at silhouettes: every pixel whose 3×3 neighbourhood in the ideal
/// depth `zbuf` spans more than `jump` (or borders a pixel that sees nothing) is marked in
/// `silhouette`; with probability ½ it is lost, otherwise it reads z_near + α·(z_far − z_near),
/// α uniform in [0, 1), the nearest and farthest depths of its neighbourhood — the correlation
/// window of the Kinect's stereo matcher straddles both surfaces. A pixel with no farther
/// surface to mix with (the neighbourhood sees nothing there) is lost. A flying pixel keeps its
/// vertex id only while within [`FLYING_KEEP_ID_M`] of its own surface.
fn flying_pixels(
    zbuf: &[f64],
    (w, h): (usize, usize),
    jump: f64,
    zmeas: &mut [f64],
    vid: &mut [u32],
    silhouette: &mut [bool],
    rng: &mut ChaCha8Rng,
) {
    for v in 0..h {
        for u in 0..w {
            let i = v * w + u;
            if !zbuf[i].is_finite() {
                continue;
            }
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for vv in v.saturating_sub(1)..=(v + 1).min(h - 1) {
                for uu in u.saturating_sub(1)..=(u + 1).min(w - 1) {
                    let z = zbuf[vv * w + uu];
                    lo = lo.min(z);
                    hi = hi.max(z);
                }
            }
            if hi - lo <= jump {
                continue;
            }
            silhouette[i] = true;
            let lost = unit_f64(rng) < 0.5;
            let alpha = unit_f64(rng);
            if !zmeas[i].is_finite() {
                continue; // already shadowed
            }
            if lost || !hi.is_finite() {
                zmeas[i] = f64::INFINITY;
                vid[i] = NO_VERTEX;
                continue;
            }
            let z = lo + alpha * (hi - lo);
            if (z - zbuf[i]).abs() > FLYING_KEEP_ID_M {
                vid[i] = NO_VERTEX;
            }
            zmeas[i] = z;
        }
    }
}

/// The native camera whose image `camera`'s is a scaled-down stream of: the same pose and
/// field of view at [`KINECT_NATIVE_WIDTH`] pixels across, its pixel (s·u + s/2, s·v + s/2) on
/// the ray of the small image's pixel (u, v) (s = 640 / width). `None` when the image is
/// native or its width does not divide 640.
fn native_camera(camera: &Camera) -> Option<Camera> {
    let k = &camera.intrinsics;
    let native = KINECT_NATIVE_WIDTH as u32;
    let s = native / k.width.max(1);
    if s < 2 || s * k.width != native {
        return None;
    }
    let (scale, offset) = (f64::from(s), f64::from(s / 2));
    Some(Camera {
        intrinsics: Intrinsics {
            width: k.width * s,
            height: k.height * s,
            fx: k.fx * scale,
            fy: k.fy * scale,
            cx: k.cx * scale + offset,
            cy: k.cy * scale + offset,
            ..*k
        },
        ..*camera
    })
}

/// The native rendering `r` delivered at the size of `k`: one native pixel per small pixel,
/// the one on its ray ([`native_camera`]), as a sensor's scaled-down stream skips pixels.
fn decimate(r: &Rendering, k: &Intrinsics) -> Rendering {
    let (w, h) = (k.width as usize, k.height as usize);
    let (nw, s) = (r.width as usize, r.width as usize / w.max(1));
    let mut depth_mm = Vec::with_capacity(w * h);
    let mut vertex_id = Vec::with_capacity(w * h);
    for v in 0..h {
        for u in 0..w {
            let i = (v * s + s / 2) * nw + u * s + s / 2;
            depth_mm.push(r.depth_mm[i]);
            vertex_id.push(r.vertex_id[i]);
        }
    }
    Rendering {
        width: k.width,
        height: k.height,
        depth_mm,
        vertex_id,
    }
}

/// Renders `mesh` (world frame) with `camera`. An image whose width divides 640 (320, 160) is
/// rendered at the native 640 pixels across and delivered one pixel in every s × s block
/// (`native_camera`): a Kinect's artefacts — silhouette dropout, flying pixels, the
/// projector's shadow, speckle dropout — are one or two *native* pixels wide, and its smaller
/// streams are the native image scaled down, so they lose a thinner band along a silhouette
/// than the same terms drawn at the small image's pixel size would
/// (docs/decisions/2026-12-04-native-depth-steps.md). `stream` separates the noise of
/// different frames that share a seed.
pub fn render(mesh: &TriMesh, camera: &Camera, realism: &Realism, stream: u64) -> Rendering {
    let k = &camera.intrinsics;
    if let Some(native) = native_camera(camera) {
        return decimate(&render(mesh, &native, realism, stream), k);
    }
    let (w, h) = (k.width as usize, k.height as usize);
    let to_cam = camera.world_to_camera();
    let cam: Vec<V3> = mesh.positions.iter().map(|&p| to_cam.apply(p)).collect();
    let near = NEAR_M;
    let mut zbuf = vec![f64::INFINITY; w * h];
    let mut vid = vec![NO_VERTEX; w * h];
    let mut cos_view = vec![1.0f64; w * h];
    rasterise(
        &cam,
        &mesh.triangles,
        k,
        &mut zbuf,
        |i, z, t, corners, n, q| {
            let x = k.unproject(q[0], q[1], z);
            let mut best = (0, f64::INFINITY);
            for (c, pc) in corners.iter().enumerate() {
                let d = (x - pc).norm_squared();
                if d < best.1 {
                    best = (c, d);
                }
            }
            vid[i] = t[best.0];
            cos_view[i] = n.dot(&normalize(x.coords)).abs();
        },
    );
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
    // The depth the sensor measures before noise; the kinect-v1 terms draw from their own
    // stream so that the other presets' noise stays as it was.
    let mut zmeas = zbuf.clone();
    let mut silhouette = vec![false; w * h];
    if realism.has_v1_terms() {
        let mut rng_v1 = ChaCha8Rng::seed_from_u64(realism.seed ^ V1_STREAM_SALT);
        rng_v1.set_stream(stream);
        if realism.ir_shadow {
            let shadow = projector_shadow(&cam, &mesh.triangles, k, &zbuf);
            for (i, _) in shadow.iter().enumerate().filter(|s| *s.1) {
                zmeas[i] = f64::INFINITY;
                vid[i] = NO_VERTEX;
            }
        }
        if let Some(jump) = realism.silhouette_jump_m {
            flying_pixels(
                &zbuf,
                (w, h),
                jump,
                &mut zmeas,
                &mut vid,
                &mut silhouette,
                &mut rng_v1,
            );
        }
        if realism.random_dropout > 0.0 {
            for i in 0..w * h {
                if zmeas[i].is_finite() && unit_f64(&mut rng_v1) < realism.random_dropout {
                    zmeas[i] = f64::INFINITY;
                    vid[i] = NO_VERTEX;
                }
            }
        }
    }
    let axial_coeff = realism.axial_coeff.unwrap_or(KINECT_AXIAL_COEFF);
    // The sensor matches its speckle pattern at its native resolution, whatever size the
    // depth image is delivered at: the disparity's focal length is that of the same field of
    // view at 640 pixels across (this image's own when it is native or rendered natively).
    let fb = k.fx * (KINECT_NATIVE_WIDTH / k.width as f64) * KINECT_BASELINE_M;
    let mut depth = vec![0u16; w * h];
    for i in 0..w * h {
        let mut z = zmeas[i];
        if !z.is_finite() {
            vid[i] = NO_VERTEX;
            continue;
        }
        if let Some(max_deg) = realism.grazing_deg {
            if cos_view[i] < max_deg.to_radians().cos() {
                vid[i] = NO_VERTEX;
                continue;
            }
        }
        if realism.axial_noise {
            z += axial_coeff * z * z * standard_normal(&mut rng);
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
                if depth[i] == 0 || silhouette[i] {
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
