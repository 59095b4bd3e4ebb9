//! The weighted Jacobian motion model of §III (eq. 2–5).
//!
//! The contact Jacobians of all wheels are stacked as `S u̇ = J ṗ` (eq. 2)
//! and split into sensed and non-sensed quantities (eq. 3–4):
//!
//! * sensed: the body angular rate (IMU gyros) and the joint rates `q̇`
//!   (bogies, steering, wheels);
//! * non-sensed: the body linear velocity, and per contact the contact-angle
//!   rate and the slip `(δ_x, δ_y, δ_ψ)`.
//!
//! A robot without an IMU has no sensed angular rate: the yaw rate then
//! joins the non-sensed quantities and is solved from the wheels (through
//! their lever arms about the body's centre), and the roll and pitch rates
//! are taken as zero, as the ground is taken as level.
//!
//! `Ω v = b` is solved by minimising `E = eᵀ C e` (eq. 5), where `C` weights
//! each contact's six rows by its static normal force (or uniformly). Left
//! alone, the in-plane slips would absorb every wheel's disagreement and leave
//! the horizontal velocity undetermined, so the slips carry a weak
//! zero-mean prior, `κ · w_i · (δ_x² + δ_y²)`, scaled with each contact's
//! weight so that the load weighting is kept for any `κ`. `κ` also decides
//! which equations carry the forward speed: with a tiny `κ` the slips are
//! free and the speed is fixed by the wheels' non-penetration rows, which
//! depend on the contact angles a real rover does not sense; with `κ ≈ 1`
//! the rolling rows dominate. When this default was chosen, a simulated
//! no-slip run over hills gave a median horizontal speed error of 2.2 mm/s
//! with `κ = 1e-3` and below 0.1 mm/s with `κ ≥ 1` (the latter is what
//! `datasets/tests/simulator.rs` now checks), hence `κ = 1`. When bounds are
//! configured (contact angle, slip rate), the same objective is minimised
//! subject to them as a QP (see [`crate::qp`]).

use nalgebra::{DMatrix, DVector, SMatrix, SVector, Vector3, Vector6};
use serde::{Deserialize, Serialize};

use gpodo_traits::{BodyTwist, Error, MotionEstimate, MotionModel, ProprioceptiveSample};

use crate::chain::{ChainAngles, ContactGeometry};
use crate::description::WheelChain;
use crate::jacobian::{COL_BOGIE, COL_CONTACT_ANGLE, COL_STEER, COL_WHEEL, contact_jacobian};
use crate::loads::static_normal_forces;
use crate::qp::{Bound, solve_bounded_qp};
use crate::{KinematicsError, RoverDescription};

/// Unknowns per contact: contact angle rate, three slips, and the roller
/// rate of a mecanum wheel (held at 0 for an ordinary wheel).
const LOCAL: usize = 5;

/// Offset of the roller rate among a contact's unknowns.
const ROLLER: usize = 4;

/// Columns of one contact's block of Ω: the body velocity (3), the body
/// yaw rate (1) and the contact's own unknowns ([`LOCAL`]).
const BLOCK: usize = 4 + LOCAL;

/// The column of the body yaw rate in a contact's block.
const YAW: usize = 3;

/// The first column of a contact's own unknowns in its block.
const OWN: usize = 4;

/// The non-zero block of one contact's rows of Ω.
type ContactBlock = SMatrix<f64, 6, BLOCK>;

/// The unknowns shared by every contact: the body velocity, and the yaw
/// rate when no gyro senses it.
fn shared_unknowns(yaw_unknown: bool) -> usize {
    if yaw_unknown { 4 } else { 3 }
}

/// Where the columns of contact `i`'s block sit among all unknowns; `None`
/// for the yaw-rate column when a gyro senses it.
fn block_index(i: usize, yaw_unknown: bool) -> [Option<usize>; BLOCK] {
    let shared = shared_unknowns(yaw_unknown);
    let mut index = [None; BLOCK];
    for (k, slot) in index.iter_mut().enumerate() {
        *slot = match k {
            0..YAW => Some(k),
            YAW => yaw_unknown.then_some(YAW),
            _ => Some(shared + LOCAL * i + (k - OWN)),
        };
    }
    index
}

