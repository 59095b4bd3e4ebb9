//! One front-end run over a traverse (§V-B): wheel odometry integrated at
//! the sensor rate and corrected by the predicted residual; at every camera
//! frame the selector decides; processed frames are tracked against their
//! reference keyframe by the visual odometry, become keyframes when they
//! share too little with it, close loops, and relocalise after a loss only
//! where the map already is; an online residual source learns from the VO
//! (§VI).
//!
//! Which frames enter the pose graph follows the odometry's
//! [`ErrorStructure`]. When frames tracked against one keyframe share its
//! map error (ORB-SLAM), only keyframes become nodes, linked by the wheel
//! odometry between them and by their visual edges (to the reference
//! keyframe, relocalisation, loop closure), as in ORB-SLAM's local bundle
//! adjustment; any other processed frame is placed by its tracked pose
//! relative to its keyframe (or, lost, by the odometry from the frame
//! before). When every measurement is independent, every processed frame
//! is a node. At the end the graph is optimised and the trajectory at every
//! sensor sample is the pose of the last processed frame composed with the
//! odometry since.

use gpodo_traits::{FrameContext, FrameDecision, FrameSelector};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use serde::{Deserialize, Serialize};

use crate::FrontendError;
use crate::backend::{EdgeKind, PoseGraph, PoseGraphEdge};
use crate::gate::GateState;
use crate::metrics::{TrajectoryMetrics, trajectory_metrics};
use crate::odometry::{OdometryIntegrator, OdometryInterval};
use crate::params::{FrontendParams, MotionPrior};
use crate::prediction::{ResidualPrediction, ResidualSource};
use crate::rover_measures::{Look, RoverMeasures, SampledTruth, rover_measures};
use crate::traverse::Traverse;
use crate::vo::{
    ErrorStructure, FrameRef, RefinedLink, TrackOutcome, TrackPurpose, TrackRequest,
    VisualOdometry, VoMeasurement,
};
use crate::vo_target::TargetInterval;

mod stepper;
mod trace;

pub use stepper::FrontEnd;

/// One processed frame, as the learning curve records it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ProcessedFrame {
    /// Camera frame index.
    pub frame: usize,
    /// Time (s).
    pub time_secs: f64,
    /// Ground-truth distance travelled by then (m).
    pub distance_m: f64,
    /// Whether it became a keyframe.
    pub keyframe: bool,
    /// Whether it was tracked (or relocalised) rather than lost.
    pub tracked: bool,
    /// The VO's pose of the frame (the visual map's, `world_from_body`)
    /// when it was tracked: what a VO behind the live gate would publish
    /// for it (not written to records).
    #[serde(skip)]
    pub vo_pose: Option<Isometry3<f64>>,
}

/// What a run produced.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrontendRun {
    /// Frames processed.
    pub frames: usize,
    /// Keyframes inserted.
    pub keyframes: usize,
    /// Times tracking was lost.
    pub tracking_losses: usize,
    /// Successful relocalisations.
    pub relocalisations: usize,
    /// Loop closures.
    pub loop_closures: usize,
    /// Loop closures and relocalisations the back end dropped as
    /// inconsistent with the rest of the graph
    /// ([`BackendParams::closure_chi2_max`](crate::backend::BackendParams)).
    pub rejected_closures: usize,
    /// Time spent lost (s).
    pub lost_secs: f64,
    /// The compute proxy (ms).
    pub compute_ms: f64,
    /// Residual targets learned online.
    pub online_targets: usize,
    /// Position errors of the final trajectory.
    pub metrics: TrajectoryMetrics,
    /// Drift since the last look, relative pose error, compute per metre
    /// and the RMSE's decomposition.
    #[serde(default)]
    pub rover: RoverMeasures,
    /// Weighted squared error of the pose graph before and after
    /// optimisation.
    pub graph_error: (f64, f64),
    /// Nodes of the pose graph (the start pose and the keyframes, or every
    /// processed frame; see the module documentation).
    #[serde(default)]
    pub graph_nodes: usize,
    /// Every processed frame, in order.
    pub processed: Vec<ProcessedFrame>,
    /// The prediction in force from each time on (time, prediction).
    pub predictions: Vec<(f64, ResidualPrediction)>,
    /// Estimated `world_from_body` at every sensor sample.
    #[serde(skip)]
    pub trajectory: Vec<Isometry3<f64>>,
}

