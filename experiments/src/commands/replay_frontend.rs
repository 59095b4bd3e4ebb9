//! The offline schemes' VO behind the gate in a replay (`gpodo live
//! --gate FILE --replay BAG`, the gate file's `replay_frontend:`).
//!
//! The recording is imported as `gpodo run` imports a bag: through the
//! topic map, its joints brought into the rover's order, its camera frames
//! the gate's stereo pairs ([`RecordedTraverse::load`]). Its traverse is
//! made with the saved model's motion model, window and input scaling, as
//! a scheme's is. The front end the offline schemes run is then stepped by
//! the pairs the gate forwards ([`FrontEndVo`]): its tracked pose, or a
//! null pose while it is lost, is the odometry the VO publishes.

use std::path::Path;
use std::sync::Arc;

use anyhow::Context as _;
use gpodo_datasets::bags::images::CameraTopics;
use gpodo_datasets::bags::import::TopicMap;
use gpodo_datasets::bags::messages::{Header, Odometry, Pose, Twist};
use gpodo_frontends::FrontendError;
use gpodo_frontends::params::{FrontendParams, VoSpec};
use gpodo_frontends::prediction::{Precomputed, ResidualPrediction};
use gpodo_frontends::run::FrontEnd;
use gpodo_frontends::traverse::Traverse;
use gpodo_frontends::tum::StampedPose;
use gpodo_frontends::vo::stereo::StereoFrames;
use gpodo_frontends::vo::{FrameRef, VisualOdometry};
use gpodo_kinematics::RoverDescription;
use gpodo_kinematics::spec::MotionModelSpec;
use gpodo_node::gate::GateDecision;
use gpodo_node::gate::topics::GateTopics;
use gpodo_node::replay::RecordedPair;
use gpodo_regressors::model_file::ModelFile;

/// The variance the front end's VO publishes on its position (m²): what
/// the target code reads to tell a jump from motion.
pub const FRONT_END_POSITION_VARIANCE_M2: f64 = 1e-6;

/// A recording as the offline schemes see it.
pub struct RecordedTraverse {
    /// The front end's view of it.
    pub traverse: Traverse,
    /// Its stereo pairs as the stereo VO reads them, for `frontend.vo`
    /// `stereo`.
    pub frames: Option<Arc<StereoFrames>>,
    /// Its poses of the VO topic, when the topic map names one.
    pub recorded_vo: Vec<StampedPose>,
    /// The traverse's time 0 (ns since the epoch).
    pub start_epoch_ns: i64,
}

impl RecordedTraverse {
    /// Imports the recording `bag` through `map`, its camera frames the
    /// gate's image pairs (`camera`), for the rover at `rover_path` and the
    /// saved model `model`, as `frontend` will read it.
    ///
    /// # Errors
    /// A recording, model or rover that cannot be used, named.
    pub fn load(
        bag: &Path,
        map: &TopicMap,
        camera: &GateTopics,
        model: &ModelFile,
        rover_path: &Path,
        frontend: &FrontendParams,
    ) -> anyhow::Result<Self> {
        let recipe = model.rows.as_ref().context(
            "the model does not say how its rows were made, which its traverse needs; fit it again with `gpodo fit`",
        )?;
        let spec: MotionModelSpec = serde_json::from_value(recipe.motion_model.clone())
            .context("the model's motion model cannot be read")?;
        let (motion, rover) = spec.with_rover(rover_path.to_path_buf()).build()?;
        let rover = match rover {
            Some(r) => r,
            None => RoverDescription::from_path(rover_path)
                .map_err(|e| anyhow::anyhow!("{}: {e}", rover_path.display()))?,
        };
        let name = bag
            .file_stem()
            .map_or_else(|| "recording".into(), |s| s.to_string_lossy().into_owned());
        let (log, report) = gpodo_datasets::bags::import::import_bag(bag, &name, map)
            .with_context(|| format!("{}: imported as `gpodo run` imports it", bag.display()))?;
        let mut log = crate::execute::data::in_rover_order(&[log], Some(&rover))?
            .pop()
            .context("one recording imported")?;
        let topics = CameraTopics {
            left: camera.left_image.clone(),
            right: camera.right_image.clone(),
            left_info: Some(camera.left_info.clone()),
            right_info: Some(camera.right_info.clone()),
        };
        let frames = crate::execute::data::recorded_camera(
            bag,
            &topics,
            map.skip_damaged,
            &report,
            &mut log,
        )?;
        let frames = match &frontend.vo {
            VoSpec::Stereo(vo) => Some(
                crate::execute::camera::recorded_stereo_frames(&Arc::new(frames), vo)
                    .map_err(|e| anyhow::anyhow!("{}: its camera: {e}", bag.display()))?,
            ),
            _ => None,
        };
        // A model fitted on unscaled inputs: its windows' inputs as they are.
        let scaler =
            model
                .input_standardizer
                .clone()
                .unwrap_or_else(|| gpodo_traits::Standardizer {
                    mean: vec![0.0; model.input_names.len()],
                    std: vec![1.0; model.input_names.len()],
                });
        let window_secs = recipe.window_secs.context(
            "the model's rows have no window, which the offline schemes' traverse needs",
        )?;
        let traverse = crate::execute::traverses::build_traverse(
            &log,
            motion.as_ref(),
            rover.wheel_radius_m,
            window_secs,
            &scaler,
        )?;
        let recorded_vo = report
            .vo_poses
            .iter()
            .map(|&(time_secs, pose)| StampedPose { time_secs, pose })
            .collect();
        Ok(Self {
            traverse,
            frames,
            recorded_vo,
            start_epoch_ns: report.start_epoch_ns,
        })
    }

