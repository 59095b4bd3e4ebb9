//! The minimal solver of the perspective-3-point problem: Grunert's
//! solution (1841), as reviewed by Haralick et al. (IJCV 1994). With the
//! three points' unknown distances `s_i` along their unit bearings `j_i`,
//! the law of cosines in the three triangles through the camera centre
//! gives, for `u = s2 / s1` and `v = s3 / s1`, `u` as a rational function
//! of `v` and a quartic in `v`. Here the quartic's coefficients are
//! multiplied out from those two equations (no transcribed coefficient
//! table), its real roots found as the companion matrix's eigenvalues and
//! polished by Newton's method; each root gives the points in the camera
//! frame, and the pose aligns them with the world points (Kabsch).

use nalgebra::{
    Isometry3, Matrix3, Matrix4, Point3, Rotation3, Translation3, UnitQuaternion, Vector3,
};

/// A polynomial's coefficients, lowest degree first.
type Poly = Vec<f64>;

fn mul(a: &[f64], b: &[f64]) -> Poly {
    let mut out = vec![0.0; a.len() + b.len() - 1];
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate() {
            out[i + j] += x * y;
        }
    }
    out
}

fn add(a: &[f64], b: &[f64], scale_b: f64) -> Poly {
    let mut out = vec![0.0; a.len().max(b.len())];
    for (k, x) in a.iter().enumerate() {
        out[k] += x;
    }
    for (k, y) in b.iter().enumerate() {
        out[k] += scale_b * y;
    }
    out
}

fn eval(p: &[f64], x: f64) -> f64 {
    p.iter().rev().fold(0.0, |acc, c| acc * x + c)
}

/// The real roots of the quartic `p` (5 coefficients, lowest first).
fn quartic_roots(p: &[f64]) -> Vec<f64> {
    let lead = p[4];
    if lead.abs() < 1e-14 * p.iter().fold(0.0f64, |m, c| m.max(c.abs())) {
        return Vec::new();
    }
    let mut companion = Matrix4::zeros();
    for k in 0..3 {
        companion[(k + 1, k)] = 1.0;
    }
    for k in 0..4 {
        companion[(k, 3)] = -p[k] / lead;
    }
    let derivative: Poly = (1..5).map(|k| k as f64 * p[k]).collect();
    companion
        .complex_eigenvalues()
        .iter()
        .filter(|z| z.im.abs() <= 1e-6 * (1.0 + z.re.abs()))
        .map(|z| {
            let mut x = z.re;
            for _ in 0..3 {
                let d = eval(&derivative, x);
                if d.abs() > 0.0 {
                    x -= eval(p, x) / d;
                }
            }
            x
        })
        .collect()
}

/// The rigid motion `T` with `camera_k ≈ T · world_k` for three or more
/// point pairs, in the least-squares sense (Kabsch's SVD, a reflection
/// excluded); `None` when the points are degenerate.
pub fn align(world: &[Point3<f64>], camera: &[Point3<f64>]) -> Option<Isometry3<f64>> {
    let n = world.len() as f64;
    let cw = world.iter().fold(Vector3::zeros(), |s, p| s + p.coords) / n;
    let cc = camera.iter().fold(Vector3::zeros(), |s, p| s + p.coords) / n;
    let mut h = Matrix3::zeros();
    for (w, c) in world.iter().zip(camera) {
        h += (w.coords - cw) * (c.coords - cc).transpose();
    }
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let v = v_t.transpose();
    let d = (v * u.transpose()).determinant().signum();
    let r = v * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * u.transpose();
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    let t = cc - rotation * cw;
    (r.iter().all(|x| x.is_finite()) && t.iter().all(|x| x.is_finite()))
        .then(|| Isometry3::from_parts(Translation3::from(t), rotation))
}

/// The poses `camera_from_world` (up to four) that put the three `world`
/// points on the unit `bearings` (camera frame) in front of the camera.
pub fn p3p(world: &[Point3<f64>; 3], bearings: &[Vector3<f64>; 3]) -> Vec<Isometry3<f64>> {
    let [p1, p2, p3] = world;
    let [j1, j2, j3] = bearings;
    let a2 = (p2 - p3).norm_squared();
    let b2 = (p1 - p3).norm_squared();
    let c2 = (p1 - p2).norm_squared();
    if a2 < 1e-12 || b2 < 1e-12 || c2 < 1e-12 {
        return Vec::new();
    }
    let (ca, cb, cg) = (j2.dot(j3), j1.dot(j3), j1.dot(j2));
    let k = (a2 - c2) / b2;
    // u = N(v) / D(v).
    let numerator = vec![1.0 + k, -2.0 * k * cb, k - 1.0];
    let denominator = vec![2.0 * cg, -2.0 * ca];
    // The second triangle's relation times D²:
    // D² + N² − 2 cγ N D − (c²/b²)(1 + v² − 2 v cβ) D² = 0.
    let d2 = mul(&denominator, &denominator);
    let q = vec![1.0, -2.0 * cb, 1.0];
    let mut quartic = add(&d2, &mul(&numerator, &numerator), 1.0);
    quartic = add(&quartic, &mul(&numerator, &denominator), -2.0 * cg);
    quartic = add(&quartic, &mul(&q, &d2), -c2 / b2);
    quartic.resize(5, 0.0);
    let mut poses = Vec::new();
    for v in quartic_roots(&quartic) {
        let d = eval(&denominator, v);
        if d.abs() < 1e-12 {
            continue;
        }
        let u = eval(&numerator, v) / d;
        let s1_squared = b2 / eval(&q, v);
        if !(s1_squared > 0.0 && u > 0.0 && v > 0.0) {
            continue;
        }
        let s1 = s1_squared.sqrt();
        let camera = [j1 * s1, j2 * (u * s1), j3 * (v * s1)].map(Point3::from);
        if let Some(pose) = align(world, &camera) {
            poses.push(pose);
        }
    }
    poses
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_true_pose_is_among_the_solutions() {
        let truth = Isometry3::new(Vector3::new(0.3, -0.2, 1.5), Vector3::new(0.1, -0.4, 0.25));
        let world = [
            Point3::new(0.5, 0.2, 2.0),
            Point3::new(-0.4, 0.6, 3.1),
            Point3::new(0.1, -0.7, 2.5),
        ];
        let bearings = world.map(|p| (truth * p).coords.normalize());
        let poses = p3p(&world, &bearings);
        assert!(!poses.is_empty());
        let best = poses
            .iter()
            .map(|p| {
                (p.inverse() * truth).translation.vector.norm()
                    + (p.inverse() * truth).rotation.angle()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(best < 1e-9, "{best}");
        // Every solution puts the points on their bearings.
        for pose in &poses {
            for (p, j) in world.iter().zip(&bearings) {
                let x = pose * p;
                assert!(x.z > 0.0);
                assert!((x.coords.normalize() - j).norm() < 1e-9);
            }
        }
    }

    #[test]
    fn alignment_recovers_a_motion_from_four_points() {
        let truth = Isometry3::new(Vector3::new(1.0, 2.0, -0.5), Vector3::new(-0.3, 0.2, 1.1));
        let world = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.2),
            Point3::new(0.0, 1.0, -0.3),
            Point3::new(0.4, 0.3, 1.0),
        ];
        let camera = world.map(|p| truth * p);
        let got = align(&world, &camera).unwrap();
        assert!((got.inverse() * truth).translation.vector.norm() < 1e-12);
        assert!((got.inverse() * truth).rotation.angle() < 1e-12);
    }
}
