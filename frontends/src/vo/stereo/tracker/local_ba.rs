//! ORB-SLAM2's local bundle adjustment on a new keyframe
//! (`LocalMapping::LocalBundleAdjustment`), in this VO's terms.
//!
//! The window is the new keyframe and up to `local_ba_keyframes` keyframes
//! behind it along the links it was tracked by, placed by those links.
//! Each window keyframe's map points (its own stereo triangulations) are
//! projected into the others and matched as the local map matches them
//! (`local_map_radius_px`, the ratio test); a keypoint takes part in one
//! point only, so a point that several keyframes triangulated is one
//! point, owned by the newest. The new keyframe is adjusted with the
//! keyframes that share at least `covisible_min_points` points with it;
//! the others, and always the oldest (the map's frame, as the keyframes
//! outside ORB-SLAM2's local window are), are held fixed. The refined
//! links become the keyframes' links here and the visual edges of the
//! front end's pose graph, each with its covariance from the adjustment
//! (the map points marginalised). The refined points go back to the
//! keyframes that see them, with their covariance given the adjusted
//! poses, and later frames are tracked against them.

use nalgebra::{Isometry3, Matrix6};

use super::super::bundle::{
    Adjusted, BundleSettings, LocalMap, Observation, local_bundle_adjustment,
};
use super::super::frames::Cached;
use super::super::grid::KeypointGrid;
use super::StereoVo;
use crate::vo::{FrameRef, RefinedLink, adjoint};
use gpodo_vision::stereo::StereoFeatures;

/// The observation of keypoint `k` of `features` by window keyframe
/// `keyframe` (its point set later).
fn observation(keyframe: usize, features: &StereoFeatures, k: usize) -> Observation {
    let kp = &features.left.keypoints[k];
    Observation {
        keyframe,
        point: 0,
        left_px: [f64::from(kp.x), f64::from(kp.y)],
        right_x: features.right_x[k].map(f64::from),
        sigma_px: features.left.scales[usize::from(kp.level)],
    }
}

