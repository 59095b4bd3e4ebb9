//! The pose's covariance, propagated from the twist's as the pose is
//! integrated (first order, as an EKF's prediction step does it).
//!
//! The pose integrates `p ← p + R v dt`, `R ← R Exp(ω dt)`. Its error is
//! the position's in the odom frame and a rotation about the odom frame's
//! axes (`R = Exp(θ) R̂`), the order and frame of `nav_msgs/Odometry`'s pose
//! covariance. To first order, one step maps them as
//!
//! ```text
//! δp' = δp − [R̂ v dt]× θ + R̂ δv dt
//! θ'  = θ + R̂' δω dt            (R̂' = R̂ Exp(ω dt))
//! ```
//!
//! so `P' = F P Fᵀ + G Q Gᵀ` with `F = [[I, −[R̂ v dt]×], [0, I]]`,
//! `G = diag(R̂ dt, R̂' dt)` and `Q` the twist's variances. Each step's
//! twist error is taken as independent of the others'; the heading's
//! error then grows the position's across the track, as it does on a
//! rover.

use nalgebra::{Isometry3, Matrix3, Matrix6, Vector3};

/// The skew-symmetric matrix of `v` (`[v]× w = v × w`).
fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// The covariance after one step of `dt` from `pose` with body twist
/// `(linear, angular)` whose variances are `variance` (linear x, y, z,
/// then angular).
pub fn propagate(
    covariance: &Matrix6<f64>,
    pose: &Isometry3<f64>,
    linear: &Vector3<f64>,
    angular: &Vector3<f64>,
    variance: &[f64; 6],
    dt: f64,
) -> Matrix6<f64> {
    let r = pose.rotation.to_rotation_matrix().into_inner();
    let r_next = (pose.rotation * nalgebra::UnitQuaternion::from_scaled_axis(angular * dt))
        .to_rotation_matrix()
        .into_inner();
    let mut f = Matrix6::identity();
    f.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&(-skew(&(r * linear * dt))));
    let mut g = Matrix6::zeros();
    g.fixed_view_mut::<3, 3>(0, 0).copy_from(&(r * dt));
    g.fixed_view_mut::<3, 3>(3, 3).copy_from(&(r_next * dt));
    let q = Matrix6::from_diagonal(&nalgebra::Vector6::from_row_slice(variance));
    let next = f * covariance * f.transpose() + g * q * g.transpose();
    // Symmetric to the last bit.
    (next + next.transpose()) * 0.5
}

/// `covariance` as `nav_msgs/Odometry` carries it (row-major), with no
/// diagonal element below `floor`.
pub fn row_major(covariance: &Matrix6<f64>, floor: f64) -> [f64; 36] {
    std::array::from_fn(|k| {
        let (i, j) = (k / 6, k % 6);
        let v = covariance[(i, j)];
        if i == j { v.max(floor) } else { v }
    })
}
