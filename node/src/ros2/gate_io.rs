//! The gate on DDS: the stereo camera's four topics and the VO's in, the
//! chosen pairs and every decision out.
//!
//! * Subscribes best effort, keep last `history_depth` (the pairing's), to
//!   the left and right images and camera infos, as camera drivers
//!   publish; reliable, keep last 10, to the VO's `nav_msgs/Odometry` and
//!   its `std_msgs/Bool` status, as ROS 2 publishes by default (a
//!   reliable reader also takes a best-effort writer's messages).
//! * Republishes each chosen pair's four messages unchanged, byte for
//!   byte, reliable (ORB-SLAM3's ROS 2 wrappers and OpenVINS subscribe
//!   reliable, and a reliable reader does not take a best-effort writer).
//! * Publishes each decision as a `diagnostic_msgs/DiagnosticStatus`,
//!   before the pair it forwards.
//!
//! A pair is decided once the odometry has reached its stamp (a joint
//! state stamped at or after it has been processed), so that the gate
//! reads the odometry up to the frame as the offline schemes do, or once
//! it has waited `pair_wait`.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use rustdds::no_key::{DataReader, DataWriter};
use rustdds::{DomainParticipant, Publisher, QosPolicies, Subscriber};

use gpodo_datasets::bags::messages::{RosMessage, decode, decode_bool, decode_image_header};
use gpodo_datasets::bags::write::diagnostic_status_message;

use super::{RawCdr, RawCdrAdapter, dds_error, output_qos, sensor_qos, topic};
use crate::NodeError;
use crate::gate::pairing::{Part, PartHeader, StereoPair};
use crate::gate::report::decision_status;
use crate::gate::session::GateSession;
use crate::gate::topics::GateTopics;

/// The bytes of an image or camera info read for its header and size.
const HEADER_BYTES: usize = 1024;

/// The gate given to [`super::run`].
pub struct Ros2Gate<'a> {
    /// Its topics.
    pub topics: &'a GateTopics,
    /// The VO's `std_msgs/Bool` lost status, if wired.
    pub status_topic: Option<&'a str>,
    /// The gate, pairing and learner.
    pub session: &'a mut GateSession<RawCdr>,
}

/// What the gate did on DDS.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct GateTraffic {
    /// Pairs decided.
    pub decided: u64,
    /// Pairs forwarded.
    pub forwarded: u64,
    /// Pairs decided after waiting `pair_wait` for the odometry.
    pub decided_before_odometry: u64,
    /// VO odometry messages taken.
    pub vo_messages: u64,
}

/// The gate's readers and writers.
pub(super) struct GateIo {
    parts: Vec<(Part, DataReader<RawCdr, RawCdrAdapter>)>,
    vo: DataReader<RawCdr, RawCdrAdapter>,
    status: Option<DataReader<RawCdr, RawCdrAdapter>>,
    gated: Vec<DataWriter<RawCdr, RawCdrAdapter>>,
    decisions: DataWriter<RawCdr, RawCdrAdapter>,
    /// Pairs waiting for the odometry to reach their stamp.
    waiting: VecDeque<(StereoPair<RawCdr>, Instant)>,
    traffic: GateTraffic,
}

impl GateIo {
    /// The gate's readers and writers for `topics`.
    pub(super) fn new(
        participant: &DomainParticipant,
        subscriber: &Subscriber,
        publisher: &Publisher,
        gate: &Ros2Gate<'_>,
        history_depth: usize,
    ) -> Result<Self, NodeError> {
        let topics = gate.topics;
        let depth = i32::try_from(history_depth.max(1)).unwrap_or(i32::MAX);
        let cameras = sensor_qos(depth);
        let reliable = output_qos();
        let reader = |ros_topic: &str,
                      ros_type: &str,
                      qos: &QosPolicies|
         -> Result<DataReader<RawCdr, RawCdrAdapter>, NodeError> {
            let t = topic(participant, ros_topic, ros_type, qos)?;
            subscriber
                .create_datareader_no_key::<RawCdr, RawCdrAdapter>(&t, Some(qos.clone()))
                .map_err(|e| dds_error(&format!("reader of {ros_topic}"), e))
        };
        let writer = |ros_topic: &str,
                      ros_type: &str|
         -> Result<DataWriter<RawCdr, RawCdrAdapter>, NodeError> {
            let t = topic(participant, ros_topic, ros_type, &reliable)?;
            publisher
                .create_datawriter_no_key::<RawCdr, RawCdrAdapter>(&t, None)
                .map_err(|e| dds_error(&format!("writer of {ros_topic}"), e))
        };
        let part_type = |part: Part| {
            if part.is_image() {
                "sensor_msgs/msg/Image"
            } else {
                "sensor_msgs/msg/CameraInfo"
            }
        };
        let parts = Part::ALL
            .iter()
            .map(|&p| Ok((p, reader(topics.input(p), part_type(p), &cameras)?)))
            .collect::<Result<_, NodeError>>()?;
        let gated = Part::ALL
            .iter()
            .map(|&p| writer(&topics.gated(p), part_type(p)))
            .collect::<Result<_, NodeError>>()?;
        let vo = reader(&topics.vo_odometry, "nav_msgs/msg/Odometry", &reliable)?;
        let status = match gate.status_topic {
            Some(t) => Some(reader(t, "std_msgs/msg/Bool", &reliable)?),
            None => None,
        };
        let decisions = writer(&topics.decisions, "diagnostic_msgs/msg/DiagnosticStatus")?;
        Ok(Self {
            parts,
            vo,
            status,
            gated,
            decisions,
            waiting: VecDeque::new(),
            traffic: GateTraffic::default(),
        })
    }

