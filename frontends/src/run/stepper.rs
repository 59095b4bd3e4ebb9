//! The front end one camera frame at a time, for a caller that decides
//! the frames itself: [`run_frontend`](super::run_frontend) asks a
//! selector; the live gate's replay asks the gate and uses the front end
//! as the VO behind it.

use gpodo_traits::FrameContext;

use super::{FrontendRun, ProcessedFrame, Session};
use crate::FrontendError;
use crate::params::FrontendParams;
use crate::prediction::ResidualSource;
use crate::traverse::Traverse;
use crate::vo::{FrameRef, VisualOdometry};

/// A front-end run over a traverse, stepped by its caller: odometry up to
/// a time, the selector's context there, a frame processed, the run
/// finished.
pub struct FrontEnd<'a> {
    session: Session<'a>,
}

impl<'a> FrontEnd<'a> {
    /// A run over `traverse` with `params`, the residual predictions from
    /// `source` (which may learn online) and `vo` tracking.
    ///
    /// # Errors
    /// [`FrontendError::InvalidConfig`] for bad settings.
    pub fn new(
        traverse: &'a Traverse,
        params: &'a FrontendParams,
        source: &'a mut dyn ResidualSource,
        vo: &'a mut dyn VisualOdometry,
    ) -> Result<Self, FrontendError> {
        params.validate()?;
        Ok(Self {
            session: Session::new(traverse, params, source, vo),
        })
    }

    /// Integrates the odometry up to `time_secs` (no further than the
    /// traverse's last sample), delivering the source's predictions as
    /// windows complete.
    ///
    /// # Errors
    /// What the source reports.
    pub fn advance_to(&mut self, time_secs: f64) -> Result<(), FrontendError> {
        self.session.advance_to(time_secs)
    }

    /// What a selector reads for the frame at `time_secs`.
    pub fn context(&self, time_secs: f64) -> FrameContext {
        self.session.context(time_secs)
    }

    /// Processes `frame` (after [`FrontEnd::advance_to`] its time) with
    /// the keyframe-threshold scale the selector asked for: tracked,
    /// perhaps made a keyframe, learned from; what became of it.
    ///
    /// # Errors
    /// What the source reports.
    pub fn process(
        &mut self,
        frame: FrameRef,
        keyframe_threshold_scale: f64,
    ) -> Result<ProcessedFrame, FrontendError> {
        self.session.process(frame, keyframe_threshold_scale)
    }

    /// Whether the tracker is lost.
    pub fn lost(&self) -> bool {
        !self.session.tracking
    }

    /// Integrates to the traverse's end and optimises the pose graph.
    ///
    /// # Errors
    /// What the source or the back end report.
    pub fn finish(self) -> Result<FrontendRun, FrontendError> {
        self.session.finish()
    }
}
