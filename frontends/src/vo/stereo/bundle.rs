//! ORB-SLAM2's local bundle adjustment (`Optimizer::LocalBundleAdjustment`):
//! the poses of a new keyframe and its covisible keyframes, and the map
//! points they see, refined together on the stereo reprojection error;
//! the keyframes that see those points but are not covisible are held
//! fixed. As ORB-SLAM2 does it: a first pass with Huber's loss at the
//! observation's 95 % χ² quantile (7.815 stereo, 5.991 left image only),
//! then the observations beyond it (or behind their camera) set aside,
//! and a second pass without the loss.
//!
//! Each pass is Levenberg–Marquardt on the normal equations with the map
//! points eliminated by their Schur complement: a point's block is 3 × 3,
//! so the reduced system is the free poses' `6m × 6m`, solved by
//! Cholesky, and each point's step follows from the poses'. factrs
//! (which the pose graph uses) has no stereo reprojection factor; one
//! could be written, but a local map is tens of poses and thousands of
//! points with 3 × 3 blocks, the structure the Schur complement is made
//! for, and here it is a few dense `nalgebra` blocks (not timed against
//! factrs). It runs on one thread, in the order of the observations
//! given, so its numbers do not depend on a thread count.
//!
//! Poses are `camera_from_world`; a point `P` (world frame) is at `T · P`
//! in the camera's. Steps are left perturbations `Exp(δ) · T`,
//! `δ = [ω; ρ]`, as in [`super::pose`].

use nalgebra::{
    DMatrix, DVector, Isometry3, Matrix3, Matrix6, Point3, SMatrix, Translation3, UnitQuaternion,
    Vector3, Vector6,
};

use super::pose::{
    Correspondence, StereoIntrinsics, chi2 as correspondence_chi2, chi2_limit, whitened,
};
use crate::FrontendError;

/// One keyframe's observation of one map point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// The keyframe (index into [`LocalMap::poses`]).
    pub keyframe: usize,
    /// The map point (index into [`LocalMap::points`]).
    pub point: usize,
    /// Its left-image pixel.
    pub left_px: [f64; 2],
    /// Its right-image column, when stereo-matched.
    pub right_x: Option<f64>,
    /// Its standard deviation (px): its pyramid level's scale.
    pub sigma_px: f64,
}

/// The local map a new keyframe's adjustment works on.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalMap {
    /// Per keyframe, `camera_from_world`.
    pub poses: Vec<Isometry3<f64>>,
    /// Per keyframe, whether it is held fixed (at least one must be: the
    /// map's frame).
    pub fixed: Vec<bool>,
    /// The map points (world frame, m).
    pub points: Vec<Point3<f64>>,
    /// Every observation of those points by those keyframes.
    pub observations: Vec<Observation>,
}

/// How long each pass runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BundleSettings {
    /// Levenberg–Marquardt iterations with Huber's loss (ORB-SLAM2: 5).
    pub robust_iterations: usize,
    /// Iterations without it, after the outliers are set aside (10).
    pub refine_iterations: usize,
}

impl Default for BundleSettings {
    fn default() -> Self {
        Self {
            robust_iterations: 5,
            refine_iterations: 10,
        }
    }
}

/// The adjusted local map.
#[derive(Debug, Clone, PartialEq)]
pub struct Adjusted {
    /// Per keyframe, `camera_from_world` (the fixed ones unchanged).
    pub poses: Vec<Isometry3<f64>>,
    /// The map points.
    pub points: Vec<Point3<f64>>,
    /// Per observation: kept (within its χ² limit, in front of its camera).
    pub inliers: Vec<bool>,
    /// The kept observations' χ² before and after.
    pub chi2: (f64, f64),
    /// The free poses' covariance at the end (left perturbations, in the
    /// order of the free keyframes): the inverse of the reduced system,
    /// the map points marginalised; empty when that system is not positive
    /// definite (a free keyframe the points do not hold).
    pub pose_covariance: DMatrix<f64>,
    /// Per point, its covariance given the adjusted poses (the inverse of
    /// its block of the normal equations at the end); `None` for a point
    /// no kept observation sees, or when the system is singular.
    pub point_covariance: Vec<Option<Matrix3<f64>>>,
}

/// How an observation is weighed.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Loss {
    Huber,
    Squared,
}