/// Where a processed frame's final pose comes from.
#[derive(Debug, Clone, Copy)]
enum Placement {
    /// A pose-graph node.
    Graph(usize),
    /// Another processed frame's final pose composed with a relative pose.
    Relative {
        parent: usize,
        relative: Isometry3<f64>,
    },
}

/// A processed frame (the first is the start pose).
#[derive(Debug, Clone, Copy)]
struct Node {
    frame: Option<FrameRef>,
    /// The frame's pose according to the visual map (keyframe chain), when
    /// it was tracked.
    map_pose: Option<Isometry3<f64>>,
    /// The odometry chain's estimate (the graph's initial value).
    initial: Isometry3<f64>,
    placement: Placement,
}

/// Scales a relative motion by `s` (rotation angle and translation).
fn scale_motion(m: &Isometry3<f64>, s: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::from(m.translation.vector * s),
        UnitQuaternion::from_scaled_axis(m.rotation.scaled_axis() * s),
    )
}

struct Session<'a> {
    traverse: &'a Traverse,
    params: &'a FrontendParams,
    source: &'a mut dyn ResidualSource,
    vo: &'a mut dyn VisualOdometry,
    /// The odometry since the last processed frame and the prediction in
    /// force: what the selector reads.
    gate: GateState,
    /// Whether only keyframes are pose-graph nodes.
    keyframe_graph: bool,
    /// Odometry since the last pose-graph node (keyframe graph only).
    graph_integrator: OdometryIntegrator,
    /// The processed frame that is the last pose-graph node.
    last_graph_node: usize,
    time: f64,
    step: usize,
    next_window: usize,
    predictions: Vec<(f64, ResidualPrediction)>,
    /// Per sample: the processed frame it hangs from and the odometry
    /// since.
    anchors: Vec<(usize, Isometry3<f64>)>,
    /// Step → window index, for the regressor inputs of a step.
    step_window: Vec<Option<usize>>,
    graph: PoseGraph,
    nodes: Vec<Node>,
    last_node: usize,
    tracking: bool,
    lost_since: f64,
    reference_kf: Option<usize>,
    keyframes: Vec<usize>,
    /// The last two tracked nodes with their times (constant velocity).
    tracked_history: [Option<(usize, f64)>; 2],
    target_anchor: Option<TargetInterval>,
    run: FrontendRun,
}

impl<'a> Session<'a> {
    fn new(
        traverse: &'a Traverse,
        params: &'a FrontendParams,
        source: &'a mut dyn ResidualSource,
        vo: &'a mut dyn VisualOdometry,
    ) -> Self {
        let n = traverse.len();
        let mut step_window = vec![None; n - 1];
        for (w, window) in traverse.windows().iter().enumerate() {
            for s in window.steps.clone() {
                step_window[s] = Some(w);
            }
        }
        let t0 = traverse.times_secs()[0];
        let mut graph = PoseGraph::default();
        let start = traverse.ground_truth()[0];
        let origin = graph.add_node(start);
        let keyframe_graph = vo.error_structure() == ErrorStructure::SharedPerKeyframe;
        Self {
            traverse,
            params,
            source,
            vo,
            gate: GateState::new(
                params.odometry,
                params.odometry_mode,
                params.initial_residual_variance,
            ),
            keyframe_graph,
            graph_integrator: OdometryIntegrator::new(params.odometry),
            last_graph_node: 0,
            time: t0,
            step: 0,
            next_window: 0,
            predictions: vec![(
                t0,
                ResidualPrediction::uninformed(params.initial_residual_variance),
            )],
            anchors: vec![(0, Isometry3::identity())],
            step_window,
            graph,
            nodes: vec![Node {
                frame: None,
                map_pose: None,
                initial: start,
                placement: Placement::Graph(origin),
            }],
            last_node: 0,
            tracking: true,
            lost_since: t0,
            reference_kf: None,
            keyframes: Vec::new(),
            tracked_history: [None, None],
            target_anchor: None,
            run: FrontendRun {
                frames: 0,
                keyframes: 0,
                tracking_losses: 0,
                relocalisations: 0,
                loop_closures: 0,
                rejected_closures: 0,
                lost_secs: 0.0,
                compute_ms: 0.0,
                online_targets: 0,
                metrics: TrajectoryMetrics::default(),
                rover: RoverMeasures::default(),
                graph_error: (0.0, 0.0),
                graph_nodes: 0,
                processed: Vec::new(),
                predictions: Vec::new(),
                trajectory: Vec::new(),
            },
        }
    }

