//! The camera a run's stereo VO reads: each test traverse's frames
//! rendered from its ground truth over the simulated testbed's ground, or
//! a recording's own images.

use std::sync::{Arc, OnceLock};
use std::time::Instant;

use gpodo_datasets::bags::frames::BagFrames;
use gpodo_frontends::traverse::Traverse;
use gpodo_frontends::vo::stereo::{LocalMapPlacement, StereoFrames};
use gpodo_testbed::camera::{FramePose, GroundMaps, RenderedFrames, SceneSpec, SensorSpec};
use gpodo_traits::{CameraParams, FrameRef};
use rayon::prelude::*;

use crate::config::ExperimentConfig;
use crate::error::PipelineError;
use crate::execute::data::PreparedData;

/// A dataset's ground maps, built the first time a run asks for them (or
/// why they could not be).
pub(crate) type GroundCell = OnceLock<Result<Arc<GroundMaps>, String>>;

/// Each test traverse's camera frames, rendered on demand from its ground
/// truth through the stereo VO's camera, for a run whose VO reads images
/// (none otherwise). The testbed's ground maps are built once per
/// dataset; each traverse's frames are rendered (or read) and their
/// features found once per run, shared by its schemes: the frames of the
/// fixed-rate schemes up front and in parallel, any other when a scheme
/// first asks for it.
pub(crate) fn camera_frames(
    config: &ExperimentConfig,
    data: &PreparedData,
    ground: &GroundCell,
    traverses: &[Traverse],
) -> Result<Vec<Option<Arc<StereoFrames>>>, PipelineError> {
    let frames = camera_sources(config, data, ground, traverses)?;
    let start = Instant::now();
    for (traverse, frames) in traverses.iter().zip(&frames) {
        if let Some(frames) = frames {
            let times = traverse.camera_times_secs();
            fixed_rate_frames(config, times)
                .par_iter()
                .for_each(|&index| {
                    let _ = frames.features(FrameRef {
                        index,
                        time_secs: times[index],
                    });
                });
        }
    }
    if frames.iter().any(Option::is_some) {
        tracing::info!(
            secs = start.elapsed().as_secs_f64(),
            "camera frames rendered and their features found"
        );
    }
    Ok(frames)
}

/// The camera frames (indices into `times`) that the fixed-rate schemes
/// of `config` process, which they do whatever happens: each rate's
/// schedule, as its selector makes it, merged.
fn fixed_rate_frames(config: &ExperimentConfig, times: &[f64]) -> Vec<usize> {
    use gpodo_frontends::FixedRate;
    use gpodo_frontends::spec::SelectorSpec;
    use gpodo_traits::{FrameContext, FrameSelector};
    let mut frames: Vec<usize> = config
        .schemes
        .iter()
        .filter_map(|s| match s.selector {
            SelectorSpec::FixedRate { fps, phase_secs } => FixedRate::new(fps)
                .and_then(|s| s.with_phase(phase_secs))
                .ok(),
            SelectorSpec::ResidualSchedule(_)
            | SelectorSpec::UncertaintyBudget(_)
            | SelectorSpec::MaxGap { .. }
            | SelectorSpec::Hysteresis { .. }
            | SelectorSpec::Oracle(_)
            | SelectorSpec::FrontLoaded(_) => None,
        })
        .flat_map(|mut selector| {
            times
                .iter()
                .enumerate()
                .filter(|&(_, &time_secs)| {
                    selector
                        .decide(&FrameContext {
                            time_secs,
                            ..FrameContext::default()
                        })
                        .is_process()
                })
                .map(|(k, _)| k)
                .collect::<Vec<_>>()
        })
        .collect();
    frames.sort_unstable();
    frames.dedup();
    frames
}