    /// What it did.
    pub(super) fn traffic(&self) -> GateTraffic {
        self.traffic
    }

    /// Takes what waits on the gate's topics at `now_secs` on the node's
    /// clock; returns whether anything came.
    pub(super) fn take(
        &mut self,
        session: &mut GateSession<RawCdr>,
        now_secs: f64,
    ) -> Result<bool, NodeError> {
        let mut took = false;
        for (part, reader) in &mut self.parts {
            while let Some(s) = reader
                .take_next_sample()
                .map_err(|e| dds_error("camera", e))?
            {
                took = true;
                let message = s.into_value();
                // The header and size, read from the message's head: a
                // frame id longer than that is undecodable.
                let Ok((header, width, height)) =
                    decode_image_header("cdr", &message.encoded_head(HEADER_BYTES))
                else {
                    session.undecodable();
                    continue;
                };
                let header = PartHeader {
                    stamp_ns: header.stamp_ns,
                    width,
                    height,
                };
                if let Some(pair) = session.part(*part, header, message, now_secs) {
                    self.waiting.push_back((pair, Instant::now()));
                }
            }
        }
        if let Some(reader) = self.status.as_mut() {
            while let Some(s) = reader
                .take_next_sample()
                .map_err(|e| dds_error("VO status", e))?
            {
                took = true;
                match decode_bool("cdr", &s.value().encoded()) {
                    Ok(lost) => session.vo_status(lost),
                    Err(_) => session.undecodable(),
                }
            }
        }
        while let Some(s) = self
            .vo
            .take_next_sample()
            .map_err(|e| dds_error("VO odometry", e))?
        {
            took = true;
            self.traffic.vo_messages += 1;
            match decode("nav_msgs/msg/Odometry", "cdr", &s.value().encoded()) {
                Ok(RosMessage::Odometry(m)) => {
                    session.vo_odometry(&m);
                }
                _ => session.undecodable(),
            }
        }
        session.watch(now_secs);
        Ok(took)
    }

    /// Decides the waiting pairs the odometry has reached (`odometry_ns`:
    /// the stamp of the last joint state processed), or that have waited
    /// `wait`; forwards those chosen and publishes every decision.
    pub(super) fn decide(
        &mut self,
        session: &mut GateSession<RawCdr>,
        odometry_ns: Option<i64>,
        wait: Duration,
        now_secs: f64,
    ) -> Result<(), NodeError> {
        while let Some((pair, since)) = self.waiting.front() {
            let reached = odometry_ns.is_some_and(|t| t >= pair.stamp_ns);
            if !reached && since.elapsed() < wait {
                break;
            }
            if !reached {
                self.traffic.decided_before_odometry += 1;
            }
            let Some((pair, _)) = self.waiting.pop_front() else {
                break;
            };
            let (decision, forwarded) = session.decide(pair, now_secs);
            self.traffic.decided += 1;
            // The decision goes first, so that a consumer of both has it
            // before the pair.
            let status = decision_status(&decision);
            self.decisions
                .write(
                    RawCdr::from_encoded(diagnostic_status_message(&status)),
                    None,
                )
                .map_err(|e| dds_error("decision", e))?;
            if let Some(pair) = forwarded {
                self.traffic.forwarded += 1;
                let parts = [pair.left, pair.right, pair.left_info, pair.right_info];
                for (w, message) in self.gated.iter().zip(parts) {
                    w.write(message, None)
                        .map_err(|e| dds_error("gated pair", e))?;
                }
            }
        }
        Ok(())
    }
}