/// How each contact's equations are weighted (the matrix `C` of eq. 5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Weighting {
    /// By the contact's static normal force (the authors' choice).
    #[default]
    NormalForce,
    /// Equally, `C = I/N`.
    Uniform,
}

/// Where the contact angles that place the contact points come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactAngleSource {
    /// Assume every contact is straight below its wheel centre (a real rover
    /// does not sense contact angles).
    #[default]
    AssumeZero,
    /// Use `ProprioceptiveSample::contact_angles_rad` when present (e.g. a
    /// simulator's), zero otherwise.
    FromSample,
}

/// Optional bounds; any that is set turns the solve into a QP.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SolveBounds {
    /// Largest contact angle magnitude after the step (deg), e.g. 60.
    pub contact_angle_max_deg: Option<f64>,
    /// Largest in-plane slip rate magnitude per axis (m/s).
    pub slip_rate_max_mps: Option<f64>,
}

/// Settings of the weighted Jacobian model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WeightedJacobianConfig {
    /// Row weighting (default: `normal_force`).
    pub weighting: Weighting,
    /// Slip prior strength κ relative to each contact's weight (default 1:
    /// a wheel's disagreement is shared between its slip and the body
    /// velocity; see the module docs).
    pub slip_prior: f64,
    /// Contact angle source (default: `assume_zero`).
    pub contact_angles: ContactAngleSource,
    /// Bounds (default: none, plain weighted least squares).
    pub bounds: SolveBounds,
}

impl Default for WeightedJacobianConfig {
    fn default() -> Self {
        Self {
            weighting: Weighting::NormalForce,
            slip_prior: 1.0,
            contact_angles: ContactAngleSource::AssumeZero,
            bounds: SolveBounds::default(),
        }
    }
}

impl WeightedJacobianConfig {
    /// Checks every field.
    ///
    /// # Errors
    /// [`KinematicsError::InvalidConfig`] naming the field.
    pub fn validate(&self) -> Result<(), KinematicsError> {
        let bad = |field: &str, expected: &str| {
            Err(KinematicsError::InvalidConfig {
                field: field.into(),
                expected: expected.into(),
            })
        };
        if !(self.slip_prior.is_finite() && self.slip_prior > 0.0) {
            return bad("slip_prior", "a positive number");
        }
        if let Some(v) = self.bounds.contact_angle_max_deg
            && !(v.is_finite() && v > 0.0 && v < 90.0)
        {
            return bad("bounds.contact_angle_max_deg", "degrees in (0, 90)");
        }
        if let Some(v) = self.bounds.slip_rate_max_mps
            && !(v.is_finite() && v > 0.0)
        {
            return bad("bounds.slip_rate_max_mps", "a positive speed in m/s");
        }
        Ok(())
    }
}

/// The normal equations of one sample (`H v = g`), each contact's block
/// of Ω with its joint terms, the contacts' weights and the gyro's rate.
struct Assembly {
    h: DMatrix<f64>,
    g: DVector<f64>,
    systems: Vec<(ContactBlock, Vector6<f64>)>,
    weights: Vec<f64>,
    gyro: Option<Vector3<f64>>,
}

/// The full solution of one step, beyond the body twist.
#[derive(Debug, Clone, PartialEq)]
pub struct WeightedJacobianSolution {
    /// Body linear velocity (m/s).
    pub linear_mps: Vector3<f64>,
    /// Body angular rate (rad/s): the gyros' when the sample has an IMU;
    /// without one, the yaw rate solved from the wheels, and roll and pitch
    /// rates of zero (the ground is taken as level).
    pub angular_radps: Vector3<f64>,
    /// Contact angle rate per contact (rad/s).
    pub contact_angle_rates_radps: Vec<f64>,
    /// Slip `(δ_x, δ_y, δ_ψ)` per contact (m/s, m/s, rad/s).
    pub slips: Vec<[f64; 3]>,
    /// Free roller speed of each mecanum wheel's contact along its free
    /// direction (m/s; 0 for an ordinary wheel).
    pub roller_speeds_mps: Vec<f64>,
    /// Row weight of each contact (sums to 1).
    pub weights: Vec<f64>,
    /// `eᵀ C e` at the solution.
    pub weighted_residual: f64,
}

