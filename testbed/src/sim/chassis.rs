//! Places the rover's chassis on the terrain: given the planar pose
//! `(x, y, yaw)` and the steering angles, find the body height, roll, pitch
//! and the three passive bogie angles that put all six wheels on the ground.
//!
//! Six contact conditions in six unknowns (the rocker-bogie's purpose: three
//! body degrees of freedom plus three bogies keep six wheels on any smooth
//! ground), solved by Newton's method. A wheel is a disk of radius `r` in its
//! own plane: its contact point is the rim point in the direction of the
//! terrain's downward normal projected onto the wheel plane, and the contact
//! angle is that direction's angle from the wheel's −z about its axle.

use gpodo_kinematics::RoverDescription;
use gpodo_kinematics::chain::{ChainAngles, ContactGeometry};
use gpodo_kinematics::description::WheelChain;
use nalgebra::{Isometry3, Point3, SMatrix, SVector, Translation3, UnitQuaternion, Vector3};

use crate::TestbedError;
use crate::sim::terrain::Terrain;

type Unknowns = SVector<f64, 6>;

/// Body height, attitude and bogie angles: the unknowns of the placement.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Suspension {
    /// Height of the body origin (m, world z).
    pub z_m: f64,
    /// Roll (rad).
    pub roll_rad: f64,
    /// Pitch (rad).
    pub pitch_rad: f64,
    /// Bogie angles (rad) in description order.
    pub bogie_rad: [f64; 3],
}

impl Suspension {
    fn to_vector(self) -> Unknowns {
        Unknowns::new(
            self.z_m,
            self.roll_rad,
            self.pitch_rad,
            self.bogie_rad[0],
            self.bogie_rad[1],
            self.bogie_rad[2],
        )
    }

    fn from_vector(v: &Unknowns) -> Self {
        Self {
            z_m: v[0],
            roll_rad: v[1],
            pitch_rad: v[2],
            bogie_rad: [v[3], v[4], v[5]],
        }
    }
}

/// The chassis resting on the terrain.
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    /// Body height, attitude and bogie angles.
    pub suspension: Suspension,
    /// Pose of the body in the world.
    pub world_from_body: Isometry3<f64>,
    /// Contact angle of each wheel (rad).
    pub contact_rad: Vec<f64>,
    /// Contact point of each wheel (world, m).
    pub contact_points: Vec<Point3<f64>>,
}

/// Solves the placement of one rover on one terrain.
#[derive(Debug, Clone)]
pub struct ChassisSolver {
    chains: Vec<WheelChain>,
    wheel_radius_m: f64,
}

/// World pose of the body for a planar pose and a suspension state
/// (yaw–pitch–roll, z up).
pub fn world_from_body(x: f64, y: f64, yaw: f64, s: &Suspension) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(x, y, s.z_m),
        UnitQuaternion::from_euler_angles(s.roll_rad, s.pitch_rad, yaw),
    )
}

impl ChassisSolver {
    /// A solver for a rover with exactly three bogies and six wheels.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] for other layouts.
    pub fn new(description: &RoverDescription) -> Result<Self, TestbedError> {
        if description.bogies.len() != 3 || description.wheels.len() != 6 {
            return Err(TestbedError::InvalidConfig {
                field: "rover".into(),
                expected: "a rover with three bogies and six wheels".into(),
            });
        }
        Ok(Self {
            chains: description.chains(),
            wheel_radius_m: description.wheel_radius_m,
        })
    }

