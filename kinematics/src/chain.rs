//! Forward kinematics of one wheel's chain body → bogie → steer → wheel →
//! contact point (paper §III, Fig. 2: frames B, A_i and C_il).
//!
//! The contact frame C is the wheel frame A rotated about the axle (y) by the
//! contact angle γ and moved to the rim: its z axis is the contact normal,
//! its x axis the rolling direction, its origin the contact point
//! `p = c + R_BC · (0, 0, −r)`. A positive γ moves the contact point
//! rearwards on the rim (it is the rotation about +y).

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};

use crate::description::WheelChain;

/// Joint angles that place one contact point.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ChainAngles {
    /// Bogie angle (rad).
    pub bogie_rad: f64,
    /// Steering angle (rad), 0 for a fixed wheel.
    pub steer_rad: f64,
    /// Contact angle (rad).
    pub contact_rad: f64,
}

/// The geometry of one wheel's contact, everything in the body frame.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactGeometry {
    /// Bogie pivot (m).
    pub bogie_pivot: Point3<f64>,
    /// Bogie axis (unit).
    pub bogie_axis: Vector3<f64>,
    /// Steering axis (unit), `None` for a fixed wheel.
    pub steer_axis: Option<Vector3<f64>>,
    /// Wheel centre (m).
    pub wheel_center: Point3<f64>,
    /// Orientation of the wheel frame A (x rolling direction, y axle).
    pub body_from_wheel: Rotation3<f64>,
    /// Pose of the contact frame C.
    pub body_from_contact: Isometry3<f64>,
}

impl ContactGeometry {
    /// Places the contact of `chain` for the given joint angles.
    pub fn new(chain: &WheelChain, wheel_radius_m: f64, angles: ChainAngles) -> Self {
        let bogie = Rotation3::from_axis_angle(&chain.bogie_axis, angles.bogie_rad);
        let wheel_center = chain.bogie_pivot + bogie * (chain.center - chain.bogie_pivot);
        let steer_rad = if chain.steer_index.is_some() {
            angles.steer_rad
        } else {
            0.0
        };
        let body_from_wheel = bogie * Rotation3::from_axis_angle(&Vector3::z_axis(), steer_rad);
        let body_from_contact_rot =
            body_from_wheel * Rotation3::from_axis_angle(&Vector3::y_axis(), angles.contact_rad);
        let contact =
            wheel_center + body_from_contact_rot * Vector3::new(0.0, 0.0, -wheel_radius_m);
        Self {
            bogie_pivot: chain.bogie_pivot,
            bogie_axis: chain.bogie_axis.into_inner(),
            steer_axis: chain.steer_index.map(|_| bogie * Vector3::z()),
            wheel_center,
            body_from_wheel,
            body_from_contact: Isometry3::from_parts(
                Translation3::from(contact.coords),
                UnitQuaternion::from_rotation_matrix(&body_from_contact_rot),
            ),
        }
    }

    /// The contact point (m).
    pub fn contact_point(&self) -> Point3<f64> {
        Point3::from(self.body_from_contact.translation.vector)
    }

    /// The axle (wheel y) axis.
    pub fn axle_axis(&self) -> Vector3<f64> {
        self.body_from_wheel * Vector3::y()
    }
}