/// The weighted Jacobian model of a rover with passive bogies.
#[derive(Debug, Clone)]
pub struct WeightedJacobianModel {
    description: RoverDescription,
    chains: Vec<WheelChain>,
    config: WeightedJacobianConfig,
    n_steer: usize,
}

impl WeightedJacobianModel {
    /// Builds the model for a validated description.
    ///
    /// # Errors
    /// [`KinematicsError`] if the description or the configuration is invalid.
    pub fn new(
        description: RoverDescription,
        config: WeightedJacobianConfig,
    ) -> Result<Self, KinematicsError> {
        description.validate()?;
        config.validate()?;
        if config.weighting == Weighting::NormalForce && description.bogies.len() != 3 {
            return Err(KinematicsError::InvalidConfig {
                field: "weighting".into(),
                expected: "`uniform` for a rover without exactly three bogies".into(),
            });
        }
        let chains = description.chains();
        let n_steer = description.steer_names().len();
        Ok(Self {
            description,
            chains,
            config,
            n_steer,
        })
    }

    /// The rover description.
    pub fn description(&self) -> &RoverDescription {
        &self.description
    }

    fn check_sample(&self, s: &ProprioceptiveSample) -> Result<(), Error> {
        let checks = [
            ("wheels", self.chains.len(), s.wheels.len()),
            ("steering joints", self.n_steer, s.steering.len()),
            ("bogies", self.description.bogies.len(), s.bogies.len()),
        ];
        for (what, expected, found) in checks {
            if expected != found {
                return Err(Error::DimensionMismatch {
                    what: what.into(),
                    expected,
                    found,
                });
            }
        }
        if let Some(angles) = &s.contact_angles_rad
            && angles.len() != self.chains.len()
        {
            return Err(Error::DimensionMismatch {
                what: "contact angles".into(),
                expected: self.chains.len(),
                found: angles.len(),
            });
        }
        Ok(())
    }

    fn contact_angle(&self, s: &ProprioceptiveSample, wheel: usize) -> f64 {
        match (self.config.contact_angles, &s.contact_angles_rad) {
            (ContactAngleSource::FromSample, Some(a)) => a[wheel],
            _ => 0.0,
        }
    }

    /// Contact geometry of every wheel for the sample's joint positions.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for a sample of another rover.
    pub fn contacts(&self, s: &ProprioceptiveSample) -> Result<Vec<ContactGeometry>, Error> {
        self.check_sample(s)?;
        Ok(self.contacts_unchecked(s))
    }

    fn contacts_unchecked(&self, s: &ProprioceptiveSample) -> Vec<ContactGeometry> {
        self.chains
            .iter()
            .enumerate()
            .map(|(i, chain)| {
                let angles = ChainAngles {
                    bogie_rad: chain.bogie_index.map_or(0.0, |b| s.bogies[b].position_rad),
                    steer_rad: chain
                        .steer_index
                        .map_or(0.0, |k| s.steering[k].position_rad),
                    contact_rad: self.contact_angle(s, i),
                };
                ContactGeometry::new(chain, self.description.wheel_radius_m, angles)
            })
            .collect()
    }

    fn weights(
        &self,
        s: &ProprioceptiveSample,
        contacts: &[ContactGeometry],
    ) -> Result<Vec<f64>, KinematicsError> {
        let raw = match self.config.weighting {
            Weighting::Uniform => vec![1.0; contacts.len()],
            Weighting::NormalForce => {
                let (roll, pitch) = s.roll_pitch_rad();
                let (sr, cr) = roll.sin_cos();
                let (sp, cp) = pitch.sin_cos();
                let gravity = Vector3::new(sp, -sr * cp, -cr * cp);
                static_normal_forces(&self.description, contacts, &gravity)?
            }
        };
        let total: f64 = raw.iter().sum();
        Ok(raw.iter().map(|w| w / total).collect())
    }

