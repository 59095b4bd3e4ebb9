//! The real ground images of `../shared/data/images/` (which the camera's
//! tests may read): every named box lies inside its image, and the table of
//! their measurements in `testbed/README.md` is what the images give.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

use gpodo_testbed::real_images::{REAL_BOXES, markdown_table, measure_real_boxes, orb_image_table};

#[test]
fn the_readme_table_of_real_image_boxes_is_what_the_images_give() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let measured = measure_real_boxes(&root.join("../../shared/data/images")).unwrap();
    assert_eq!(measured.len(), REAL_BOXES.len());
    // Sand has fewer corners than rock at either threshold, in the PRL.
    let density = |name: &str, k: usize| {
        measured
            .iter()
            .find(|m| m.region.name == name)
            .map(|m| m.corners_per_10k_px[k])
            .unwrap()
    };
    for k in 0..2 {
        assert!(density("prl-sand-navcam", k) < density("prl-rock-large", k));
    }
    let table = markdown_table(&measured);
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    assert!(
        readme.contains(&table),
        "testbed/README.md should hold the table the images give:\n{table}"
    );
    let orb = orb_image_table(&root.join("../../shared/data/images")).unwrap();
    assert!(
        readme.contains(&orb),
        "testbed/README.md should hold the ORB counts the images give:\n{orb}"
    );
}

#[test]
fn each_rendered_soil_is_within_a_factor_one_and_a_half_of_its_real_counterpart() {
    use gpodo_testbed::camera::calibration::{compare_soils, comparison_table};
    use gpodo_testbed::camera::{SceneSpec, SensorSpec};
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let real = measure_real_boxes(&root.join("../../shared/data/images")).unwrap();
    let comparisons = compare_soils(&real, &SceneSpec::default(), SensorSpec::default()).unwrap();
    let table = comparison_table(&comparisons);
    for c in &comparisons {
        for ratio in c.ratios() {
            assert!(
                (1.0 / 1.5..=1.5).contains(&ratio),
                "{} off by {ratio}:\n{table}",
                c.rendered.soil
            );
        }
    }
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    assert!(
        readme.contains(&table),
        "testbed/README.md should hold the comparison the renders give:\n{table}"
    );
}
