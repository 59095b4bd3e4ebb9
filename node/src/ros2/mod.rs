//! The node on ROS 2, over DDS (RustDDS: no ROS installation needed).
//!
//! It speaks to ROS 2 as its DDS middlewares do (rmw_cyclonedds_cpp,
//! rmw_fastrtps_cpp on Humble and Jazzy): a topic `/a/b` is the DDS topic
//! `rt/a/b`, a type `pkg/msg/T` is `pkg::msg::dds_::T_`, and messages are
//! final types in plain CDR (XCDR1). The messages' bytes are gpodo's own
//! CDR codec, the one its bag reader and writer use, so that a message is
//! written once for bags and for the wire.
//!
//! * Subscribes (best effort, keep last 100, as sensor drivers publish) to
//!   the topic map's joint states and IMU.
//! * Publishes (reliable, keep last 10, volatile: ROS 2's defaults)
//!   `nav_msgs/Odometry` on `/odom/gp` (the published odometry) and
//!   `/odom/wheel` (the motion model's alone), and
//!   `diagnostic_msgs/DiagnosticArray` on `/diagnostics` once a second.
//! * With a gate ([`Ros2Gate`]), the stereo camera's four topics in, the
//!   chosen pairs and every decision out, and the VO's odometry in
//!   (`gate_io.rs`).
//!
//! Discovery: RustDDS announces itself to the well-known unicast ports of
//! the first participants on 127.0.0.1 as well as by multicast, so that
//! nodes on one machine find each other where the loopback interface has
//! no multicast; a Cyclone DDS peer there needs
//! `<Peers><Peer address="127.0.0.1"/></Peers>` (see the on-the-robot
//! tutorial).

use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use rustdds::bytes::Bytes;
use rustdds::no_key::{
    DataReader, DataWriter, Decode, DefaultDecoder, DeserializerAdapter, SerializerAdapter,
};
use rustdds::policy::{Durability, History, Reliability};
use rustdds::{
    DomainParticipant, DomainParticipantBuilder, QosPolicies, QosPolicyBuilder,
    RepresentationIdentifier, Topic, TopicKind,
};

use gpodo_datasets::bags::import::TopicMap;
use gpodo_datasets::bags::messages::{RosMessage, decode};
use gpodo_datasets::bags::write::diagnostic_array_message;
use gpodo_kinematics::RoverDescription;

use crate::NodeError;
use crate::diagnostics::Health;
use crate::feed::LiveFeed;
use crate::pipeline::LiveModel;
use crate::replay::{OUTPUT_TOPICS, output_messages};

mod gate_io;

pub use gate_io::{GateTraffic, Ros2Gate};

/// The diagnostics topic.
pub const DIAGNOSTICS_TOPIC: &str = "/diagnostics";

/// How the node runs on DDS.
#[derive(Debug, Clone, PartialEq)]
pub struct Ros2Settings {
    /// The DDS domain (ROS_DOMAIN_ID).
    pub domain_id: u16,
    /// Seconds between two `/diagnostics` messages (default 1).
    pub diagnostics_period_secs: f64,
    /// How long the loop sleeps when no message is waiting (default
    /// 0.5 ms): an input waits at most this long before it is taken.
    pub poll: Duration,
    /// How long a joint state may wait for the IMU reading of its own
    /// time (default 20 ms): DDS delivers the two topics independently, so
    /// a joint state can come before the IMU reading stamped with it; it
    /// waits until a reading at or after its stamp has come, or this long,
    /// and then takes the latest one before it (the stale-IMU warning
    /// says when that is old).
    pub imu_wait: Duration,
    /// Stop after this many outputs (none: run until stopped).
    pub max_outputs: Option<usize>,
    /// Stop when no input came for this long after the first one (s).
    pub idle_exit_secs: Option<f64>,
    /// The network interfaces DDS uses, by address (empty: all). With
    /// `127.0.0.1` alone, nothing leaves the machine.
    pub interfaces: Vec<std::net::IpAddr>,
    /// With a gate: how long a stereo pair may wait for the odometry to
    /// reach its stamp before it is decided on the odometry so far
    /// (default 100 ms).
    pub pair_wait: Duration,
}

impl Default for Ros2Settings {
    fn default() -> Self {
        Self {
            domain_id: 0,
            diagnostics_period_secs: 1.0,
            poll: Duration::from_micros(500),
            imu_wait: Duration::from_millis(20),
            max_outputs: None,
            idle_exit_secs: None,
            interfaces: Vec::new(),
            pair_wait: Duration::from_millis(100),
        }
    }
}

