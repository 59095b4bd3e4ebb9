//! The front end takes the keyframe links a VO's local bundle adjustment
//! refined ([`VisualOdometry::keyframe_inserted`]): they replace the
//! visual edges that placed those keyframes in the pose graph, and re-place
//! the keyframes on the visual map that later frames are tracked on.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use gpodo_frontends::params::{FrontendParams, VoSpec};
use gpodo_frontends::prediction::{Precomputed, ResidualPrediction};
use gpodo_frontends::run::FrontendRun;
use gpodo_frontends::traverse::Traverse;
use gpodo_frontends::vo::{
    ErrorStructure, FrameRef, RefinedLink, SimulatedVo, SimulatedVoParams, TrackOutcome,
    TrackRequest, VisualOdometry, VoMeasurement,
};
use gpodo_frontends::{FixedRate, run_frontend};
use nalgebra::{Isometry3, Vector3};

use common::{earlier_tracker, s_curve, traverse};

/// The statistical tracker, whose "adjustment" hands back each new
/// keyframe's tracked link moved by `shift_m` along its x axis.
struct Refining {
    inner: SimulatedVo,
    shift_m: f64,
    last: Option<(FrameRef, FrameRef, VoMeasurement)>,
    refined: usize,
}

impl VisualOdometry for Refining {
    fn name(&self) -> &str {
        "refining"
    }

    fn error_structure(&self) -> ErrorStructure {
        self.inner.error_structure()
    }

    fn track(&mut self, request: &TrackRequest) -> TrackOutcome {
        let outcome = self.inner.track(request);
        if let TrackOutcome::Tracked(m) = &outcome {
            self.last = Some((request.reference, request.current, *m));
        }
        outcome
    }

    fn success_probability(&self, request: &TrackRequest) -> f64 {
        self.inner.success_probability(request)
    }

    fn predicted_overlap(&self, reference: FrameRef, current: FrameRef) -> Option<f64> {
        self.inner.predicted_overlap(reference, current)
    }

    fn recognise(&self, current: FrameRef, keyframes: &[FrameRef]) -> Vec<FrameRef> {
        self.inner.recognise(current, keyframes)
    }

    fn keyframe_inserted(&mut self, keyframe: FrameRef) -> Vec<RefinedLink> {
        match self.last {
            Some((reference, current, m)) if current.index == keyframe.index => {
                self.refined += 1;
                vec![RefinedLink {
                    reference,
                    current,
                    relative: m.relative * Isometry3::translation(self.shift_m, 0.0, 0.0),
                    covariance: m.covariance,
                }]
            }
            _ => Vec::new(),
        }
    }
}

fn run(t: &Traverse, vo: &mut dyn VisualOdometry) -> FrontendRun {
    let p = FrontendParams {
        vo: VoSpec::Simulated(earlier_tracker()),
        ..FrontendParams::default()
    };
    let mut selector = FixedRate::new(2.5).unwrap();
    let mut source = Precomputed::new(
        "zero",
        vec![ResidualPrediction::uninformed(1e-6); t.windows().len()],
    );
    run_frontend(t, &p, &mut selector, &mut source, vo).unwrap()
}

fn refining(t: &Traverse, vo: SimulatedVoParams, shift_m: f64) -> Refining {
    Refining {
        inner: SimulatedVo::new(vo, t).unwrap(),
        shift_m,
        last: None,
        refined: 0,
    }
}

#[test]
fn refined_keyframe_links_replace_the_visual_edges_and_re_place_the_keyframes() {
    let t = traverse(120.0, s_curve, Vector3::zeros(), &[0.0]);
    let vo = earlier_tracker();
    let plain = run(&t, &mut SimulatedVo::new(vo, &t).unwrap());
    assert!(plain.keyframes >= 3, "{} keyframes", plain.keyframes);

    // The tracked links handed back unchanged: nothing moves.
    let mut same = refining(&t, vo, 0.0);
    let unchanged = run(&t, &mut same);
    assert_eq!(same.refined, plain.keyframes - 1);
    assert_eq!(unchanged.trajectory, plain.trajectory);
    assert_eq!(unchanged.processed, plain.processed);

    // Moved by 0.5 m: the second keyframe (the first refined, on the map's
    // origin keyframe) sits 0.5 m along its x axis from where it was
    // tracked, and the optimised trajectory follows the replaced edges.
    let mut moved = refining(&t, vo, 0.5);
    let shifted = run(&t, &mut moved);
    assert_eq!(moved.refined, same.refined);
    let second = plain
        .processed
        .iter()
        .filter(|f| f.keyframe)
        .nth(1)
        .unwrap();
    let at = |r: &FrontendRun| {
        r.processed
            .iter()
            .find(|f| f.frame == second.frame)
            .and_then(|f| f.vo_pose)
            .unwrap()
    };
    let expected = at(&plain) * Isometry3::translation(0.5, 0.0, 0.0);
    let got = at(&shifted);
    assert!(
        (got.translation.vector - expected.translation.vector).norm() < 1e-9,
        "{got} against {expected}"
    );
    let moved_m = shifted
        .trajectory
        .iter()
        .zip(&plain.trajectory)
        .map(|(a, b)| (a.translation.vector - b.translation.vector).norm())
        .fold(0.0, f64::max);
    assert!(moved_m > 0.1, "the trajectory moved {moved_m} m");
}
