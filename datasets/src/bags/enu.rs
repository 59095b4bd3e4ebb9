//! GNSS fixes in a local east-north-up frame about a reference fix
//! (WGS 84: geodetic → Earth-centred Earth-fixed → ENU), as ground truth
//! for a recording whose only absolute positions are a GPS's.

/// WGS 84 semi-major axis (m).
const A: f64 = 6_378_137.0;
/// WGS 84 flattening.
const F: f64 = 1.0 / 298.257_223_563;

/// Earth-centred Earth-fixed coordinates (m) of a geodetic position
/// (degrees, degrees, metres above the ellipsoid).
pub fn ecef(latitude_deg: f64, longitude_deg: f64, altitude_m: f64) -> [f64; 3] {
    let e2 = F * (2.0 - F);
    let (lat, lon) = (latitude_deg.to_radians(), longitude_deg.to_radians());
    let n = A / (1.0 - e2 * lat.sin().powi(2)).sqrt();
    [
        (n + altitude_m) * lat.cos() * lon.cos(),
        (n + altitude_m) * lat.cos() * lon.sin(),
        (n * (1.0 - e2) + altitude_m) * lat.sin(),
    ]
}

/// A local east-north-up frame with its origin at a reference fix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalEnu {
    origin: [f64; 3],
    /// Rows: the east, north and up unit vectors in ECEF.
    axes: [[f64; 3]; 3],
}

impl LocalEnu {
    /// The frame about the fix (degrees, degrees, metres).
    pub fn new(latitude_deg: f64, longitude_deg: f64, altitude_m: f64) -> Self {
        let (lat, lon) = (latitude_deg.to_radians(), longitude_deg.to_radians());
        let (sl, cl, so, co) = (lat.sin(), lat.cos(), lon.sin(), lon.cos());
        Self {
            origin: ecef(latitude_deg, longitude_deg, altitude_m),
            axes: [
                [-so, co, 0.0],
                [-sl * co, -sl * so, cl],
                [cl * co, cl * so, sl],
            ],
        }
    }

    /// East, north, up (m) of a fix.
    pub fn to_enu(&self, latitude_deg: f64, longitude_deg: f64, altitude_m: f64) -> [f64; 3] {
        let p = ecef(latitude_deg, longitude_deg, altitude_m);
        let d = [
            p[0] - self.origin[0],
            p[1] - self.origin[1],
            p[2] - self.origin[2],
        ];
        self.axes
            .map(|axis| axis[0] * d[0] + axis[1] * d[1] + axis[2] * d[2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reference_is_the_origin_and_up_is_altitude() {
        let enu = LocalEnu::new(42.375812, -71.147395, 10.0);
        let o = enu.to_enu(42.375812, -71.147395, 10.0);
        assert!(o.iter().all(|v| v.abs() < 1e-9), "{o:?}");
        let up = enu.to_enu(42.375812, -71.147395, 25.0);
        assert!((up[2] - 15.0).abs() < 1e-9 && up[0].abs() < 1e-9 && up[1].abs() < 1e-9);
    }

    #[test]
    fn small_steps_match_the_meridian_and_parallel_radii() {
        // Closed form: north per radian of latitude is the meridian radius
        // M = a(1 − e²)/(1 − e² sin²φ)^{3/2}; east per radian of longitude is
        // N cos φ with N = a/√(1 − e² sin²φ).
        let (lat, lon) = (42.375812f64, -71.147395f64);
        let e2 = F * (2.0 - F);
        let s2 = lat.to_radians().sin().powi(2);
        let m = A * (1.0 - e2) / (1.0 - e2 * s2).powf(1.5);
        let n = A / (1.0 - e2 * s2).sqrt();
        let enu = LocalEnu::new(lat, lon, 0.0);
        let d = 1e-5; // degrees: about a metre
        let north = enu.to_enu(lat + d, lon, 0.0);
        assert!((north[1] - m * d.to_radians()).abs() < 1e-4, "{north:?}");
        assert!(north[0].abs() < 1e-6);
        let east = enu.to_enu(lat, lon + d, 0.0);
        let expected = n * lat.to_radians().cos() * d.to_radians();
        assert!((east[0] - expected).abs() < 1e-4, "{east:?} vs {expected}");
        assert!(east[1].abs() < 1e-4);
    }

    #[test]
    fn the_equator_and_prime_meridian_map_to_the_axes() {
        let p = ecef(0.0, 0.0, 0.0);
        assert!((p[0] - A).abs() < 1e-6 && p[1].abs() < 1e-6 && p[2].abs() < 1e-6);
        let pole = ecef(90.0, 0.0, 0.0);
        let b = A * (1.0 - F);
        assert!((pole[2] - b).abs() < 1e-6, "{pole:?}");
    }
}
