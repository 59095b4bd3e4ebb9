//! The contact Jacobian of eq. (1): body twist = `J_il · [q̇, ε_il, δ_il]`.
//!
//! For a wheel on locally planar ground, the wheel's material point at the
//! contact moves only by slip in the ground plane, and the contact frame
//! turns only about the contact normal:
//!
//! ```text
//! v_B + ω_B × p + Σ_j q̇_j a_j × (p − o_j) + φ̇ a_φ × (p − c) = δ_x x_C + δ_y y_C
//! ω_B + Σ_j q̇_j a_j + γ̇ a_φ                              = δ_ψ z_C
//! ```
//!
//! with `j` over the bogie and steering joints (axes `a_j` through `o_j`),
//! `φ̇` the wheel rate about the axle `a_φ` through the centre `c`, `γ̇` the
//! contact angle rate and `(δ_x, δ_y, δ_ψ)` the slip. Solving for the twist
//! gives the 6 × 7 Jacobian of one chain, columns
//! `[bogie, steer, wheel, contact angle, slip x, slip y, slip ψ]`
//! (`n = 3` joints + 4), rows `[v_B; ω_B]`.

use nalgebra::{Matrix6x1, SMatrix, Vector3};

use crate::chain::ContactGeometry;

/// Number of columns of one contact Jacobian.
pub const CONTACT_COLUMNS: usize = 7;
/// Column of the bogie rate.
pub const COL_BOGIE: usize = 0;
/// Column of the steering rate.
pub const COL_STEER: usize = 1;
/// Column of the wheel rate.
pub const COL_WHEEL: usize = 2;
/// Column of the contact angle rate ε.
pub const COL_CONTACT_ANGLE: usize = 3;
/// First of the three slip columns δ = (δ_x, δ_y, δ_ψ).
pub const COL_SLIP: usize = 4;

/// The 6 × 7 Jacobian of one contact.
pub type ContactJacobian = SMatrix<f64, 6, CONTACT_COLUMNS>;

fn column(linear: Vector3<f64>, angular: Vector3<f64>) -> Matrix6x1<f64> {
    Matrix6x1::new(
        linear.x, linear.y, linear.z, angular.x, angular.y, angular.z,
    )
}

/// The Jacobian of eq. (1) for one contact placed by `g`.
pub fn contact_jacobian(g: &ContactGeometry) -> ContactJacobian {
    let p = g.contact_point().coords;
    let c = g.wheel_center.coords;
    let rot = g.body_from_contact.rotation;
    let (x_c, y_c, z_c) = (rot * Vector3::x(), rot * Vector3::y(), rot * Vector3::z());
    let a_b = g.bogie_axis;
    let a_w = g.axle_axis();
    let zero = Vector3::zeros();

    let mut j = ContactJacobian::zeros();
    j.set_column(COL_BOGIE, &column(a_b.cross(&g.bogie_pivot.coords), -a_b));
    if let Some(a_s) = g.steer_axis {
        j.set_column(COL_STEER, &column(a_s.cross(&c), -a_s));
    }
    j.set_column(COL_WHEEL, &column(-a_w.cross(&(p - c)), zero));
    j.set_column(COL_CONTACT_ANGLE, &column(a_w.cross(&p), -a_w));
    j.set_column(COL_SLIP, &column(x_c, zero));
    j.set_column(COL_SLIP + 1, &column(y_c, zero));
    j.set_column(COL_SLIP + 2, &column(-z_c.cross(&p), z_c));
    j
}
