//! Static normal forces on the wheels: the weights of the weighted Jacobian
//! model (Hidalgo-Carrió et al., IROS 2014, "Static forces weighted Jacobian
//! motion models"): a wheel that carries more of the rover's weight has more
//! traction, so its kinematic chain is trusted more.
//!
//! Quasi-static equilibrium of a rover on three passive bogies: each bogie
//! is one support (the bogie shares its load among its wheels by the lever
//! arms about its pivot), the contacts lie in one ground plane, the centre
//! of mass is at height `h` above it, and tangential contact forces (friction)
//! hold the rover on a slope. Force balance along the body z axis and moment
//! balance about the body x and y axes, with gravity `g` in the body frame
//! and unit weight, give three equations in the three support forces:
//!
//! ```text
//! Σ F_b = −g_z,   Σ F_b x_b = h g_x − x_c g_z,   Σ F_b y_b = h g_y − y_c g_z
//! ```

use nalgebra::{Matrix3, Point3, Vector3};

use crate::{KinematicsError, RoverDescription, chain::ContactGeometry};

/// Smallest share of the weight a wheel keeps when equilibrium says it lifts
/// off, so that its equations keep a (tiny) weight.
const MIN_SHARE: f64 = 1e-6;

/// Normal force on each wheel as a fraction of the rover's weight, for
/// gravity direction `gravity_body` (unit vector in the body frame; `(0, 0,
/// −1)` on flat ground). Sums to `−g_z` before clamping lifted wheels.
///
/// # Errors
/// [`KinematicsError::InvalidConfig`] unless the rover has exactly three
/// bogies, [`KinematicsError::Solve`] if the supports are collinear.
pub fn static_normal_forces(
    description: &RoverDescription,
    contacts: &[ContactGeometry],
    gravity_body: &Vector3<f64>,
) -> Result<Vec<f64>, KinematicsError> {
    if description.bogies.len() != 3 {
        return Err(KinematicsError::InvalidConfig {
            field: "weighting".into(),
            expected: "`uniform` for a rover without exactly three bogies".into(),
        });
    }
    let chains = description.chains();
    let Some(bogie_of) = chains
        .iter()
        .map(|c| c.bogie_index)
        .collect::<Option<Vec<usize>>>()
    else {
        return Err(KinematicsError::InvalidConfig {
            field: "weighting".into(),
            expected: "`uniform` for a rover with a wheel mounted rigidly on the body".into(),
        });
    };
    let points: Vec<Point3<f64>> = contacts.iter().map(|c| c.contact_point()).collect();
    let shares = bogie_shares(&chains, contacts, &points);

    // Support point of each bogie: its wheels' contacts weighted by share.
    let mut support = [Vector3::zeros(); 3];
    for ((bogie, p), share) in bogie_of.iter().zip(&points).zip(&shares) {
        support[*bogie] += p.coords * *share;
    }
    let ground_z = points.iter().map(|p| p.z).sum::<f64>() / points.len() as f64;
    let com = Vector3::from(description.center_of_mass_m);
    let h = com.z - ground_z;
    let g = gravity_body;

    let a = Matrix3::new(
        1.0,
        1.0,
        1.0, //
        support[0].x,
        support[1].x,
        support[2].x, //
        support[0].y,
        support[1].y,
        support[2].y,
    );
    let rhs = Vector3::new(-g.z, h * g.x - com.x * g.z, h * g.y - com.y * g.z);
    let forces = a
        .lu()
        .solve(&rhs)
        .ok_or_else(|| KinematicsError::Solve("bogie supports are collinear".into()))?;

    let total = -g.z;
    Ok(bogie_of
        .iter()
        .zip(&shares)
        .map(|(bogie, share)| (forces[*bogie] * share).max(MIN_SHARE * total.abs()))
        .collect())
}

/// Share of its bogie's load that each wheel carries: two wheels split it by
/// their lever arms about the pivot (perpendicular to the bogie axis in the
/// body x–y plane); otherwise the wheels share it equally.
fn bogie_shares(
    chains: &[crate::description::WheelChain],
    contacts: &[ContactGeometry],
    points: &[Point3<f64>],
) -> Vec<f64> {
    let mut shares = vec![0.0; chains.len()];
    for (i, chain) in chains.iter().enumerate() {
        let mates: Vec<usize> = (0..chains.len())
            .filter(|&k| chains[k].bogie_index == chain.bogie_index)
            .collect();
        shares[i] = if mates.len() == 2 {
            let other = if mates[0] == i { mates[1] } else { mates[0] };
            let lever = |k: usize| {
                let axis = contacts[k].bogie_axis;
                let across = Vector3::z().cross(&axis);
                ((points[k].coords - contacts[k].bogie_pivot.coords).dot(&across)).abs()
            };
            let (mine, theirs) = (lever(i), lever(other));
            if mine + theirs > 0.0 {
                theirs / (mine + theirs)
            } else {
                0.5
            }
        } else {
            1.0 / mates.len() as f64
        };
    }
    shares
}