    /// Integrates odometry up to `t`, delivering predictions as windows
    /// complete and recording every sample passed.
    fn advance_to(&mut self, t: f64) -> Result<(), FrontendError> {
        let times = self.traverse.times_secs();
        let windows = self.traverse.windows();
        while self.time < t && self.step + 1 < times.len() {
            let mut end = t.min(times[self.step + 1]);
            if let Some(w) = windows.get(self.next_window)
                && w.end_secs > self.time
            {
                end = end.min(w.end_secs);
            }
            let inputs = self.step_window[self.step].map(|w| windows[w].inputs.as_slice());
            let twist = &self.traverse.twists()[self.step];
            if self.keyframe_graph {
                self.graph_integrator.advance(
                    twist,
                    end - self.time,
                    self.gate.epoch(),
                    self.gate.window(),
                    inputs,
                );
            }
            self.gate.drive(twist, end - self.time, inputs);
            self.time = end;
            if self.time >= times[self.step + 1] {
                self.step += 1;
                self.anchors
                    .push((self.last_node, *self.gate.since_processed().relative()));
            }
            while let Some(w) = windows.get(self.next_window)
                && w.end_secs <= self.time
            {
                let prediction = self.source.on_window(self.next_window, w)?;
                self.gate.predict(prediction)?;
                self.next_window += 1;
                self.predictions.push((self.time, prediction));
            }
        }
        Ok(())
    }

    fn context(&self, time_secs: f64) -> FrameContext {
        self.gate.context(time_secs, !self.tracking)
    }

    fn frame_of(&self, node: usize) -> Option<FrameRef> {
        self.nodes[node].frame
    }

    /// The motion prior for tracking `current` against the reference
    /// keyframe: `kf_from_current` predicted.
    fn prior(
        &self,
        interval: &OdometryInterval,
        kf_from_last: &Isometry3<f64>,
        gap: f64,
    ) -> Option<Isometry3<f64>> {
        match self.params.motion_prior {
            MotionPrior::Odometry => Some(kf_from_last * interval.relative),
            MotionPrior::None => None,
            MotionPrior::ConstantVelocity => {
                let [Some((a, ta)), Some((b, tb))] = self.tracked_history else {
                    return Some(*kf_from_last);
                };
                let (pa, pb) = (self.nodes[a].map_pose?, self.nodes[b].map_pose?);
                let velocity = pa.inverse() * pb;
                Some(kf_from_last * scale_motion(&velocity, gap / (tb - ta).max(1e-6)))
            }
        }
    }

    /// The pose-graph node of processed frame `node`, if it is one.
    fn graph_node(&self, node: usize) -> Option<usize> {
        match self.nodes[node].placement {
            Placement::Graph(g) => Some(g),
            Placement::Relative { .. } => None,
        }
    }

    /// Adds a visual edge between two processed frames that are graph
    /// nodes (a keyframe always is).
    fn add_vo_edge(&mut self, from_node: usize, to_node: usize, m: &VoMeasurement, kind: EdgeKind) {
        let (Some(from), Some(to)) = (self.graph_node(from_node), self.graph_node(to_node)) else {
            debug_assert!(
                false,
                "a visual edge between frames that are not graph nodes"
            );
            return;
        };
        self.trace_edge_error(kind, from_node, to_node, &m.relative, &m.covariance);
        self.graph.add_edge(PoseGraphEdge {
            from,
            to,
            measurement: m.relative,
            covariance: m.covariance,
            kind,
        });
    }

    /// Makes processed frame `node` a pose-graph node, linked to the last
    /// one by the wheel odometry between them.
    fn add_graph_node(&mut self, node: usize, odometry: &OdometryInterval) {
        let Some(from) = self.graph_node(self.last_graph_node) else {
            debug_assert!(false, "the last graph node is not a graph node");
            return;
        };
        let to = self.graph.add_node(self.nodes[node].initial);
        self.trace_edge_error(
            EdgeKind::Odometry,
            self.last_graph_node,
            node,
            &odometry.relative,
            &odometry.covariance,
        );
        self.graph.add_edge(PoseGraphEdge {
            from,
            to,
            measurement: odometry.relative,
            covariance: odometry.covariance,
            kind: EdgeKind::Odometry,
        });
        self.nodes[node].placement = Placement::Graph(to);
        self.last_graph_node = node;
    }

