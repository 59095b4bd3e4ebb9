//! The statistical tracker's covisible keyframes: what the stereo VO's
//! local bundle adjustment does to the links between keyframes, drawn from
//! ground truth as the tracker's measurements are.
//!
//! On a new keyframe, the window is that keyframe and up to
//! `covisibility_keyframes` keyframes behind it along the links they were
//! placed by. Every two window keyframes that are not linked already and
//! whose views overlap by at least `covisible_min_overlap` are measured
//! against each other, the older as the reference: a relative pose drawn
//! as a tracking request between them would be, with the error at their
//! overlap and, under `error_model: shared`, the older keyframe's map
//! error, which the links tracked against it share. Each pair's draw is
//! keyed by the seed and the two frames, so the same pair measures the
//! same at every adjustment and in every run.
//!
//! The window's keyframes are then placed by all those measurements and
//! the links at once, by least squares with each measurement weighed by
//! its own covariance and the oldest keyframe held fixed (the map's frame,
//! as in the stereo VO's adjustment). A keyframe seen by several others
//! is placed by all of them, so where keyframes are dense their links are
//! averaged and where they are sparse they stand as tracked. The
//! refined links, each with its covariance from the solution, replace the
//! tracked ones in the front end's pose graph; like the stereo VO's after
//! its adjustment, their errors are correlated with each other, which the
//! pose graph does not see.
//!
//! The least squares is in the errors, to first order: a measurement of
//! `reference_from_current` is the truth `T` times `Exp(δ)`, and with the
//! keyframes at `T_i · Exp(ε_i)` it predicts `T · Exp(ε_c − Ad(T⁻¹) ε_r)`.

use std::collections::HashMap;

use nalgebra::{DMatrix, DVector, Isometry3, Matrix6, Vector6};

use super::SimulatedVo;
use crate::vo::{FrameRef, RefinedLink, TrackPurpose, TrackRequest, VoMeasurement, adjoint};

/// The generator key of a covisible pair's measurement (apart from the
/// request purposes 1–3, place recognition's 0 and the map error's 16).
const COVISIBLE_PAIR_KEY: u64 = 17;

/// A keyframe's link as tracked: its reference, the measured
/// `reference_from_keyframe` and its covariance.
#[derive(Debug, Clone, Copy)]
struct Link {
    reference: FrameRef,
    relative: Isometry3<f64>,
    covariance: Matrix6<f64>,
}

/// The keyframes' tracked links, and the last measurement (which becomes
/// a keyframe's link when its frame is made a keyframe).
#[derive(Debug, Clone, Default)]
pub struct Links {
    last: Option<(FrameRef, Link)>,
    links: HashMap<usize, Link>,
}

impl Links {
    /// Notes a successful tracking or relocalisation measurement.
    pub(super) fn tracked(&mut self, request: &TrackRequest, m: &VoMeasurement) {
        self.last = Some((
            request.current,
            Link {
                reference: request.reference,
                relative: m.relative,
                covariance: m.covariance,
            },
        ));
    }
}

/// One relative measurement in the window: reference and current (window
/// places), the truth of `reference_from_current`, the measurement's error
/// `δ` against it, and its information.
struct Measured {
    reference: usize,
    current: usize,
    truth: Isometry3<f64>,
    error: Vector6<f64>,
    information: Matrix6<f64>,
}

/// `δ` with `measured = truth · Exp(δ)`, `[rotation; translation]` (first
/// order, as the tracker's noise is applied).
fn right_error(truth: &Isometry3<f64>, measured: &Isometry3<f64>) -> Vector6<f64> {
    let d = truth.inverse() * measured;
    let (r, t) = (d.rotation.scaled_axis(), d.translation.vector);
    Vector6::new(r.x, r.y, r.z, t.x, t.y, t.z)
}

/// `truth · Exp(δ)`, as the tracker applies its noise.
fn right_perturbed(truth: &Isometry3<f64>, delta: &Vector6<f64>) -> Isometry3<f64> {
    truth
        * Isometry3::from_parts(
            nalgebra::Translation3::new(delta[3], delta[4], delta[5]),
            nalgebra::UnitQuaternion::from_scaled_axis(delta.fixed_rows::<3>(0).into_owned()),
        )
}

impl SimulatedVo {
    /// The window of a new keyframe: it and up to `count` keyframes
    /// behind it along their links, newest first.
    fn covisibility_window(&self, keyframe: FrameRef, count: usize) -> Vec<FrameRef> {
        let mut window = vec![keyframe];
        let mut at = keyframe.index;
        while window.len() <= count {
            let Some(link) = self.covisibility.links.get(&at) else {
                break;
            };
            if window.iter().any(|f| f.index == link.reference.index) {
                break;
            }
            window.push(link.reference);
            at = link.reference.index;
        }
        window
    }

    /// The covisible pair's measurement of `reference_from_current`
    /// (`reference` the older keyframe) and its covariance, drawn as a
    /// tracking request between them would be (see the module); `None`
    /// below `covisible_min_overlap` or outside the traverse.
    pub fn covisible_measurement(
        &self,
        reference: FrameRef,
        current: FrameRef,
    ) -> Option<(Isometry3<f64>, Matrix6<f64>)> {
        let truth = self.truth(reference, current)?;
        let overlap = self.params.camera.body_overlap(&truth);
        if overlap < self.params.covisible_min_overlap {
            return None;
        }
        let request = TrackRequest {
            reference,
            current,
            prior: None,
            purpose: TrackPurpose::Tracking,
        };
        let sigmas = self.request_sigmas(&request, &truth, overlap);
        let mut rng = self.rng(COVISIBLE_PAIR_KEY, reference.index, current.index);
        let noise = self.drawn_error(&mut rng, reference.index, sigmas);
        Some((
            truth * noise,
            crate::vo::isotropic_covariance(sigmas.0, sigmas.1),
        ))
    }