    /// Contact point and contact angle of wheel `i`, and its clearance above
    /// the ground (negative when it sinks in).
    fn wheel_contact(
        &self,
        terrain: &Terrain,
        body: &Isometry3<f64>,
        i: usize,
        bogie_rad: f64,
        steer_rad: f64,
    ) -> (Point3<f64>, f64, f64) {
        let g = ContactGeometry::new(
            &self.chains[i],
            self.wheel_radius_m,
            ChainAngles {
                bogie_rad,
                steer_rad,
                contact_rad: 0.0,
            },
        );
        let center = body * g.wheel_center;
        let world_from_wheel = body.rotation.to_rotation_matrix() * g.body_from_wheel;
        let axle = world_from_wheel * Vector3::y();
        // Two passes: the normal below the centre, then below the contact.
        let mut contact = center;
        for _ in 0..2 {
            let n = terrain.normal(contact.x, contact.y);
            let down = -(n - axle * n.dot(&axle));
            let down = down.try_normalize(1e-12).unwrap_or(-Vector3::z());
            contact = center + down * self.wheel_radius_m;
        }
        let in_wheel = world_from_wheel.inverse() * (contact - center);
        let contact_rad = (-in_wheel.x).atan2(-in_wheel.z);
        let clearance = contact.z - terrain.height(contact.x, contact.y);
        (contact, contact_rad, clearance)
    }

    fn clearances(
        &self,
        terrain: &Terrain,
        planar: (f64, f64, f64),
        steer: &[f64; 6],
        v: &Unknowns,
    ) -> Unknowns {
        let s = Suspension::from_vector(v);
        let body = world_from_body(planar.0, planar.1, planar.2, &s);
        Unknowns::from_fn(|i, _| {
            let bogie = self.chains[i].bogie_index.map_or(0.0, |b| s.bogie_rad[b]);
            self.wheel_contact(terrain, &body, i, bogie, steer[i]).2
        })
    }

    /// Places the chassis at planar pose `(x, y, yaw)` with per-wheel steering
    /// angles `steer` (0 for fixed wheels), starting Newton from `guess`.
    ///
    /// # Errors
    /// [`TestbedError::Simulation`] if Newton does not converge (e.g. the
    /// terrain is too steep for the chassis).
    pub fn place(
        &self,
        terrain: &Terrain,
        planar: (f64, f64, f64),
        steer: &[f64; 6],
        guess: &Suspension,
    ) -> Result<Placement, TestbedError> {
        let mut v = guess.to_vector();
        let mut converged = false;
        for _ in 0..50 {
            let f = self.clearances(terrain, planar, steer, &v);
            if f.amax() < 1e-11 {
                converged = true;
                break;
            }
            let mut jac = SMatrix::<f64, 6, 6>::zeros();
            let h = 1e-7;
            for k in 0..6 {
                let mut vp = v;
                vp[k] += h;
                let mut vm = v;
                vm[k] -= h;
                let col = (self.clearances(terrain, planar, steer, &vp)
                    - self.clearances(terrain, planar, steer, &vm))
                    / (2.0 * h);
                jac.set_column(k, &col);
            }
            let step = jac.lu().solve(&f).ok_or_else(|| TestbedError::Simulation {
                detail: format!("singular chassis placement at {planar:?}"),
            })?;
            // Limit angle steps to keep Newton in its basin on rough ground.
            let scale = (0.2 / step.amax()).min(1.0);
            v -= step * scale;
        }
        if !converged {
            return Err(TestbedError::Simulation {
                detail: format!("chassis placement did not converge at {planar:?}"),
            });
        }
        let suspension = Suspension::from_vector(&v);
        let body = world_from_body(planar.0, planar.1, planar.2, &suspension);
        let (mut contact_rad, mut contact_points) = (Vec::new(), Vec::new());
        for (i, (chain, steer_rad)) in self.chains.iter().zip(steer).enumerate() {
            let bogie = chain.bogie_index.map_or(0.0, |b| suspension.bogie_rad[b]);
            let (p, gamma, _) = self.wheel_contact(terrain, &body, i, bogie, *steer_rad);
            contact_points.push(p);
            contact_rad.push(gamma);
        }
        Ok(Placement {
            suspension,
            world_from_body: body,
            contact_rad,
            contact_points,
        })
    }

    /// The suspension of the chassis resting on flat ground at height 0.
    pub fn resting_guess(&self, terrain: &Terrain, x: f64, y: f64) -> Suspension {
        let lowest = self
            .chains
            .iter()
            .map(|c| c.center.z)
            .fold(f64::INFINITY, f64::min);
        Suspension {
            z_m: terrain.height(x, y) + self.wheel_radius_m - lowest,
            ..Default::default()
        }
    }
}