    /// The normal equations' matrix `H` of eq. (5) with the slip prior, for
    /// one sample: over the body velocity, the yaw rate when no gyro senses
    /// it, and each contact's unknowns.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for a sample of another rover.
    pub fn normal_equations(&self, s: &ProprioceptiveSample) -> Result<DMatrix<f64>, Error> {
        Ok(self.assemble(s)?.h)
    }

    /// The normal equations of one sample, and what the solve needs beside.
    fn assemble(&self, s: &ProprioceptiveSample) -> Result<Assembly, Error> {
        let contacts = self.contacts(s)?;
        let weights = self.weights(s, &contacts)?;
        let n_contacts = contacts.len();
        // Without a gyro the yaw rate joins the unknowns, and the roll and
        // pitch rates are taken as zero (level ground).
        let gyro = s.gyro_radps();
        let yaw_unknown = gyro.is_none();
        let shared = shared_unknowns(yaw_unknown);
        let n_unknowns = shared + LOCAL * n_contacts;

        // Normal equations of eq. (5) plus the slip prior, assembled contact
        // by contact: H = Σ_i w_i Ω_iᵀ Ω_i, g = Σ_i w_i Ω_iᵀ b_i. Contact i's
        // rows touch only the body velocity, the yaw rate and its own
        // unknowns, so Ω_i is kept as its 6 × 9 non-zero block; the rows
        // hold `[v; ω] − J_c ċ = J_q q̇` for the contact unknowns `c` and the
        // joint rates `q̇`.
        let mut h = DMatrix::<f64>::zeros(n_unknowns, n_unknowns);
        let mut g = DVector::<f64>::zeros(n_unknowns);
        let mut systems = Vec::with_capacity(n_contacts);
        for (i, (contact, chain)) in contacts.iter().zip(&self.chains).enumerate() {
            let j = contact_jacobian(contact);
            let mut omega = ContactBlock::zeros();
            let mut joints = Vector6::zeros();
            let bogie_rate = chain.bogie_index.map_or(0.0, |b| s.bogies[b].rate_radps);
            let steer_rate = chain.steer_index.map_or(0.0, |k| s.steering[k].rate_radps);
            let wheel_rate = s.wheels[i].rate_radps;
            for r in 0..6 {
                if r < 3 {
                    omega[(r, r)] = 1.0;
                } else if r == 5 {
                    omega[(r, YAW)] = 1.0;
                }
                for k in 0..ROLLER {
                    omega[(r, OWN + k)] = -j[(r, COL_CONTACT_ANGLE + k)];
                }
                // A mecanum contact also moves freely along the ground
                // direction perpendicular to its roller axis,
                // d = cos γ x_C − sin γ y_C: a column made of the slip ones.
                if let Some(gamma) = chain.roller_angle_rad {
                    omega[(r, OWN + ROLLER)] =
                        gamma.cos() * omega[(r, OWN + 1)] - gamma.sin() * omega[(r, OWN + 2)];
                }
                joints[r] = j[(r, COL_BOGIE)] * bogie_rate
                    + j[(r, COL_STEER)] * steer_rate
                    + j[(r, COL_WHEEL)] * wheel_rate;
            }
            // A sensed angular rate moves to the right-hand side.
            let mut b = joints;
            if let Some(w) = gyro {
                for r in 3..6 {
                    b[r] -= w[r - 3];
                }
            }
            let index = block_index(i, yaw_unknown);
            let hb = omega.transpose() * omega * weights[i];
            let gb = omega.transpose() * b * weights[i];
            for (p, row) in index.iter().enumerate() {
                let Some(row) = *row else { continue };
                g[row] += gb[p];
                for (q, col) in index.iter().enumerate() {
                    if let Some(col) = *col {
                        h[(row, col)] += hb[(p, q)];
                    }
                }
            }
            for slip_axis in [1, 2] {
                h[(
                    shared + LOCAL * i + slip_axis,
                    shared + LOCAL * i + slip_axis,
                )] += self.config.slip_prior * weights[i];
            }
            if chain.roller_angle_rad.is_none() {
                // No roller: a unit prior holds the unused rate at zero.
                h[(shared + LOCAL * i + ROLLER, shared + LOCAL * i + ROLLER)] += 1.0;
            }
            systems.push((omega, joints));
        }

        Ok(Assembly {
            h,
            g,
            systems,
            weights,
            gyro,
        })
    }