    /// Puts the links a local bundle adjustment refined (oldest first) in
    /// place of the visual edges that placed those keyframes, and places
    /// the keyframes on the visual map by them.
    fn apply_refined_links(&mut self, links: &[RefinedLink]) {
        for link in links {
            let (Some(from_node), Some(to_node)) = (
                self.node_of_frame(link.reference.index),
                self.node_of_frame(link.current.index),
            ) else {
                continue;
            };
            if let (Some(from), Some(to)) = (self.graph_node(from_node), self.graph_node(to_node))
                && let Some(edge) = self.graph.edges.iter_mut().rev().find(|e| {
                    e.from == from
                        && e.to == to
                        && matches!(e.kind, EdgeKind::VisualOdometry | EdgeKind::Relocalisation)
                })
            {
                edge.measurement = link.relative;
                edge.covariance = link.covariance;
            }
            self.nodes[to_node].map_pose =
                self.nodes[from_node].map_pose.map(|p| p * link.relative);
        }
    }

    fn make_keyframe(&mut self, node: usize) {
        self.keyframes.push(node);
        self.reference_kf = Some(node);
        self.run.keyframes += 1;
    }

    /// Matches frame `current` without a prior against the keyframes
    /// place recognition proposes among those older than `before_secs`,
    /// best first; the first match and its keyframe.
    fn match_recognised(
        &mut self,
        current: FrameRef,
        before_secs: f64,
        purpose: TrackPurpose,
    ) -> Option<(usize, VoMeasurement)> {
        let known: Vec<FrameRef> = self
            .keyframes
            .iter()
            .filter_map(|&k| self.frame_of(k))
            .filter(|f| f.time_secs < before_secs)
            .collect();
        for candidate in self.vo.recognise(current, &known) {
            let request = TrackRequest {
                reference: candidate,
                current,
                prior: None,
                purpose,
            };
            if let TrackOutcome::Tracked(m) = self.vo.track(&request)
                && let Some(kf) = self.node_of_frame(candidate.index)
            {
                return Some((kf, m));
            }
        }
        None
    }

    /// Looks for a loop from the new keyframe `node` to an old one.
    fn close_loop(&mut self, node: usize, time_secs: f64) {
        if !self.params.loop_closure.enabled {
            return;
        }
        let Some(current) = self.frame_of(node) else {
            return;
        };
        let horizon = time_secs - self.params.loop_closure.min_separation_secs;
        if let Some((kf, m)) = self.match_recognised(current, horizon, TrackPurpose::LoopClosure) {
            self.add_vo_edge(kf, node, &m, EdgeKind::LoopClosure);
            self.run.loop_closures += 1;
        }
    }

    fn node_of_frame(&self, frame: usize) -> Option<usize> {
        self.keyframes
            .iter()
            .copied()
            .find(|&k| self.nodes[k].frame.is_some_and(|f| f.index == frame))
    }

    /// Tries to relocalise frame `current` against a recognised keyframe.
    fn relocalise(&mut self, current: FrameRef) -> Option<(usize, VoMeasurement)> {
        self.match_recognised(current, f64::INFINITY, TrackPurpose::Relocalisation)
    }

    /// Learns from the VO over the interval since the target anchor.
    fn online_target(
        &mut self,
        node: usize,
        time_secs: f64,
        interval: &OdometryInterval,
    ) -> Result<(), FrontendError> {
        if !self.source.learns_online() {
            return Ok(());
        }
        let Some(anchor) = self.target_anchor.as_mut() else {
            return Ok(());
        };
        anchor.add(
            &interval.raw_relative,
            interval.mean_inputs.as_deref(),
            interval.duration_secs,
        );
        let limits = self.params.online;
        if !anchor.is_ready(time_secs, &limits) {
            return Ok(());
        }
        let closed = anchor.close(time_secs, self.nodes[node].map_pose.as_ref(), &limits);
        self.start_target(node, time_secs);
        if let Ok(target) = closed {
            self.source
                .on_target(&target.inputs, &target.residual, time_secs)?;
            self.run.online_targets += 1;
        }
        Ok(())
    }

    fn start_target(&mut self, node: usize, time_secs: f64) {
        self.target_anchor = Some(TargetInterval::open(time_secs, self.nodes[node].map_pose));
    }