impl StereoVo {
    /// The local bundle adjustment on the new keyframe `keyframe` (see the
    /// module): its refined links, oldest first, each with the body
    /// motion and covariance a tracked measurement has; none when it is
    /// off, the keyframe has no keyframe behind it, or the adjustment
    /// fails.
    pub(super) fn adjust_local_map(&mut self, keyframe: FrameRef) -> Vec<RefinedLink> {
        let count = self.params.local_ba_keyframes;
        if count == 0 {
            return Vec::new();
        }
        // `keyframe_from_it` of each window keyframe, the new one first.
        let mut window = vec![(keyframe, Isometry3::identity())];
        window.extend(self.chained_keyframes(keyframe.index, count));
        if window.len() < 2 {
            return Vec::new();
        }
        let cached: Vec<Cached> = window.iter().map(|(f, _)| self.features(*f)).collect();
        let Some(stereo) = cached
            .iter()
            .map(|c| c.as_ref().as_ref().ok().map(|f| &f.stereo))
            .collect::<Option<Vec<&StereoFeatures>>>()
        else {
            return Vec::new();
        };
        let grids: Vec<KeypointGrid> = stereo.iter().map(|s| KeypointGrid::new(s)).collect();
        let mut taken: Vec<Vec<bool>> = stereo
            .iter()
            .map(|s| vec![false; s.left.keypoints.len()])
            .collect();
        // The map's frame is the new keyframe's camera.
        let poses: Vec<Isometry3<f64>> = window.iter().map(|(_, p)| p.inverse()).collect();
        let mut points = Vec::new();
        let mut observations = Vec::new();
        // Per observation, the keypoint it is.
        let mut keypoints = Vec::new();
        let mut shared = vec![0_usize; window.len()];
        for (i, &features) in stereo.iter().enumerate() {
            for (k, point, _) in self.map_points(window[i].0, features) {
                if taken[i][k] {
                    continue;
                }
                let world = window[i].1 * point;
                let level = usize::from(features.left.keypoints[k].level);
                let radius = self.params.local_map_radius_px * features.left.scales[level];
                let mut seen = vec![(observation(i, features, k), k)];
                for (j, &other) in stereo.iter().enumerate() {
                    if j == i {
                        continue;
                    }
                    let Some(centre) = self.in_image(&(poses[j] * world)) else {
                        continue;
                    };
                    if let Some(found) =
                        self.best_match((features, k), (centre, radius), other, &grids[j])
                        && !taken[j][found]
                    {
                        seen.push((observation(j, other, found), found));
                    }
                }
                if seen.len() < 2 {
                    continue;
                }
                let index = points.len();
                points.push(world);
                let by_new = seen.iter().any(|(o, _)| o.keyframe == 0);
                for (o, found) in seen {
                    taken[o.keyframe][found] = true;
                    if by_new && o.keyframe != 0 {
                        shared[o.keyframe] += 1;
                    }
                    observations.push(Observation { point: index, ..o });
                    keypoints.push(found);
                }
            }
        }
        let last = window.len() - 1;
        let fixed: Vec<bool> = (0..window.len())
            .map(|j| j == last || (j != 0 && shared[j] < self.params.covisible_min_points))
            .collect();
        let map = LocalMap {
            poses,
            fixed,
            points,
            observations,
        };
        let adjusted =
            match local_bundle_adjustment(&map, &self.intrinsics, &BundleSettings::default()) {
                Ok(a) => a,
                Err(e) => {
                    tracing::debug!(keyframe = keyframe.index, "local bundle adjustment: {e}");
                    return Vec::new();
                }
            };
        // Each free keyframe's block in the covariance.
        let mut block = vec![None; window.len()];
        let mut next = 0;
        for (j, f) in map.fixed.iter().enumerate() {
            if !f {
                block[j] = Some(next);
                next += 1;
            }
        }
        // A free keyframe the points do not hold (its covariance cannot
        // be had): the tracked links stand.
        if adjusted.pose_covariance.nrows() != 6 * next {
            tracing::debug!(
                keyframe = keyframe.index,
                "local bundle adjustment: a free keyframe unconstrained, links kept"
            );
            return Vec::new();
        }
        let sigma = |a: Option<usize>, b: Option<usize>| -> Matrix6<f64> {
            match (a, b) {
                (Some(a), Some(b)) => adjusted
                    .pose_covariance
                    .fixed_view::<6, 6>(6 * a, 6 * b)
                    .into_owned(),
                _ => Matrix6::zeros(),
            }
        };
        self.keep_refined_points(&window, &map, &adjusted, &keypoints);
        let mut links = Vec::new();
        for m in (0..last).rev() {
            let (child, parent) = (m, m + 1);
            if map.fixed[child] && map.fixed[parent] {
                continue;
            }
            // `child_from_parent`, and its left-perturbation covariance:
            // δ = δ_child − Ad(child_from_parent) δ_parent.
            let relative = adjusted.poses[child] * adjusted.poses[parent].inverse();
            let a = adjoint(&relative);
            let (c, p) = (block[child], block[parent]);
            let covariance = sigma(c, c) - sigma(c, p) * a.transpose() - a * sigma(p, c)
                + a * sigma(p, p) * a.transpose();
            let covariance = 0.5 * (covariance + covariance.transpose());
            if covariance.cholesky().is_none() {
                // The reduced system's inverse can lose definiteness to
                // cancellation where the points barely hold a keyframe:
                // that link stands as tracked.
                continue;
            }
            self.parents
                .insert(window[child].0.index, (window[parent].0, relative));
            let (body, body_covariance) = self.body_motion(&relative, &covariance);
            links.push(RefinedLink {
                reference: window[parent].0,
                current: window[child].0,
                relative: body,
                covariance: body_covariance,
            });
        }
        tracing::trace!(
            keyframe = keyframe.index,
            window = window.len(),
            points = map.points.len(),
            chi2 = ?adjusted.chi2,
            "local bundle adjustment"
        );
        links
    }

    /// Hands the adjusted points back to the keyframes that see them: each
    /// kept observation's keypoint takes its point, in its keyframe's
    /// camera, with the point's covariance given the adjusted poses, so
    /// later frames are tracked against the refined map (as ORB-SLAM2's
    /// are against its shared map points). A point its keyframes no longer
    /// agree on (fewer than two kept observations) is left as it was.
    fn keep_refined_points(
        &mut self,
        window: &[(FrameRef, Isometry3<f64>)],
        map: &LocalMap,
        adjusted: &Adjusted,
        keypoints: &[usize],
    ) {
        let mut kept = vec![0_usize; map.points.len()];
        for (o, inlier) in map.observations.iter().zip(&adjusted.inliers) {
            if *inlier {
                kept[o.point] += 1;
            }
        }
        for ((o, inlier), &k) in map
            .observations
            .iter()
            .zip(&adjusted.inliers)
            .zip(keypoints)
        {
            let Some(covariance) = adjusted.point_covariance[o.point] else {
                continue;
            };
            if !*inlier || kept[o.point] < 2 {
                continue;
            }
            let pose = &adjusted.poses[o.keyframe];
            let r = pose.rotation.to_rotation_matrix().into_inner();
            self.refined_points
                .entry(window[o.keyframe].0.index)
                .or_default()
                .insert(
                    k,
                    (
                        pose * adjusted.points[o.point],
                        r * covariance * r.transpose(),
                    ),
                );
        }
    }
}