/// The normal equations with the points' blocks kept apart.
struct Normal {
    /// The free poses' block (`6m × 6m`).
    poses: DMatrix<f64>,
    /// Their gradient.
    pose_gradient: DVector<f64>,
    /// Per point, its block and gradient.
    points: Vec<(Matrix3<f64>, Vector3<f64>)>,
    /// Per observation of a free pose: its `Jₚᵀ W J_l` (6 × 3).
    coupling: Vec<Option<SMatrix<f64, 6, 3>>>,
    /// The cost (Huber's or the χ²).
    cost: f64,
}

/// Adjusts `map` as ORB-SLAM2's local bundle adjustment does (see the
/// module).
///
/// # Errors
/// [`FrontendError::InvalidConfig`] for a map with no fixed keyframe, an
/// observation of a keyframe or point it does not have, or a standard
/// deviation that is not positive.
pub fn local_bundle_adjustment(
    map: &LocalMap,
    camera: &StereoIntrinsics,
    settings: &BundleSettings,
) -> Result<Adjusted, FrontendError> {
    check(map)?;
    let free: Vec<Option<usize>> = map
        .fixed
        .iter()
        .scan(0, |next, &fixed| {
            Some((!fixed).then(|| {
                *next += 1;
                *next - 1
            }))
        })
        .collect();
    let mut poses = map.poses.clone();
    let mut points = map.points.clone();
    let mut inliers = vec![true; map.observations.len()];
    let chi2_before = chi2(map, &poses, &points, &inliers, camera);
    let context = Context {
        map,
        camera,
        free: &free,
    };
    context.minimise(
        &mut poses,
        &mut points,
        &inliers,
        Loss::Huber,
        settings.robust_iterations,
    );
    set_aside(map, &poses, &points, camera, &mut inliers);
    context.minimise(
        &mut poses,
        &mut points,
        &inliers,
        Loss::Squared,
        settings.refine_iterations,
    );
    set_aside(map, &poses, &points, camera, &mut inliers);
    let n = context.normal(&poses, &points, &inliers, Loss::Squared);
    let (pose_covariance, point_covariance) = match context.reduced(&n, 0.0) {
        Some((s, _, inverses)) => (
            s.cholesky()
                .map_or_else(|| DMatrix::zeros(0, 0), |c| c.inverse()),
            inverses,
        ),
        None => (DMatrix::zeros(0, 0), vec![None; points.len()]),
    };
    Ok(Adjusted {
        chi2: (chi2_before, chi2(map, &poses, &points, &inliers, camera)),
        poses,
        points,
        inliers,
        pose_covariance,
        point_covariance,
    })
}

fn check(map: &LocalMap) -> Result<(), FrontendError> {
    let invalid = |field: &str, expected: String| FrontendError::InvalidConfig {
        field: field.into(),
        expected,
    };
    if map.fixed.len() != map.poses.len() {
        return Err(invalid(
            "local_map.fixed",
            format!("one flag per keyframe ({})", map.poses.len()),
        ));
    }
    if !map.fixed.iter().any(|f| *f) {
        return Err(invalid(
            "local_map.fixed",
            "at least one fixed keyframe (the map's frame)".into(),
        ));
    }
    for (i, o) in map.observations.iter().enumerate() {
        if o.keyframe >= map.poses.len() || o.point >= map.points.len() {
            return Err(invalid(
                &format!("local_map.observations[{i}]"),
                format!(
                    "a keyframe below {} and a point below {}",
                    map.poses.len(),
                    map.points.len()
                ),
            ));
        }
        if !(o.sigma_px.is_finite() && o.sigma_px > 0.0) {
            return Err(invalid(
                &format!("local_map.observations[{i}].sigma_px"),
                "a positive standard deviation".into(),
            ));
        }
    }
    Ok(())
}

/// `o` as the motion-only refinement's correspondence: its point in the
/// world frame, seen from its keyframe.
fn correspondence(o: &Observation, point: &Point3<f64>) -> Correspondence {
    Correspondence {
        point: *point,
        left_px: o.left_px,
        right_x: o.right_x,
        sigma_px: o.sigma_px,
        point_covariance: Matrix3::zeros(),
    }
}