    /// Processes camera frame `frame` with the selector's decision.
    fn process(
        &mut self,
        frame: FrameRef,
        keyframe_scale: f64,
    ) -> Result<ProcessedFrame, FrontendError> {
        let gap = frame.time_secs - self.gate.last_processed_secs().unwrap_or(frame.time_secs);
        let interval = self.gate.processed(frame.time_secs);
        let previous = self.last_node;
        let node = self.nodes.len();
        self.nodes.push(Node {
            frame: Some(frame),
            map_pose: None,
            initial: self.nodes[previous].initial * interval.relative,
            placement: Placement::Relative {
                parent: previous,
                relative: interval.relative,
            },
        });
        if !self.keyframe_graph {
            self.add_graph_node(node, &interval);
        }
        self.last_node = node;
        self.run.frames += 1;
        let mut became_keyframe = false;
        // The visual edge that places the frame: from its keyframe, and of
        // which kind.
        let mut placed_by: Option<(usize, VoMeasurement, EdgeKind)> = None;
        // A target interval starts here (map initialised or relocalised).
        let mut fresh_anchor = false;
        if self.tracking {
            match self.reference_kf {
                None => {
                    // The first processed frame initialises the map.
                    self.nodes[node].map_pose = Some(self.nodes[node].initial);
                    if self.keyframe_graph {
                        let span = self.graph_integrator.take();
                        self.add_graph_node(node, &span);
                    }
                    self.make_keyframe(node);
                    became_keyframe = true;
                    fresh_anchor = true;
                }
                Some(kf) => {
                    let kf_from_last =
                        match (self.nodes[kf].map_pose, self.nodes[previous].map_pose) {
                            (Some(k), Some(l)) => k.inverse() * l,
                            _ => Isometry3::identity(),
                        };
                    let reference = self.frame_of(kf).unwrap_or(frame);
                    let request = TrackRequest {
                        reference,
                        current: frame,
                        prior: self.prior(&interval, &kf_from_last, gap),
                        purpose: TrackPurpose::Tracking,
                    };
                    match self.vo.track(&request) {
                        TrackOutcome::Tracked(m) => {
                            self.nodes[node].map_pose =
                                self.nodes[kf].map_pose.map(|p| p * m.relative);
                            placed_by = Some((kf, m, EdgeKind::VisualOdometry));
                            became_keyframe =
                                self.keyframe_due(&m, reference, frame, keyframe_scale);
                        }
                        TrackOutcome::Lost => self.lose_track(&request, gap),
                    }
                }
            }
        } else if let Some((kf, m)) = self.relocalise(frame) {
            self.tracking = true;
            self.run.relocalisations += 1;
            self.run.lost_secs += frame.time_secs - self.lost_since;
            self.nodes[node].map_pose = self.nodes[kf].map_pose.map(|p| p * m.relative);
            self.reference_kf = Some(kf);
            placed_by = Some((kf, m, EdgeKind::Relocalisation));
            let reference = self.frame_of(kf).unwrap_or(frame);
            became_keyframe = self.keyframe_due(&m, reference, frame, keyframe_scale);
            fresh_anchor = true;
        }
        let tracked = placed_by.is_some() || fresh_anchor;
        if let Some((kf, m, kind)) = placed_by {
            if !self.keyframe_graph {
                self.add_vo_edge(kf, node, &m, kind);
            } else if became_keyframe {
                let span = self.graph_integrator.take();
                self.add_graph_node(node, &span);
                self.add_vo_edge(kf, node, &m, kind);
            } else {
                self.nodes[node].placement = Placement::Relative {
                    parent: kf,
                    relative: m.relative,
                };
            }
        }
        if tracked {
            self.tracked_history = [self.tracked_history[1], Some((node, frame.time_secs))];
            if fresh_anchor {
                self.start_target(node, frame.time_secs);
            } else {
                self.online_target(node, frame.time_secs, &interval)?;
            }
        } else {
            self.tracked_history = [None, None];
        }
        if became_keyframe && self.reference_kf != Some(node) {
            self.make_keyframe(node);
            let links = self.vo.keyframe_inserted(frame);
            self.apply_refined_links(&links);
            self.close_loop(node, frame.time_secs);
        }
        let processed = ProcessedFrame {
            frame: frame.index,
            time_secs: frame.time_secs,
            distance_m: self
                .traverse
                .distance_at(self.traverse.sample_at_or_before(frame.time_secs)),
            keyframe: became_keyframe,
            tracked,
            vo_pose: self.nodes[node].map_pose.filter(|_| tracked),
        };
        self.run.processed.push(processed);
        Ok(processed)
    }