/// A recording's stereo pairs as the stereo VO `vo` reads them: through
/// the recorded camera infos' intrinsics and baseline when the recording
/// has both, else `vo`'s camera.
///
/// # Errors
/// Camera infos that cannot give a camera, said.
pub(crate) fn recorded_stereo_frames(
    frames: &Arc<BagFrames>,
    vo: &gpodo_frontends::vo::stereo::StereoVoParams,
) -> Result<Arc<StereoFrames>, String> {
    let camera = frames.camera(&vo.camera)?;
    let source: Arc<BagFrames> = Arc::clone(frames);
    Ok(Arc::new(StereoFrames::with_orb(
        camera,
        source,
        vo.orb(&camera),
    )))
}

/// The frames of each traverse, before any is rendered.
fn camera_sources(
    config: &ExperimentConfig,
    data: &PreparedData,
    ground: &GroundCell,
    traverses: &[Traverse],
) -> Result<Vec<Option<Arc<StereoFrames>>>, PipelineError> {
    use gpodo_frontends::params::VoSpec;
    let VoSpec::Stereo(vo) = &config.frontend.vo else {
        return Ok(vec![None; traverses.len()]);
    };
    let (Some((terrain, seed)), Some(soils)) = (&data.terrain, &data.soils) else {
        if data.recorded_cameras.is_empty() {
            return Err(gpodo_frontends::FrontendError::InvalidConfig {
                field: "frontend.vo.kind".into(),
                expected: "a VO without images for this dataset: `stereo` reads camera images, which a simulated dataset renders and a bag gives when its topic map names a `camera:`".into(),
            }
            .into());
        }
        return traverses
            .iter()
            .map(|t| {
                let frames = data.recorded_cameras.get(t.name()).ok_or_else(|| {
                    PipelineError::Inconsistent(format!(
                        "the test traverse `{}` has no recorded camera",
                        t.name()
                    ))
                })?;
                recorded_stereo_frames(frames, vo)
                    .map(Some)
                    .map_err(|detail| {
                        PipelineError::Inconsistent(format!(
                            "the camera of `{}`: {detail}",
                            t.name()
                        ))
                    })
            })
            .collect();
    };
    let ground: Arc<GroundMaps> = ground
        .get_or_init(|| {
            let start = Instant::now();
            let maps = GroundMaps::build(terrain, soils, &SceneSpec::default(), *seed)
                .map(Arc::new)
                .map_err(|e| e.to_string());
            tracing::info!(
                secs = start.elapsed().as_secs_f64(),
                "camera's ground maps built"
            );
            maps
        })
        .clone()
        .map_err(|detail| {
            PipelineError::Inconsistent(format!("the camera's ground maps: {detail}"))
        })?;
    Ok(traverses
        .iter()
        .map(|t| {
            let source = RenderedFrames::new(
                Arc::clone(&ground),
                vo.camera,
                SensorSpec::default(),
                *seed,
                traverse_frame_poses(&vo.camera, t),
            );
            // The true poses only for the control that reads them.
            let true_poses = (vo.local_map_placement == LocalMapPlacement::GroundTruth)
                .then(|| source.true_camera_poses());
            let frames = StereoFrames::with_orb(vo.camera, Arc::new(source), vo.orb(&vo.camera));
            Some(Arc::new(match true_poses {
                Some(poses) => frames.with_true_camera_poses(poses),
                None => frames,
            }))
        })
        .collect())
}

/// The rendered camera's pose for each frame of `traverse`'s camera
/// stream: the traverse's ground truth at the frame's time, blurred by the
/// motion over `camera`'s exposure centred there.
fn traverse_frame_poses(camera: &CameraParams, traverse: &Traverse) -> Vec<FramePose> {
    let half = 0.5 * camera.exposure_secs;
    traverse
        .camera_times_secs()
        .iter()
        .map(|&t| FramePose {
            world_from_body: traverse.ground_truth_at(t),
            exposure_motion: traverse.ground_truth_at(t - half).inverse()
                * traverse.ground_truth_at(t + half),
        })
        .collect()
}
