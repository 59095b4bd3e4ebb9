//! The motion blur of an exposure: each pixel's ground point (from its
//! depth; far away for the background) seen from the exposure's start to
//! its end pose, the radiance sampled along that image segment and
//! averaged (a static scene's blur; occlusions during the exposure are
//! ignored).
//!
//! The geometry of four pixels at a time (three rigid motions and two
//! projections each) runs on the processor's 256-bit vectors where it has
//! them (x86-64 with AVX2, found at run time), the sampling per pixel.
//! Every lane does nalgebra's operations on points in nalgebra's order,
//! so the blurred radiance is the same float either way.

use std::ops::{Add, Div, Mul, Sub};

use gpodo_traits::CameraParams;
use nalgebra::Isometry3;
use rayon::prelude::*;

use super::convert::{as_f64, truncate};

/// Depths are capped here (m): the background is far, not infinite.
const FAR_M: f64 = 1e3;

/// Samples along a pixel's segment are at most this many plus one.
const MAX_STEPS: usize = 64;

/// Float arithmetic on one value or on a vector of them.
trait Arith:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// Every lane `x`.
    fn splat(&self, x: f64) -> Self;
    /// The square root, correctly rounded.
    fn sqrt(self) -> Self;
}

impl Arith for f64 {
    #[inline(always)]
    fn splat(&self, x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
}

/// A rigid motion's parts: the rotation quaternion's vector part and
/// scalar, and the translation.
#[derive(Debug, Clone, Copy)]
struct Rigid {
    q: [f64; 3],
    w: f64,
    t: [f64; 3],
}

impl Rigid {
    fn of(iso: &Isometry3<f64>) -> Self {
        let q = iso.rotation.quaternion();
        let t = iso.translation.vector;
        Self {
            q: [q.i, q.j, q.k],
            w: q.w,
            t: [t.x, t.y, t.z],
        }
    }