    /// The VO `frontend` names on this recording, as the offline schemes
    /// build it.
    ///
    /// # Errors
    /// What the VO's constructor reports.
    pub fn vo(&self, frontend: &FrontendParams) -> Result<Box<dyn VisualOdometry>, FrontendError> {
        frontend.vo.build(
            &self.traverse,
            Some(&self.recorded_vo),
            self.frames.as_ref(),
        )
    }
}

/// What the front end behind the gate reads for the residual: nothing (it
/// tracks with its own motion prior, as an external SLAM does).
pub struct ReplayFrontEnd;

impl ReplayFrontEnd {
    /// A source that knows nothing on `traverse`'s windows, at `frontend`'s
    /// initial variance.
    pub fn no_model(traverse: &Traverse, frontend: &FrontendParams) -> Precomputed {
        let uninformed = ResidualPrediction::uninformed(frontend.initial_residual_variance);
        Precomputed::new("none", vec![uninformed; traverse.windows().len()])
    }
}

/// The front end stepped by the gate's forwarded pairs, answering each
/// with the odometry a VO behind the gate publishes.
pub struct FrontEndVo<'f, 'a> {
    front_end: &'f mut FrontEnd<'a>,
    camera_times_secs: Vec<f64>,
    start_epoch_ns: i64,
    child_frame_id: String,
    /// The first error the front end reported (it then answers nothing).
    pub error: Option<FrontendError>,
    /// Forwarded pairs the VO lost.
    pub lost: usize,
    /// The frames it processed, in order.
    pub processed: Vec<usize>,
}

impl<'f, 'a> FrontEndVo<'f, 'a> {
    /// `front_end` on `recorded`'s frames, its poses (the body's in the
    /// visual map) published for the child frame `child_frame_id`.
    pub fn new(
        front_end: &'f mut FrontEnd<'a>,
        recorded: &RecordedTraverse,
        child_frame_id: &str,
    ) -> Self {
        Self {
            front_end,
            camera_times_secs: recorded.traverse.camera_times_secs().to_vec(),
            start_epoch_ns: recorded.start_epoch_ns,
            child_frame_id: child_frame_id.to_string(),
            error: None,
            lost: 0,
            processed: Vec::new(),
        }
    }

    /// The front end's answer to a forwarded pair: its tracked pose with
    /// [`FRONT_END_POSITION_VARIANCE_M2`], or a null pose (lost); nothing
    /// for a pair that is not one of the recording's frames, or after an
    /// error.
    pub fn answer(&mut self, pair: &RecordedPair<'_>, decision: &GateDecision) -> Option<Odometry> {
        if self.error.is_some() {
            return None;
        }
        let time_secs = (pair.stamp_ns - self.start_epoch_ns) as f64 * 1e-9;
        // The frames' times increase (a traverse checks them).
        let index = self
            .camera_times_secs
            .binary_search_by(|t| t.total_cmp(&time_secs))
            .ok()?;
        let processed = self.front_end.advance_to(time_secs).and_then(|()| {
            self.front_end.process(
                FrameRef { index, time_secs },
                decision.keyframe_threshold_scale.unwrap_or(1.0),
            )
        });
        let processed = match processed {
            Ok(p) => p,
            Err(e) => {
                self.error = Some(e);
                return None;
            }
        };
        self.processed.push(index);
        let (position, orientation) = match processed.vo_pose {
            Some(p) => {
                let q = p.rotation.quaternion();
                let x = p.translation.vector;
                ([x.x, x.y, x.z], [q.i, q.j, q.k, q.w])
            }
            None => {
                self.lost += 1;
                ([0.0; 3], [0.0; 4])
            }
        };
        let mut pose_covariance = vec![0.0; 36];
        for i in 0..3 {
            pose_covariance[i * 7] = FRONT_END_POSITION_VARIANCE_M2;
        }
        Some(Odometry {
            header: Header {
                stamp_ns: pair.stamp_ns,
                frame_id: "vo".into(),
            },
            child_frame_id: self.child_frame_id.clone(),
            pose: Pose {
                position,
                orientation,
            },
            pose_covariance,
            twist: Twist {
                linear: [0.0; 3],
                angular: [0.0; 3],
            },
            twist_covariance: vec![0.0; 36],
        })
    }
}
