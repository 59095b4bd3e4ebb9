//! The import's conversions one message at a time, for a node that reads
//! a robot's topics as they arrive: an IMU message in the body frame, and a
//! joint-state message as the rover's joints in its order. The import's
//! streams (`roles.rs`) use the same conversions.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use gpodo_traits::{ImuSample, JointState as Joint};

use super::{JointRef, TopicMap};
use crate::bags::messages::{Imu, JointState};

/// An IMU message in the body frame: `world_from_body`, the gyro and the
/// specific force, rotated by the map's `imu_rotation_rpy_rad`.
pub(super) fn imu_in_body(
    body_from_imu: &UnitQuaternion<f64>,
    m: &Imu,
) -> (UnitQuaternion<f64>, Vector3<f64>, Vector3<f64>) {
    let o = m.orientation;
    let world_from_imu = UnitQuaternion::from_quaternion(Quaternion::new(o[3], o[0], o[1], o[2]));
    (
        world_from_imu * body_from_imu.inverse(),
        body_from_imu * Vector3::from(m.angular_velocity),
        body_from_imu * Vector3::from(m.linear_acceleration),
    )
}

/// The mapped joints by group (wheels, steering, bogies), each in name
/// order: the rover's order.
pub(super) type JointGroups = [(&'static str, Vec<(String, JointRef)>); 3];

/// The joint groups of the map (empty without a joints role).
pub(super) fn joint_groups(map: &TopicMap) -> JointGroups {
    match &map.joints {
        Some(j) => [
            ("wheels", j.wheels.clone().into_iter().collect()),
            ("steering", j.steering.clone().into_iter().collect()),
            ("bogies", j.bogies.clone().into_iter().collect()),
        ],
        None => [("wheels", vec![]), ("steering", vec![]), ("bogies", vec![])],
    }
}

/// Position and rate of every mapped joint of a message, in `groups`
/// order; the first mapped joint it lacks (or lacks a position or rate
/// for) otherwise.
pub(super) fn joint_values(groups: &JointGroups, m: &JointState) -> Result<Vec<f64>, String> {
    let mut v = Vec::new();
    for (_, refs) in groups {
        for (_, r) in refs {
            match m.name.iter().position(|n| *n == r.joint) {
                Some(k) if k < m.position.len() && k < m.velocity.len() => {
                    v.push(m.position[k] * r.position_scale);
                    v.push(m.velocity[k] * r.rate_scale);
                }
                _ => return Err(r.joint.clone()),
            }
        }
    }
    Ok(v)
}

/// Roll and pitch (rad) of an orientation (ZYX Euler angles).
pub(super) fn roll_pitch(q: &UnitQuaternion<f64>) -> (f64, f64) {
    let (x, y, z, w) = (q.i, q.j, q.k, q.w);
    let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
    let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
    (roll, pitch)
}

/// A topic map's conversions for one rover, one message at a time.
pub struct LiveDecoder {
    groups: JointGroups,
    body_from_imu: UnitQuaternion<f64>,
    /// Per group (wheels, steering, bogies), the rover's joints as
    /// indices into the group's mapped joints.
    order: [Vec<usize>; 3],
}

impl LiveDecoder {
    /// The conversions of `map` for a rover whose wheels, steering and
    /// bogie joints are named (in its order) as given.
    ///
    /// # Errors
    /// The first rover joint the map's `joints:` does not map, named with
    /// its group.
    pub fn new(
        map: &TopicMap,
        wheels: &[String],
        steering: &[String],
        bogies: &[String],
    ) -> Result<Self, String> {
        let [r, p, y] = map.imu_rotation_rpy_rad;
        let groups = joint_groups(map);
        let mut order: [Vec<usize>; 3] = [vec![], vec![], vec![]];
        for (g, names) in [wheels, steering, bogies].into_iter().enumerate() {
            let (group, refs) = &groups[g];
            for name in names {
                let k = refs.iter().position(|(n, _)| n == name).ok_or_else(|| {
                    format!(
                        "the topic map's `joints.{group}` has no `{name}`, a joint of the rover"
                    )
                })?;
                order[g].push(k);
            }
        }
        Ok(Self {
            groups,
            body_from_imu: UnitQuaternion::from_euler_angles(r, p, y),
            order,
        })
    }

    /// The IMU sample of a message, as the import makes it.
    pub fn imu(&self, m: &Imu) -> ImuSample {
        let (q, gyro, accel) = imu_in_body(&self.body_from_imu, m);
        let (roll, pitch) = roll_pitch(&q);
        ImuSample {
            gyro_radps: gyro,
            accel_mps2: accel,
            roll_rad: roll,
            pitch_rad: pitch,
        }
    }

    /// The rover's wheels, steering and bogie joints in its order.
    ///
    /// # Errors
    /// The name of the first mapped joint the message lacks.
    pub fn joints(&self, m: &JointState) -> Result<[Vec<Joint>; 3], String> {
        let v = joint_values(&self.groups, m)?;
        let mut at = 0;
        let mut mapped: [Vec<Joint>; 3] = [vec![], vec![], vec![]];
        for (g, (_, refs)) in self.groups.iter().enumerate() {
            for _ in refs {
                mapped[g].push(Joint {
                    position_rad: v[at],
                    rate_radps: v[at + 1],
                });
                at += 2;
            }
        }
        Ok([0, 1, 2].map(|g| self.order[g].iter().map(|&k| mapped[g][k]).collect()))
    }
}