/// What a run on DDS did.
#[derive(Debug, Clone, PartialEq)]
pub struct Ros2Summary {
    /// Joint-state messages taken.
    pub joint_messages: usize,
    /// IMU messages taken.
    pub imu_messages: usize,
    /// Outputs published (each on both odometry topics).
    pub outputs: usize,
    /// Joint states that gave no output.
    pub skipped: usize,
    /// The last reason an input gave no output.
    pub last_skip: Option<String>,
    /// Latency p50 and p99 over the last outputs (s): from taking the
    /// joint state off its reader to both odometry messages written.
    pub latency_secs: Option<(f64, f64)>,
    /// Messages that could not be decoded.
    pub undecodable: usize,
    /// What the gate did, when there was one.
    pub gate: Option<GateTraffic>,
}

/// A message's CDR bytes without the encapsulation header, as DDS carries
/// them (the header is the representation identifier DDS sends apart).
#[derive(Debug, Clone)]
pub struct RawCdr {
    /// Little- or big-endian CDR.
    pub representation: RepresentationIdentifier,
    /// The body.
    pub body: Vec<u8>,
}

impl RawCdr {
    /// From gpodo's encoder output (header included, little-endian).
    fn from_encoded(mut bytes: Vec<u8>) -> Self {
        bytes.drain(..4.min(bytes.len()));
        Self {
            representation: RepresentationIdentifier::CDR_LE,
            body: bytes,
        }
    }

    /// The first `max` bytes of [`RawCdr::encoded`]: what a decoder of
    /// the header alone reads, without copying an image's pixels.
    fn encoded_head(&self, max: usize) -> Vec<u8> {
        let mut bytes = Vec::with_capacity(max.min(self.body.len()) + 4);
        bytes.extend(self.representation.to_bytes());
        bytes.extend([0, 0]);
        bytes.extend(&self.body[..max.min(self.body.len())]);
        bytes
    }

    /// The bytes with their encapsulation header, as a bag stores them.
    fn encoded(&self) -> Vec<u8> {
        let mut bytes = Vec::with_capacity(self.body.len() + 4);
        bytes.extend(self.representation.to_bytes());
        bytes.extend([0, 0]);
        bytes.extend(&self.body);
        bytes
    }
}

/// Passes CDR bodies through DDS unchanged.
pub struct RawCdrAdapter;

/// The (infallible) error of [`RawCdrAdapter`].
#[derive(Debug, thiserror::Error)]
#[error("raw CDR")]
pub struct RawCdrError;

/// [`RawCdrAdapter`]'s decoder.
#[derive(Clone)]
pub struct RawCdrDecoder;

impl<'de> Decode<'de, RawCdr> for RawCdrDecoder {
    type Error = RawCdrError;

    fn decode_bytes(
        self,
        input_bytes: &'de [u8],
        encoding: RepresentationIdentifier,
    ) -> Result<RawCdr, RawCdrError> {
        Ok(RawCdr {
            representation: encoding,
            body: input_bytes.to_vec(),
        })
    }
}

impl DeserializerAdapter<RawCdr> for RawCdrAdapter {
    type Error = RawCdrError;
    type Decoded = RawCdr;

    fn supported_encodings() -> &'static [RepresentationIdentifier] {
        &[
            RepresentationIdentifier::CDR_LE,
            RepresentationIdentifier::CDR_BE,
        ]
    }

    fn transform_decoded(decoded: RawCdr) -> RawCdr {
        decoded
    }
}

impl DefaultDecoder<RawCdr> for RawCdrAdapter {
    type Decoder = RawCdrDecoder;
    const DECODER: RawCdrDecoder = RawCdrDecoder;
}

impl SerializerAdapter<RawCdr> for RawCdrAdapter {
    type Error = RawCdrError;

    fn output_encoding() -> RepresentationIdentifier {
        RepresentationIdentifier::CDR_LE
    }

    fn to_bytes(value: &RawCdr) -> Result<Bytes, RawCdrError> {
        Ok(Bytes::from(value.body.clone()))
    }
}

/// ROS 2's DDS topic name of a ROS topic (`/odom/gp` → `rt/odom/gp`).
pub fn dds_topic_name(ros_topic: &str) -> String {
    format!("rt/{}", ros_topic.trim_start_matches('/'))
}

/// ROS 2's DDS type name of a message type (`nav_msgs/msg/Odometry` →
/// `nav_msgs::msg::dds_::Odometry_`).
pub fn dds_type_name(ros_type: &str) -> String {
    let parts: Vec<&str> = ros_type.split('/').collect();
    match parts.as_slice() {
        [package, "msg", name] | [package, name] => format!("{package}::msg::dds_::{name}_"),
        _ => ros_type.to_string(),
    }
}

fn dds_error(what: &str, e: impl std::fmt::Display) -> NodeError {
    NodeError::Dds(format!("{what}: {e}"))
}