    /// `iso * p` as nalgebra computes it: the unit quaternion's rotation
    /// `v + w t + q × t` with `t = 2 q × v`, then the translation.
    #[inline(always)]
    fn apply<F: Arith>(&self, p: [F; 3]) -> [F; 3] {
        // No closures here: they would not be inlined into the vector
        // code's target features.
        let one = p[0];
        let q = [
            one.splat(self.q[0]),
            one.splat(self.q[1]),
            one.splat(self.q[2]),
        ];
        let (w, two) = (one.splat(self.w), one.splat(2.0));
        let t = cross(q, p);
        let t = [t[0] * two, t[1] * two, t[2] * two];
        let c = cross(q, t);
        [
            t[0] * w + c[0] + p[0] + one.splat(self.t[0]),
            t[1] * w + c[1] + p[1] + one.splat(self.t[1]),
            t[2] * w + c[2] + p[2] + one.splat(self.t[2]),
        ]
    }
}

/// `a × b` as nalgebra computes it.
#[inline(always)]
fn cross<F: Arith>(a: [F; 3], b: [F; 3]) -> [F; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// One exposure of one view: the camera, the view's radiance and depth,
/// where the camera is at the middle of the exposure, and the inverses of
/// its start and end poses.
struct Exposure<'a> {
    camera: &'a CameraParams,
    width: usize,
    height: usize,
    radiance: &'a [f32],
    depth_m: &'a [f32],
    world_from_camera: Rigid,
    start_from_world: Rigid,
    end_from_world: Rigid,
    /// `(u − c_x) / f` of every column.
    ray_x: Vec<f64>,
}

/// A pixel's path over the exposure: where its ground point is seen at
/// the start (`u0, v0`) and at the end (`u1, v1`), the path's length
/// (pixels), and the point's depth at either end.
struct Path<F> {
    u0: F,
    v0: F,
    u1: F,
    v1: F,
    length: F,
    z0: F,
    z1: F,
}

/// The radiance of `camera`'s view (`radiance` and `depth_m`, row-major,
/// `width` wide) integrated over the exposure of a camera at
/// `world_from_camera` at its middle, moving from `start` to `end`:
/// every pixel's ground point seen from the start to the end pose,
/// sampled along that image segment, one sample a pixel of its length and
/// at least two.
pub(super) fn blur(
    camera: &CameraParams,
    width: usize,
    radiance: &[f32],
    depth_m: &[f32],
    world_from_camera: &Isometry3<f64>,
    [start, end]: [&Isometry3<f64>; 2],
) -> Vec<f32> {
    let exposure = Exposure::new(
        camera,
        width,
        [radiance, depth_m],
        world_from_camera,
        [start, end],
    );
    let mut blurred = vec![0f32; radiance.len()];
    blurred
        .par_chunks_mut(width.max(1))
        .enumerate()
        .for_each(|(v, row)| exposure.blur_row(v, row));
    blurred
}

impl<'a> Exposure<'a> {
    /// The exposure of the view `radiance` and `depth_m` of `camera`
    /// (see [`blur`]).
    fn new(
        camera: &'a CameraParams,
        width: usize,
        [radiance, depth_m]: [&'a [f32]; 2],
        world_from_camera: &Isometry3<f64>,
        [start, end]: [&Isometry3<f64>; 2],
    ) -> Self {
        let [cx, _] = camera.principal_point();
        Self {
            camera,
            width,
            height: radiance.len() / width.max(1),
            radiance,
            depth_m,
            world_from_camera: Rigid::of(world_from_camera),
            start_from_world: Rigid::of(&start.inverse()),
            end_from_world: Rigid::of(&end.inverse()),
            ray_x: (0..width)
                .map(|u| (as_f64(u) - cx) / camera.focal_px)
                .collect(),
        }
    }

    /// The blurred row `v` into `row`.
    fn blur_row(&self, v: usize, row: &mut [f32]) {
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = pulp::x86::V3::try_new() {
            simd.vectorize(lanes::Row {
                simd,
                exposure: self,
                v,
                row,
            });
            return;
        }
        self.blur_pixels(v, 0, row);
    }

    /// The blurred pixels of row `v` from column `first` on, one at a
    /// time, into `out`.
    fn blur_pixels(&self, v: usize, first: usize, out: &mut [f32]) {
        let y = self.ray_y(v);
        for (u, out) in (first..).zip(out) {
            let path = self.path(self.ray_x[u], y, self.depth(u, v));
            *out = self.integrate(u, v, &path);
        }
    }

    /// `(v − c_y) / f` of row `v`.
    fn ray_y(&self, v: usize) -> f64 {
        let [_, cy] = self.camera.principal_point();
        (as_f64(v) - cy) / self.camera.focal_px
    }

    /// The depth of the pixel `(u, v)`, capped.
    fn depth(&self, u: usize, v: usize) -> f64 {
        f64::from(self.depth_m[v * self.width + u]).min(FAR_M)
    }

    /// The path of the pixel whose ray is `(x, y, 1)` in the camera, its
    /// ground point at `depth`: `camera.pixel_ray(u, v) * depth` moved to
    /// the world and into the start and end cameras, and projected there
    /// ([`CameraParams::project`]), in the same operations.
    #[inline(always)]
    fn path<F: Arith>(&self, x: F, y: F, depth: F) -> Path<F> {
        let one = x;
        let p_camera = [x * depth, y * depth, one.splat(1.0) * depth];
        let p_world = self.world_from_camera.apply(p_camera);
        let a = self.start_from_world.apply(p_world);
        let b = self.end_from_world.apply(p_world);
        let [cx, cy] = self.camera.principal_point();
        let (cx, cy) = (one.splat(cx), one.splat(cy));
        let f = one.splat(self.camera.focal_px);
        let (u0, v0) = (f * a[0] / a[2] + cx, f * a[1] / a[2] + cy);
        let (u1, v1) = (f * b[0] / b[2] + cx, f * b[1] / b[2] + cy);
        let (du, dv) = (u1 - u0, v1 - v0);
        Path {
            u0,
            v0,
            u1,
            v1,
            length: (du * du + dv * dv).sqrt(),
            z0: a[2],
            z1: b[2],
        }
    }

    /// The radiance of the pixel `(u, v)` averaged along its `path`: its
    /// own where the point is behind the camera at either end.
    #[inline(always)]
    fn integrate(&self, u: usize, v: usize, path: &Path<f64>) -> f32 {
        if path.z0 <= 0.0 || path.z1 <= 0.0 {
            return self.radiance[v * self.width + u];
        }
        // `⌈length⌉` (a length is not negative).
        let whole = truncate(path.length);
        let steps = if as_f64(whole) < path.length {
            whole.saturating_add(1)
        } else {
            whole
        };
        let n = steps.clamp(1, MAX_STEPS) + 1;
        let (du, dv) = (path.u1 - path.u0, path.v1 - path.v0);
        let sum: f64 = (0..n)
            .map(|k| {
                let s = as_f64(k) / as_f64(n - 1);
                self.sample(path.u0 + du * s, path.v0 + dv * s)
            })
            .sum();
        (sum / as_f64(n)) as f32
    }

    /// The view's radiance at `(x, y)` (pixels), bilinear, clamped to the
    /// image.
    #[inline(always)]
    fn sample(&self, x: f64, y: f64) -> f64 {
        let (w, h) = (self.width, self.height);
        let x = x.clamp(0.0, as_f64(w - 1));
        let y = y.clamp(0.0, as_f64(h - 1));
        let (i, j) = (truncate(x).min(w - 2), truncate(y).min(h - 2));
        let (tx, ty) = (x - as_f64(i), y - as_f64(j));
        let at = |i: usize, j: usize| f64::from(self.radiance[j * w + i]);
        let top = at(i, j) + (at(i + 1, j) - at(i, j)) * tx;
        let bottom = at(i, j + 1) + (at(i + 1, j + 1) - at(i, j + 1)) * tx;
        top + (bottom - top) * ty
    }
}

#[cfg(target_arch = "x86_64")]
mod lanes;

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Point3, Vector3};