    /// Tracking `request` failed: the tracker is lost from here.
    fn lose_track(&mut self, request: &TrackRequest, gap: f64) {
        let (reference, frame) = (request.reference, request.current);
        let truth = self.traverse.ground_truth_at(reference.time_secs).inverse()
            * self.traverse.ground_truth_at(frame.time_secs);
        tracing::debug!(
            time_secs = frame.time_secs,
            gap_secs = gap,
            since_keyframe_secs = frame.time_secs - reference.time_secs,
            success_probability = self.vo.success_probability(request),
            prior_error_m = request
                .prior
                .map(|p| (p.inverse() * truth).translation.vector.norm()),
            prior_error_rad = request
                .prior
                .map(|p| (p.inverse() * truth).rotation.angle()),
            "tracking lost"
        );
        self.tracking = false;
        self.lost_since = frame.time_secs;
        self.run.tracking_losses += 1;
        self.target_anchor = None;
    }

    fn keyframe_due(
        &self,
        m: &VoMeasurement,
        reference: FrameRef,
        current: FrameRef,
        scale: f64,
    ) -> bool {
        let k = &self.params.keyframes;
        let threshold = 1.0 - (1.0 - k.min_overlap) * scale.max(0.0);
        m.overlap < threshold
            || m.needs_keyframe
            || k.max_interval_secs
                .is_some_and(|max| current.time_secs - reference.time_secs >= max)
    }

    fn finish(mut self) -> Result<FrontendRun, FrontendError> {
        let end = self.traverse.times_secs()[self.traverse.len() - 1];
        self.advance_to(end)?;
        if !self.tracking {
            self.run.lost_secs += end - self.lost_since;
        }
        let optimized = self.graph.optimize(&self.params.backend)?;
        if optimized.hit_iteration_limit {
            tracing::warn!(
                nodes = self.graph.initial.len(),
                "pose graph: iteration limit reached"
            );
        }
        self.trace_closures(&optimized);
        self.run.rejected_closures = optimized.rejected.len();
        self.run.graph_error = (optimized.initial_error, optimized.final_error);
        self.run.graph_nodes = self.graph.initial.len();
        let mut poses: Vec<Isometry3<f64>> = Vec::with_capacity(self.nodes.len());
        for node in &self.nodes {
            let pose = match node.placement {
                Placement::Graph(g) => optimized.poses[g],
                // A parent is always processed before its children.
                Placement::Relative { parent, relative } => poses[parent] * relative,
            };
            poses.push(pose);
        }
        self.run.trajectory = self
            .anchors
            .iter()
            .map(|(node, relative)| poses[*node] * relative)
            .collect();
        self.run.metrics = trajectory_metrics(
            &self.run.trajectory,
            self.traverse.ground_truth(),
            self.traverse.path_length_m(),
        );
        let cost = &self.params.cost;
        self.run.compute_ms =
            self.run.frames as f64 * cost.frame_ms + self.run.keyframes as f64 * cost.keyframe_ms;
        self.run.rover = rover_measures(
            &self.run.trajectory,
            &SampledTruth {
                times_secs: self.traverse.times_secs(),
                ground_truth: self.traverse.ground_truth(),
                distance_m: self.traverse.distances_m(),
            },
            self.run.processed.iter().map(|p| Look {
                time_secs: p.time_secs,
                keyframe: p.keyframe,
                tracked: p.tracked,
            }),
            self.run.compute_ms,
        );
        self.run.predictions = self.predictions;
        Ok(self.run)
    }
}

/// Runs the front end over `traverse`: `selector` decides which camera
/// frames are processed, `source` supplies (and may learn) the residual
/// predictions, `vo` tracks.
///
/// # Errors
/// [`FrontendError::InvalidConfig`] for bad settings, what the source or
/// the back end report.
pub fn run_frontend(
    traverse: &Traverse,
    params: &FrontendParams,
    selector: &mut dyn FrameSelector,
    source: &mut dyn ResidualSource,
    vo: &mut dyn VisualOdometry,
) -> Result<FrontendRun, FrontendError> {
    selector.reset();
    let mut front_end = FrontEnd::new(traverse, params, source, vo)?;
    for (index, &time_secs) in traverse.camera_times_secs().iter().enumerate() {
        front_end.advance_to(time_secs)?;
        if let FrameDecision::Process {
            keyframe_threshold_scale,
        } = selector.decide(&front_end.context(time_secs))
        {
            front_end.process(FrameRef { index, time_secs }, keyframe_threshold_scale)?;
        }
    }
    front_end.finish()
}