fn topic(
    participant: &DomainParticipant,
    ros_topic: &str,
    ros_type: &str,
    qos: &QosPolicies,
) -> Result<Topic, NodeError> {
    participant
        .create_topic(
            dds_topic_name(ros_topic),
            dds_type_name(ros_type),
            qos,
            TopicKind::NoKey,
        )
        .map_err(|e| dds_error(&format!("topic {ros_topic}"), e))
}

/// QoS of sensor inputs: best effort, keep last `depth`, volatile.
fn sensor_qos(depth: i32) -> QosPolicies {
    QosPolicyBuilder::new()
        .reliability(Reliability::BestEffort)
        .history(History::KeepLast { depth })
        .durability(Durability::Volatile)
        .build()
}

/// QoS of outputs: ROS 2's defaults (reliable, keep last 10, volatile).
fn output_qos() -> QosPolicies {
    QosPolicyBuilder::new()
        .reliability(Reliability::Reliable {
            max_blocking_time: rustdds::Duration::from_millis(100),
        })
        .history(History::KeepLast { depth: 10 })
        .durability(Durability::Volatile)
        .build()
}

fn now_ns() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as i64)
}

/// Runs `model` on the rover `rover` from the DDS topics of `map` until
/// `stop` says so (or a limit of `settings` is reached); with `gate`, the
/// frame gate and its learner too (whose residual is then the one
/// published, and whose status joins `/diagnostics`).
///
/// # Errors
/// [`NodeError::Topics`] for a map that cannot drive the node,
/// [`NodeError::Dds`] when DDS fails.
pub fn run(
    map: &TopicMap,
    rover: &RoverDescription,
    model: &mut LiveModel,
    settings: &Ros2Settings,
    mut gate: Option<Ros2Gate<'_>>,
    stop: &dyn Fn() -> bool,
) -> Result<Ros2Summary, NodeError> {
    let joints_topic = map
        .joints
        .as_ref()
        .map(|j| j.topic.clone())
        .ok_or_else(|| NodeError::Topics("the topic map has no `joints:`".into()))?;
    let model_summary = model.summary().clone();
    let live_settings = *model.settings();
    let mut feed = LiveFeed::new(map, rover, model)?;
    let mut builder = DomainParticipantBuilder::new(settings.domain_id);
    if !settings.interfaces.is_empty() {
        builder = builder.with_only_networks(settings.interfaces.iter().copied());
    }
    let participant = builder.build().map_err(|e| dds_error("participant", e))?;
    let (sensors, outputs) = (sensor_qos(100), output_qos());
    let subscriber = participant
        .create_subscriber(&sensors)
        .map_err(|e| dds_error("subscriber", e))?;
    let publisher = participant
        .create_publisher(&outputs)
        .map_err(|e| dds_error("publisher", e))?;
    let reader =
        |ros_topic: &str, ros_type: &str| -> Result<DataReader<RawCdr, RawCdrAdapter>, NodeError> {
            let t = topic(&participant, ros_topic, ros_type, &sensors)?;
            subscriber
                .create_datareader_no_key::<RawCdr, RawCdrAdapter>(&t, None)
                .map_err(|e| dds_error(&format!("reader of {ros_topic}"), e))
        };
    let writer =
        |ros_topic: &str, ros_type: &str| -> Result<DataWriter<RawCdr, RawCdrAdapter>, NodeError> {
            let t = topic(&participant, ros_topic, ros_type, &outputs)?;
            publisher
                .create_datawriter_no_key::<RawCdr, RawCdrAdapter>(&t, None)
                .map_err(|e| dds_error(&format!("writer of {ros_topic}"), e))
        };
    let mut joint_reader = reader(&joints_topic, "sensor_msgs/msg/JointState")?;
    let mut imu_reader = match &map.imu {
        Some(t) => Some(reader(t, "sensor_msgs/msg/Imu")?),
        None => None,
    };
    let odometry = [
        writer(OUTPUT_TOPICS[0], "nav_msgs/msg/Odometry")?,
        writer(OUTPUT_TOPICS[1], "nav_msgs/msg/Odometry")?,
    ];
    let diagnostics = writer(DIAGNOSTICS_TOPIC, "diagnostic_msgs/msg/DiagnosticArray")?;
    let mut gate_io = match &gate {
        Some(g) => Some(gate_io::GateIo::new(
            &participant,
            &subscriber,
            &publisher,
            g,
            g.session.history_depth(),
        )?),
        None => None,
    };
    let started = Instant::now();
    let mut last_odometry_ns: Option<i64> = None;

    let mut health = Health::default();
    let mut summary = Ros2Summary {
        joint_messages: 0,
        imu_messages: 0,
        outputs: 0,
        skipped: 0,
        last_skip: None,
        latency_secs: None,
        undecodable: 0,
        gate: None,
    };
    let mut last_input: Option<Instant> = None;
    let mut last_report = Instant::now();
    let mut last_warning: Option<Instant> = None;
    let period = Duration::from_secs_f64(settings.diagnostics_period_secs.max(0.01));
    let status_name = format!("gpodo live: {}", OUTPUT_TOPICS[0]);
    let mut waiting = Vec::new();
    loop {
        if stop() {
            break;
        }
        let mut took = false;
        if let Some(r) = imu_reader.as_mut() {
            while let Some(s) = r.take_next_sample().map_err(|e| dds_error("IMU", e))? {
                took = true;
                let receive_ns = now_ns();
                last_input = Some(Instant::now());
                match decode("sensor_msgs/msg/Imu", "cdr", &s.value().encoded()) {
                    Ok(RosMessage::Imu(m)) => {
                        summary.imu_messages += 1;
                        feed.imu(&m, receive_ns);
                    }
                    _ => summary.undecodable += 1,
                }
            }
        }
        // Joint states wait, in their stamps' order, for the IMU reading of
        // their own time (at most `imu_wait`).
        while let Some(s) = joint_reader
            .take_next_sample()
            .map_err(|e| dds_error("joint states", e))?
        {
            took = true;
            let taken = Instant::now();
            last_input = Some(taken);
            match decode("sensor_msgs/msg/JointState", "cdr", &s.value().encoded()) {
                Ok(RosMessage::JointState(m)) => waiting.push((m, now_ns(), taken)),
                _ => summary.undecodable += 1,
            }
        }
        // Then the gate's: a VO pose that came before a joint state taken
        // above is learned from before that joint state is run.
        if let (Some(g), Some(io)) = (gate.as_mut(), gate_io.as_mut()) {
            took |= io.take(g.session, started.elapsed().as_secs_f64())?;
        }
        waiting.sort_by_key(|(m, _, _)| m.header.stamp_ns);
        let ready = waiting
            .iter()
            .take_while(|(m, _, taken)| {
                feed.imu_reached(m.header.stamp_ns) || taken.elapsed() >= settings.imu_wait
            })
            .count();
        let joints: Vec<_> = waiting.drain(..ready).collect();
        for (m, receive_ns, taken) in joints {
            summary.joint_messages += 1;
            let residual = gate.as_ref().and_then(|g| g.session.residual());
            match feed.joints_with(&m, receive_ns, residual) {
                Ok(fed) => {
                    if let Some(g) = gate.as_mut()
                        && let Err(e) = g.session.output(&fed.output, fed.stamp_ns)
                    {
                        health.skipped(format!("the gate: {e}"));
                    }
                    last_odometry_ns = Some(fed.stamp_ns);
                    let stamp = u64::try_from(fed.stamp_ns).unwrap_or(0);
                    for (w, bytes) in odometry.iter().zip(output_messages(stamp, &fed.output)) {
                        w.write(RawCdr::from_encoded(bytes), None)
                            .map_err(|e| dds_error("odometry", e))?;
                    }
                    health.output(&fed, taken.elapsed().as_secs_f64());
                }
                Err(reason) => {
                    // At most one warning a second; every one is counted
                    // in the diagnostics.
                    if last_warning.is_none_or(|t: Instant| t.elapsed() >= Duration::from_secs(1)) {
                        last_warning = Some(Instant::now());
                        tracing::warn!("joint state not used: {reason}");
                    }
                    health.skipped(reason);
                }
            }
        }
        if let (Some(g), Some(io)) = (gate.as_mut(), gate_io.as_mut()) {
            let now = started.elapsed().as_secs_f64();
            io.decide(g.session, last_odometry_ns, settings.pair_wait, now)?;
        }
        if last_report.elapsed() >= period {
            last_report = Instant::now();
            let status = health.report(
                &status_name,
                &model_summary,
                &live_settings,
                last_input.map(|t| t.elapsed().as_secs_f64()),
            );
            let mut statuses = vec![status];
            statuses.extend(gate.as_ref().map(|g| g.session.status()));
            let stamp = u64::try_from(now_ns()).unwrap_or(0);
            diagnostics
                .write(
                    RawCdr::from_encoded(diagnostic_array_message(stamp, &statuses)),
                    None,
                )
                .map_err(|e| dds_error("diagnostics", e))?;
        }
        if settings.max_outputs.is_some_and(|n| health.outputs() >= n) {
            break;
        }
        if let (Some(limit), Some(t)) = (settings.idle_exit_secs, last_input)
            && t.elapsed().as_secs_f64() > limit
        {
            break;
        }
        if !took {
            std::thread::sleep(settings.poll);
        }
    }
    summary.outputs = health.outputs();
    summary.skipped = health.skipped_count();
    summary.latency_secs = health.latency_secs();
    summary.last_skip = health.last_skip().map(str::to_string);
    summary.gate = gate_io.map(|io| io.traffic());
    Ok(summary)
}
