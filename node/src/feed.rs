//! Messages in, samples out: what the node does with each joint-state and
//! IMU message, whether they come from a recording or from DDS.
//!
//! Every joint-state message drives one output. The IMU reading it gets is
//! the latest one stamped at or before it (held until a later one comes),
//! so that a reading arriving a little late on its own topic is not used
//! for an earlier joint state. Times are seconds from the whole second
//! before the first message, on the topic map's clock (header stamps or
//! receive times), as the import counts them.

use std::collections::VecDeque;

use gpodo_datasets::bags::import::live::LiveDecoder;
use gpodo_datasets::bags::import::{TimeSource, TopicMap};
use gpodo_datasets::bags::messages::{Imu, JointState};
use gpodo_kinematics::RoverDescription;
use gpodo_traits::{ImuSample, ProprioceptiveSample};

use crate::NodeError;
use crate::pipeline::{LiveModel, LiveOutput, RowResidual};

/// One joint-state message's output.
#[derive(Debug, Clone, PartialEq)]
pub struct Fed {
    /// The message's time on the map's clock (ns since the epoch).
    pub stamp_ns: i64,
    /// What the pipeline produced.
    pub output: LiveOutput,
    /// How old the IMU reading used was (s; none without an IMU).
    pub imu_age_secs: Option<f64>,
}

/// A robot's topics fed to a live model.
pub struct LiveFeed<'m> {
    model: &'m mut LiveModel,
    decoder: LiveDecoder,
    time: TimeSource,
    with_imu: bool,
    /// IMU readings by stamp (ns), oldest first; readings older than the
    /// one the last joint state used are dropped.
    imu: VecDeque<(i64, ImuSample)>,
    base_ns: Option<i64>,
    /// The last joint state that gave an output (ns).
    last_joint_ns: Option<i64>,
}

impl<'m> LiveFeed<'m> {
    /// Feeds `model` with the topics of `map` on the rover `rover`.
    ///
    /// # Errors
    /// [`NodeError::Topics`] when the map has no joint states or does not
    /// map one of the rover's joints.
    pub fn new(
        map: &TopicMap,
        rover: &RoverDescription,
        model: &'m mut LiveModel,
    ) -> Result<Self, NodeError> {
        if map.joints.is_none() {
            return Err(NodeError::Topics(
                "the topic map has no `joints:`, which drive the node".into(),
            ));
        }
        let decoder = LiveDecoder::new(
            map,
            &rover.wheel_names(),
            &rover.steer_names(),
            &rover.bogie_names(),
        )
        .map_err(NodeError::Topics)?;
        Ok(Self {
            model,
            decoder,
            time: map.time,
            with_imu: map.imu.is_some(),
            imu: VecDeque::new(),
            base_ns: None,
            last_joint_ns: None,
        })
    }

    /// The model fed.
    pub fn model(&self) -> &LiveModel {
        self.model
    }

    /// A message's time on the map's clock (ns).
    fn stamp(&mut self, header_ns: i64, receive_ns: i64) -> i64 {
        let ns = match self.time {
            TimeSource::Header => header_ns,
            TimeSource::Receive => receive_ns,
        };
        self.base_ns
            .get_or_insert(ns.div_euclid(1_000_000_000) * 1_000_000_000);
        ns
    }

    /// Seconds since the feed's origin.
    fn secs(&self, ns: i64) -> f64 {
        (ns - self.base_ns.unwrap_or(0)) as f64 * 1e-9
    }

    /// Whether the IMU reading a joint-state message stamped `header_ns`
    /// should get can no longer come: a reading stamped at or after it has
    /// been held (or the robot has no IMU, or the clock is the receive
    /// time, by which every later reading is later). Until then a reading
    /// stamped before it may still be on its way on its own topic.
    pub fn imu_reached(&self, header_ns: i64) -> bool {
        !self.with_imu
            || self.time == TimeSource::Receive
            || self.imu.back().is_some_and(|(t, _)| *t >= header_ns)
    }

    /// Holds an IMU message received at `receive_ns`.
    pub fn imu(&mut self, m: &Imu, receive_ns: i64) {
        let ns = self.stamp(m.header.stamp_ns, receive_ns);
        let sample = self.decoder.imu(m);
        let at = self.imu.partition_point(|(t, _)| *t <= ns);
        self.imu.insert(at, (ns, sample));
    }

    /// Runs the model on a joint-state message received at `receive_ns`.
    ///
    /// # Errors
    /// Why the message gives no output (a joint missing from it, no IMU
    /// reading yet, or the pipeline's refusal); the feed is unchanged but
    /// for its clock's origin.
    pub fn joints(&mut self, m: &JointState, receive_ns: i64) -> Result<Fed, String> {
        self.joints_with(m, receive_ns, None)
    }

    /// [`LiveFeed::joints`] with the residual predicted by `residual`
    /// instead of the saved model (see [`LiveModel::process_with`]).
    ///
    /// # Errors
    /// As [`LiveFeed::joints`].
    pub fn joints_with(
        &mut self,
        m: &JointState,
        receive_ns: i64,
        residual: Option<&dyn RowResidual>,
    ) -> Result<Fed, String> {
        let ns = self.stamp(m.header.stamp_ns, receive_ns);
        let time_secs = self.secs(ns);
        if self.last_joint_ns.is_some_and(|last| ns <= last) {
            return Err(format!(
                "{time_secs} s: its time is not after the previous joint state's"
            ));
        }
        let [wheels, steering, bogies] = self
            .decoder
            .joints(m)
            .map_err(|joint| format!("{time_secs} s: no joint `{joint}`"))?;
        let held = self.imu.partition_point(|(t, _)| *t <= ns);
        let imu = match held.checked_sub(1) {
            Some(k) => Some(self.imu[k]),
            None if self.with_imu => {
                return Err(format!("{time_secs} s: before the first IMU message"));
            }
            None => None,
        };
        let sample = ProprioceptiveSample {
            time_secs,
            wheels,
            steering,
            bogies,
            imu: imu.map(|(_, s)| s),
            ..ProprioceptiveSample::default()
        };
        let output = self
            .model
            .process_with(&sample, residual)
            .map_err(|e| e.to_string())?;
        // Readings before the one used are no longer needed.
        self.imu.drain(..held.saturating_sub(1));
        self.last_joint_ns = Some(ns);
        Ok(Fed {
            stamp_ns: ns,
            output,
            imu_age_secs: imu.map(|(t, _)| (ns - t) as f64 * 1e-9),
        })
    }
}