    /// The blur with nalgebra's own points and projections, one pixel at
    /// a time: what [`blur`] must give to the bit.
    fn reference(
        camera: &CameraParams,
        w: usize,
        radiance: &[f32],
        depth_m: &[f32],
        world_from_camera: &Isometry3<f64>,
        [start, end]: [&Isometry3<f64>; 2],
    ) -> Vec<f32> {
        let h = radiance.len() / w;
        let (start_inv, end_inv) = (start.inverse(), end.inverse());
        let sample = |x: f64, y: f64| -> f64 {
            let x = x.clamp(0.0, (w - 1) as f64);
            let y = y.clamp(0.0, (h - 1) as f64);
            let (i, j) = ((x as usize).min(w - 2), (y as usize).min(h - 2));
            let (tx, ty) = (x - i as f64, y - j as f64);
            let at = |i: usize, j: usize| f64::from(radiance[j * w + i]);
            let top = at(i, j) + (at(i + 1, j) - at(i, j)) * tx;
            let bottom = at(i, j + 1) + (at(i + 1, j + 1) - at(i, j + 1)) * tx;
            top + (bottom - top) * ty
        };
        let exposure = Exposure::new(
            camera,
            w,
            [radiance, depth_m],
            world_from_camera,
            [start, end],
        );
        let mut out = vec![0f32; w * h];
        for v in 0..h {
            for u in 0..w {
                let depth = f64::from(depth_m[v * w + u]).min(1e3);
                let p_cam = Point3::from(camera.pixel_ray(u as f64, v as f64) * depth);
                let p_world = world_from_camera * p_cam;
                let from = camera.project(&(start_inv * p_world));
                let to = camera.project(&(end_inv * p_world));
                // The geometry, one pixel at a time and four at a time.
                let mut paths = vec![exposure.path(exposure.ray_x[u], exposure.ray_y(v), depth)];
                #[cfg(target_arch = "x86_64")]
                if let Some(simd) = pulp::x86::V3::try_new() {
                    let first = u - u % lanes::LANES;
                    if first + lanes::LANES <= w {
                        let [a, b, c, d] =
                            lanes::paths(simd, &exposure, [first, v], exposure.ray_y(v));
                        paths.push([a, b, c, d].into_iter().nth(u % lanes::LANES).unwrap());
                    }
                }
                for path in &paths {
                    let got = [path.u0, path.v0, path.u1, path.v1].map(f64::to_bits);
                    match (from, to) {
                        (Some([u0, v0]), Some([u1, v1])) => {
                            let want = [u0, v0, u1, v1].map(f64::to_bits);
                            assert_eq!(got, want, "({u}, {v})");
                            let length = ((u1 - u0).powi(2) + (v1 - v0).powi(2)).sqrt();
                            assert_eq!(path.length.to_bits(), length.to_bits());
                        }
                        _ => assert!(path.z0 <= 0.0 || path.z1 <= 0.0, "({u}, {v})"),
                    }
                }
                let (Some([u0, v0]), Some([u1, v1])) = (from, to) else {
                    out[v * w + u] = radiance[v * w + u];
                    continue;
                };
                let length = ((u1 - u0).powi(2) + (v1 - v0).powi(2)).sqrt();
                let n = (length.ceil() as usize).clamp(1, 64) + 1;
                let sum: f64 = (0..n)
                    .map(|k| {
                        let s = k as f64 / (n - 1) as f64;
                        sample(u0 + (u1 - u0) * s, v0 + (v1 - v0) * s)
                    })
                    .sum();
                out[v * w + u] = (sum / n as f64) as f32;
            }
        }
        out
    }