/// The observation's χ² and its limit; infinite behind its camera.
fn observation_chi2(
    o: &Observation,
    poses: &[Isometry3<f64>],
    points: &[Point3<f64>],
    camera: &StereoIntrinsics,
) -> (f64, f64) {
    correspondence_chi2(
        &correspondence(o, &points[o.point]),
        &poses[o.keyframe],
        camera,
    )
}

/// Sets aside the observations beyond their χ² limit or behind their
/// camera (ORB-SLAM2's outliers after each pass).
fn set_aside(
    map: &LocalMap,
    poses: &[Isometry3<f64>],
    points: &[Point3<f64>],
    camera: &StereoIntrinsics,
    kept: &mut [bool],
) {
    for (keep, o) in kept.iter_mut().zip(&map.observations) {
        let (value, limit) = observation_chi2(o, poses, points, camera);
        *keep = *keep && value <= limit;
    }
}

/// The kept observations' χ².
fn chi2(
    map: &LocalMap,
    poses: &[Isometry3<f64>],
    points: &[Point3<f64>],
    kept: &[bool],
    camera: &StereoIntrinsics,
) -> f64 {
    map.observations
        .iter()
        .zip(kept)
        .filter(|(_, k)| **k)
        .map(|(o, _)| observation_chi2(o, poses, points, camera).0)
        .filter(|v| v.is_finite())
        .sum()
}

/// `Exp(δ) · T`.
fn perturbed(step: &[f64], pose: &Isometry3<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(step[3], step[4], step[5]),
        UnitQuaternion::from_scaled_axis(Vector3::new(step[0], step[1], step[2])),
    ) * pose
}

/// The reduced system, its right-hand side and the points' inverses.
type Reduced = (DMatrix<f64>, DVector<f64>, Vec<Option<Matrix3<f64>>>);

struct Context<'a> {
    map: &'a LocalMap,
    camera: &'a StereoIntrinsics,
    /// Per keyframe, its place among the free poses.
    free: &'a [Option<usize>],
}