    /// The covisible keyframes' adjustment on the new keyframe `keyframe`
    /// (see the module): the refined links of its window, oldest first;
    /// none when it is off, the keyframe was not placed by the last
    /// measurement, or it has no keyframe behind it.
    pub(super) fn adjust_covisible(&mut self, keyframe: FrameRef) -> Vec<RefinedLink> {
        let count = self.params.covisibility_keyframes;
        let last = self.covisibility.last.take();
        if count == 0 {
            return Vec::new();
        }
        let Some((_, link)) = last.filter(|(current, _)| current.index == keyframe.index) else {
            return Vec::new();
        };
        self.covisibility.links.insert(keyframe.index, link);
        let window = self.covisibility_window(keyframe, count);
        if window.len() < 2 {
            return Vec::new();
        }
        let place: HashMap<usize, usize> = window
            .iter()
            .enumerate()
            .map(|(i, f)| (f.index, i))
            .collect();
        // The window's links, as tracked: `(current, reference)` places,
        // the truth of `reference_from_current`, the link.
        let linked: Vec<(usize, usize, Isometry3<f64>, Link)> = window[..window.len() - 1]
            .iter()
            .enumerate()
            .filter_map(|(c, frame)| {
                let link = *self.covisibility.links.get(&frame.index)?;
                let r = *place.get(&link.reference.index)?;
                Some((c, r, self.truth(link.reference, *frame)?, link))
            })
            .collect();
        let mut measured: Vec<Measured> = linked
            .iter()
            .filter_map(|(c, r, truth, link)| {
                Some(Measured {
                    reference: *r,
                    current: *c,
                    truth: *truth,
                    error: right_error(truth, &link.relative),
                    information: link.covariance.try_inverse()?,
                })
            })
            .collect();
        // The covisible pairs not linked already, older as reference.
        for (c, current) in window.iter().enumerate() {
            for (r, reference) in window.iter().enumerate().skip(c + 1) {
                if linked
                    .iter()
                    .any(|(a, b, _, _)| (*a, *b) == (c, r) || (*a, *b) == (r, c))
                {
                    continue;
                }
                let (Some((relative, covariance)), Some(truth)) = (
                    self.covisible_measurement(*reference, *current),
                    self.truth(*reference, *current),
                ) else {
                    continue;
                };
                let error = right_error(&truth, &relative);
                let Some(information) = covariance.try_inverse() else {
                    continue;
                };
                measured.push(Measured {
                    reference: r,
                    current: c,
                    truth,
                    error,
                    information,
                });
            }
        }
        let Some((errors, covariance)) = solve_window(window.len() - 1, &measured) else {
            return Vec::new();
        };
        // Each link's refined error `ε_c − Ad(T⁻¹) ε_r` and its covariance.
        let oldest = window.len() - 1;
        let mut refined = Vec::new();
        for (c, r, truth, link) in linked.iter().rev() {
            let (c, r) = (*c, *r);
            let a = adjoint(&truth.inverse());
            let mut jacobian = DMatrix::zeros(6, 6 * oldest);
            jacobian
                .fixed_view_mut::<6, 6>(0, 6 * c)
                .copy_from(&Matrix6::identity());
            if r < oldest {
                jacobian.fixed_view_mut::<6, 6>(0, 6 * r).copy_from(&(-a));
            }
            let error = &jacobian * &errors;
            let link_covariance = &jacobian * &covariance * jacobian.transpose();
            let error = Vector6::from_iterator(error.iter().copied());
            let link_covariance: Matrix6<f64> =
                link_covariance.fixed_view::<6, 6>(0, 0).into_owned();
            refined.push(RefinedLink {
                reference: link.reference,
                current: window[c],
                relative: right_perturbed(truth, &error),
                covariance: 0.5 * (link_covariance + link_covariance.transpose()),
            });
        }
        refined
    }
}

/// The window keyframes' errors (all but the `oldest`, which is fixed,
/// stacked newest first) that best explain `measured`, and their
/// covariance; `None` when the measurements do not hold every
/// keyframe.
fn solve_window(oldest: usize, measured: &[Measured]) -> Option<(DVector<f64>, DMatrix<f64>)> {
    let n = 6 * oldest;
    let mut h = DMatrix::<f64>::zeros(n, n);
    let mut g = DVector::<f64>::zeros(n);
    for m in measured {
        let a = adjoint(&m.truth.inverse());
        // The prediction's Jacobians: I for the current, −Ad(T⁻¹) for
        // the reference; the fixed oldest has none.
        let blocks = [(m.current, Matrix6::identity()), (m.reference, -a)];
        for (i, ji) in blocks.iter().filter(|(i, _)| *i < oldest) {
            let wi = ji.transpose() * m.information;
            let mut gi = g.fixed_rows_mut::<6>(6 * i);
            gi += wi * m.error;
            for (j, jj) in blocks.iter().filter(|(j, _)| *j < oldest) {
                let mut hij = h.fixed_view_mut::<6, 6>(6 * i, 6 * j);
                hij += wi * jj;
            }
        }
    }
    let covariance = h.cholesky()?.inverse();
    let errors = &covariance * g;
    Some((errors, covariance))
}