    #[test]
    fn the_blur_is_nalgebras_geometry_to_the_bit() {
        // A width that is not a multiple of the lanes, an off-centre
        // principal point, and depths from 5 cm to the background.
        let camera = CameraParams {
            image_size_px: [203, 61],
            principal_point_px: Some([97.3, 33.9]),
            focal_px: 211.7,
            ..CameraParams::default()
        };
        let (w, h) = (203, 61);
        let mut state = 5u64;
        let mut uniform = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let radiance: Vec<f32> = (0..w * h).map(|_| (0.5 * uniform()) as f32).collect();
        let depth_m: Vec<f32> = (0..w * h)
            .map(|k| match k % 13 {
                0 => f32::INFINITY,
                1 => 0.05,
                _ => (0.3 + 4.0 * uniform()) as f32,
            })
            .collect();
        let world_from_camera =
            Isometry3::new(Vector3::new(2.1, 3.7, 1.2), Vector3::new(-1.9, 0.1, 0.7));
        let motions = [
            // A rover's exposure, a fast turn, and one that puts the
            // nearest points behind the camera.
            Isometry3::new(Vector3::new(3e-4, 1e-5, 0.0), Vector3::new(0.0, 0.0, 1e-3)),
            Isometry3::new(
                Vector3::new(0.02, 0.0, 0.01),
                Vector3::new(0.01, 0.02, 0.15),
            ),
            Isometry3::new(Vector3::new(0.0, 0.0, -0.12), Vector3::new(0.0, 0.3, 0.0)),
        ];
        let mut behind = 0;
        let mut long = 0;
        for motion in motions {
            let start = world_from_camera * motion.inverse();
            let end = world_from_camera * motion;
            let ends = [&start, &end];
            let got = blur(&camera, w, &radiance, &depth_m, &world_from_camera, ends);
            let want = reference(&camera, w, &radiance, &depth_m, &world_from_camera, ends);
            for (k, (g, r)) in got.iter().zip(&want).enumerate() {
                assert_eq!(g.to_bits(), r.to_bits(), "pixel {k}: {g} against {r}");
                behind += usize::from(*g == radiance[k] && depth_m[k] == 0.05);
                long += usize::from((g - radiance[k]).abs() > 0.05);
            }
        }
        assert!(
            behind > 100 && long > 1000,
            "{behind} behind, {long} smeared"
        );
    }
}
