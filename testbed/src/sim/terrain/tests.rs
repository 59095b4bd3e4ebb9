//! Tests of [`super`].
use super::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn default_terrain(seed: u64) -> Terrain {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    Terrain::generate(&TerrainSpec::default(), &mut rng).unwrap()
}

fn sample_points(size: f64) -> Vec<(f64, f64)> {
    let mut rng = ChaCha8Rng::seed_from_u64(99);
    (0..200)
        .map(|_| {
            (
                uniform(&mut rng, (-0.5 * size, 1.5 * size)),
                uniform(&mut rng, (-0.5 * size, 1.5 * size)),
            )
        })
        .collect()
}

#[test]
fn generated_terrain_reaches_the_requested_max_slope() {
    for seed in 0..4 {
        let terrain = default_terrain(seed);
        assert!(
            (terrain.max_slope_deg() - 20.0).abs() < 0.05,
            "{}",
            terrain.max_slope_deg()
        );
        let steepest = slope_grid(9.0)
            .iter()
            .map(|p| terrain.gradient(p.x, p.y).norm().atan().to_degrees())
            .fold(0.0, f64::max);
        assert!((steepest - terrain.max_slope_deg()).abs() < 1e-6);
    }
}

#[test]
fn gradient_matches_finite_differences() {
    let terrain = default_terrain(1);
    let h = 1e-5;
    for (x, y) in sample_points(9.0) {
        let g = terrain.gradient(x, y);
        let fd_x = (terrain.height(x + h, y) - terrain.height(x - h, y)) / (2.0 * h);
        let fd_y = (terrain.height(x, y + h) - terrain.height(x, y - h)) / (2.0 * h);
        assert!(
            (fd_x - g.x).abs() <= 1e-7 * (g.x.abs() + 1e-3),
            "x at ({x}, {y})"
        );
        assert!(
            (fd_y - g.y).abs() <= 1e-7 * (g.y.abs() + 1e-3),
            "y at ({x}, {y})"
        );
    }
}

#[test]
fn normal_is_unit_points_up_and_is_orthogonal_to_the_surface() {
    let terrain = default_terrain(2);
    for (x, y) in sample_points(9.0) {
        let n = terrain.normal(x, y);
        let g = terrain.gradient(x, y);
        assert!((n.norm() - 1.0).abs() < 1e-12 && n.z > 0.0);
        assert!(n.dot(&Vector3::new(1.0, 0.0, g.x)).abs() < 1e-12);
        assert!(n.dot(&Vector3::new(0.0, 1.0, g.y)).abs() < 1e-12);
    }
}

#[test]
fn terrain_is_finite_far_outside_the_area() {
    let terrain = default_terrain(3);
    for &(x, y) in &[(-1e4, 3.0), (1e5, -1e5), (4.5, 1e6)] {
        assert!(terrain.height(x, y).is_finite());
        assert!(terrain.normal(x, y).iter().all(|c| c.is_finite()));
    }
}

#[test]
fn generated_heights_have_zero_mean_over_the_area() {
    let terrain = default_terrain(4);
    let grid = slope_grid(9.0);
    let mean = grid.iter().map(|p| terrain.height(p.x, p.y)).sum::<f64>() / grid.len() as f64;
    assert!(mean.abs() < 1e-12);
}

#[test]
fn same_seed_gives_the_same_terrain_and_different_seeds_differ() {
    assert_eq!(default_terrain(5), default_terrain(5));
    assert_ne!(
        default_terrain(5).height(4.5, 4.5),
        default_terrain(6).height(4.5, 4.5)
    );
}

#[test]
fn plane_has_the_requested_slope_and_downhill_direction() {
    let azimuth = 0.7;
    let terrain = Terrain::plane(9.0, 15.0, azimuth).unwrap();
    let g = terrain.gradient(1.0, 8.0);
    assert!((g.norm().atan().to_degrees() - 15.0).abs() < 1e-12);
    let downhill = Vector2::new(azimuth.cos(), azimuth.sin());
    assert!(terrain.height(4.5 + downhill.x, 4.5 + downhill.y) < terrain.height(4.5, 4.5));
    assert!((terrain.gradient(0.0, 0.0) - g).norm() < 1e-15);
    assert_eq!(terrain.max_slope_deg(), 15.0);
}

#[test]
fn flat_terrain_is_level_everywhere() {
    let terrain = Terrain::flat(9.0).unwrap();
    assert_eq!(terrain.height(2.0, 7.0), 0.0);
    assert_eq!(terrain.normal(-3.0, 12.0), Vector3::z());
}

#[test]
fn spec_validation_names_the_bad_field() {
    let cases = [
        (
            TerrainSpec {
                size_m: -1.0,
                ..TerrainSpec::default()
            },
            "size_m",
        ),
        (
            TerrainSpec {
                max_slope_deg: 75.0,
                ..TerrainSpec::default()
            },
            "max_slope_deg",
        ),
        (
            TerrainSpec {
                roughness_m: f64::NAN,
                ..TerrainSpec::default()
            },
            "roughness_m",
        ),
        (
            TerrainSpec {
                hills: 1000,
                ..TerrainSpec::default()
            },
            "hills",
        ),
    ];
    for (spec, name) in cases {
        let err = spec.validate().unwrap_err();
        assert!(matches!(err, TestbedError::InvalidConfig { ref field, .. } if field == name));
    }
}

#[test]
fn bumps_steeper_than_the_max_slope_are_rejected() {
    let spec = TerrainSpec {
        max_slope_deg: 1.0,
        roughness_m: 0.05,
        ..TerrainSpec::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let err = Terrain::generate(&spec, &mut rng).unwrap_err();
    assert!(matches!(err, TestbedError::InvalidConfig { ref field, .. } if field == "roughness_m"));
}

#[test]
fn terrain_without_hills_is_a_rescaled_plane_with_bumps() {
    let spec = TerrainSpec {
        hills: 0,
        max_slope_deg: 5.0,
        ..TerrainSpec::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let terrain = Terrain::generate(&spec, &mut rng).unwrap();
    assert!((terrain.max_slope_deg() - 5.0).abs() < 0.05);
}