impl Context<'_> {
    fn free_count(&self) -> usize {
        self.free.iter().flatten().count()
    }

    /// The normal equations of the `kept` observations.
    fn normal(
        &self,
        poses: &[Isometry3<f64>],
        points: &[Point3<f64>],
        kept: &[bool],
        loss: Loss,
    ) -> Normal {
        let m = self.free_count();
        let mut n = Normal {
            poses: DMatrix::zeros(6 * m, 6 * m),
            pose_gradient: DVector::zeros(6 * m),
            points: vec![(Matrix3::zeros(), Vector3::zeros()); points.len()],
            coupling: vec![None; self.map.observations.len()],
            cost: 0.0,
        };
        for (i, o) in self.map.observations.iter().enumerate() {
            if !kept[i] {
                continue;
            }
            let c = correspondence(o, &points[o.point]);
            let Some((r, jp, jl)) = whitened(&c, &poses[o.keyframe], self.camera) else {
                continue;
            };
            let e2: f64 = r.iter().map(|x| x * x).sum();
            let limit = chi2_limit(&c);
            let (weight, cost) = match loss {
                Loss::Huber if e2 > limit => {
                    let delta = limit.sqrt();
                    (delta / e2.sqrt(), 2.0 * delta * e2.sqrt() - limit)
                }
                Loss::Huber | Loss::Squared => (1.0, e2),
            };
            n.cost += cost;
            let (block, gradient) = &mut n.points[o.point];
            let mut coupling = SMatrix::<f64, 6, 3>::zeros();
            let mut pose_block = Matrix6::zeros();
            let mut pose_gradient = Vector6::zeros();
            for ((ri, p), l) in r.iter().zip(&jp).zip(&jl) {
                *block += weight * l * l.transpose();
                *gradient += weight * l * *ri;
                coupling += weight * p * l.transpose();
                pose_block += weight * p * p.transpose();
                pose_gradient += weight * p * *ri;
            }
            if let Some(k) = self.free[o.keyframe] {
                let mut view = n.poses.fixed_view_mut::<6, 6>(6 * k, 6 * k);
                view += pose_block;
                let mut g = n.pose_gradient.fixed_rows_mut::<6>(6 * k);
                g += pose_gradient;
                n.coupling[i] = Some(coupling);
            }
        }
        n
    }

    /// The reduced system `S δp = b` with the points eliminated, each
    /// block damped by `lambda` on its diagonal, and each point's damped
    /// block's inverse. `None` when a point's block is singular.
    fn reduced(&self, n: &Normal, lambda: f64) -> Option<Reduced> {
        let mut s = n.poses.clone();
        for d in 0..s.nrows() {
            s[(d, d)] += lambda * (1.0 + s[(d, d)]);
        }
        let mut b = -n.pose_gradient.clone();
        let inverses = self.point_inverses(n, lambda)?;
        let by_point = self.observations_by_point(n);
        for (j, list) in by_point.iter().enumerate() {
            let Some(v) = inverses[j] else { continue };
            let gl = n.points[j].1;
            for &(k1, w1) in list {
                let wv = w1 * v;
                let mut bk = b.fixed_rows_mut::<6>(6 * k1);
                bk += wv * gl;
                for &(k2, w2) in list {
                    let mut block = s.fixed_view_mut::<6, 6>(6 * k1, 6 * k2);
                    block -= wv * w2.transpose();
                }
            }
        }
        Some((s, b, inverses))
    }

    /// Per point, its damped block's inverse (`None` for a point no kept
    /// observation sees); `None` when one is singular.
    fn point_inverses(&self, n: &Normal, lambda: f64) -> Option<Vec<Option<Matrix3<f64>>>> {
        n.points
            .iter()
            .map(|(block, _)| {
                if block.iter().all(|v| *v == 0.0) {
                    return Some(None);
                }
                let mut damped = *block;
                for d in 0..3 {
                    damped[(d, d)] += lambda * (1.0 + block[(d, d)]);
                }
                damped.try_inverse().map(Some)
            })
            .collect()
    }

    /// Per point, the free keyframes that see it with their couplings.
    fn observations_by_point(&self, n: &Normal) -> Vec<Vec<(usize, SMatrix<f64, 6, 3>)>> {
        let mut by_point = vec![Vec::new(); n.points.len()];
        for (o, c) in self.map.observations.iter().zip(&n.coupling) {
            if let (Some(k), Some(c)) = (self.free[o.keyframe], c) {
                by_point[o.point].push((k, *c));
            }
        }
        by_point
    }

    /// Levenberg–Marquardt for `iterations` on the `kept` observations.
    fn minimise(
        &self,
        poses: &mut [Isometry3<f64>],
        points: &mut [Point3<f64>],
        kept: &[bool],
        loss: Loss,
        iterations: usize,
    ) {
        let mut lambda = 1e-5;
        let mut n = self.normal(poses, points, kept, loss);
        for _ in 0..iterations {
            let Some((s, b, inverses)) = self.reduced(&n, lambda) else {
                return;
            };
            let Some(dp) = s.cholesky().map(|c| c.solve(&b)) else {
                lambda *= 10.0;
                continue;
            };
            // Each point's step from the poses': V⁻¹ (−g_l − Σ Wᵀ δp).
            let mut rhs: Vec<Vector3<f64>> = n.points.iter().map(|(_, g)| -g).collect();
            for (o, c) in self.map.observations.iter().zip(&n.coupling) {
                if let (Some(k), Some(c)) = (self.free[o.keyframe], c) {
                    rhs[o.point] -= c.transpose() * dp.fixed_rows::<6>(6 * k);
                }
            }
            let mut trial_poses = poses.to_vec();
            for (pose, k) in trial_poses.iter_mut().zip(self.free) {
                if let Some(k) = k {
                    *pose = perturbed(dp.fixed_rows::<6>(6 * k).as_slice(), pose);
                }
            }
            let trial_points: Vec<Point3<f64>> = points
                .iter()
                .zip(&inverses)
                .zip(&rhs)
                .map(|((p, v), r)| v.map_or(*p, |v| p + v * r))
                .collect();
            let trial = self.normal(&trial_poses, &trial_points, kept, loss);
            if trial.cost < n.cost {
                poses.copy_from_slice(&trial_poses);
                points.copy_from_slice(&trial_points);
                let converged = n.cost - trial.cost <= 1e-12 * n.cost.max(1e-300);
                n = trial;
                lambda = (lambda / 3.0).max(1e-12);
                if converged {
                    return;
                }
            } else {
                lambda *= 4.0;
            }
        }
    }
}

#[cfg(test)]
mod tests;