    /// Solves eq. (5) for one sample; `dt_secs` only matters for the
    /// contact-angle bound (the angle after the step must stay in bounds).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for a sample of another rover,
    /// [`Error::Numerical`] if the solve fails.
    pub fn solve(
        &self,
        s: &ProprioceptiveSample,
        dt_secs: f64,
    ) -> Result<WeightedJacobianSolution, Error> {
        let Assembly {
            h,
            g,
            systems,
            weights,
            gyro,
        } = self.assemble(s)?;
        let n_contacts = systems.len();
        let yaw_unknown = gyro.is_none();
        let shared = shared_unknowns(yaw_unknown);
        let bounds = self.bounds(s, dt_secs, n_contacts, shared);
        let v = if bounds.is_empty() {
            h.cholesky()
                .ok_or_else(|| KinematicsError::Solve("normal equations are singular".into()))?
                .solve(&g)
        } else {
            solve_bounded_qp(&h, &g, &bounds)?
        };
        let angular_radps = gyro.unwrap_or_else(|| Vector3::new(0.0, 0.0, v[YAW]));

        let weighted_residual = systems
            .iter()
            .zip(&weights)
            .enumerate()
            .map(|(i, ((omega, joints), w))| {
                // The whole block's values, the rates in the sensed
                // columns included: `[v; ω] − J_c ċ − J_q q̇`.
                let mut local = SVector::<f64, BLOCK>::zeros();
                for (k, at) in block_index(i, yaw_unknown).iter().enumerate() {
                    local[k] = at.map_or(angular_radps.z, |at| v[at]);
                }
                let mut sensed = Vector6::zeros();
                sensed[3] = angular_radps.x;
                sensed[4] = angular_radps.y;
                w * (joints - omega * local - sensed).norm_squared()
            })
            .sum();
        Ok(WeightedJacobianSolution {
            linear_mps: Vector3::new(v[0], v[1], v[2]),
            angular_radps,
            contact_angle_rates_radps: (0..n_contacts).map(|i| v[shared + LOCAL * i]).collect(),
            slips: (0..n_contacts)
                .map(|i| {
                    let o = shared + LOCAL * i;
                    [v[o + 1], v[o + 2], v[o + 3]]
                })
                .collect(),
            roller_speeds_mps: (0..n_contacts)
                .map(|i| v[shared + LOCAL * i + ROLLER])
                .collect(),
            weights,
            weighted_residual,
        })
    }

    fn bounds(
        &self,
        s: &ProprioceptiveSample,
        dt_secs: f64,
        n_contacts: usize,
        shared: usize,
    ) -> Vec<Bound> {
        let mut bounds = Vec::new();
        for i in 0..n_contacts {
            let o = shared + LOCAL * i;
            if let Some(max_deg) = self.config.bounds.contact_angle_max_deg
                && dt_secs > 0.0
            {
                let max = max_deg.to_radians();
                let now = self.contact_angle(s, i);
                bounds.push(Bound {
                    index: o,
                    lo: (-max - now) / dt_secs,
                    hi: (max - now) / dt_secs,
                });
            }
            if let Some(max) = self.config.bounds.slip_rate_max_mps {
                for k in [1, 2] {
                    bounds.push(Bound {
                        index: o + k,
                        lo: -max,
                        hi: max,
                    });
                }
            }
        }
        bounds
    }
}

impl MotionModel for WeightedJacobianModel {
    fn name(&self) -> &str {
        "weighted_jacobian"
    }

    fn estimate(&self, s: &ProprioceptiveSample, dt_secs: f64) -> Result<MotionEstimate, Error> {
        let solution = self.solve(s, dt_secs)?;
        Ok(MotionEstimate {
            twist: BodyTwist {
                linear_mps: solution.linear_mps,
                angular_radps: solution.angular_radps,
            },
            contact_slip_mps: solution.slips.iter().map(|d| [d[0], d[1]]).collect(),
            weighted_residual: solution.weighted_residual,
        })
    }
}
