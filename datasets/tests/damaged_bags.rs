//! Damaged recordings fail fast and clearly. An MCAP written by gpodo's
//! own writer is damaged at 200 seeded offsets (8 bytes overwritten) and
//! cut at 20 seeded lengths, and so are the shipped MCAP, ROS 1 and (with the
//! `db3` feature) SQLite fixtures, 40 of their 200 offsets in the first 256
//! bytes and 40 in the last eighth. Every read returns within a watchdog far
//! above the intact file's time, never panics, and either fails with an
//! error naming the file or returns the intact file's rows (the written
//! MCAP), or messages (the fixtures: equal but where the damage fell inside
//! a message's own bytes, which a container without checksums cannot
//! tell from data).
//! Skipping damaged chunks reads the intact file less whole chunks and
//! counts what it lost. A stamp far outside the recording and a `rate_hz`
//! typo are refused before the common clock is walked.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use gpodo_datasets::bags::import::{ImportError, TopicMap, import_bag};
use gpodo_datasets::bags::write::{write_mcap, written_topic_map};
use gpodo_datasets::bags::{Damage, OnDamage, visit_messages_with};
use gpodo_datasets::log::RoverLog;
use gpodo_traits::ProprioceptiveSample;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A robot driving straight at 0.3 m/s, 10 Hz, 60 s.
fn straight() -> RoverLog {
    let n = 600;
    let mut samples = Vec::new();
    let mut ground_truth = Vec::new();
    for k in 0..n {
        let t = k as f64 * 0.1;
        let mut s = ProprioceptiveSample {
            time_secs: t,
            ..Default::default()
        };
        s.imu.get_or_insert_default().accel_mps2 = Vector3::new(0.0, 0.0, 9.81);
        samples.push(s);
        ground_truth.push(Isometry3::from_parts(
            Translation3::new(0.3 * t, 0.0, 0.0),
            UnitQuaternion::identity(),
        ));
    }
    RoverLog {
        name: "straight".into(),
        wheel_names: vec![],
        steer_names: vec![],
        bogie_names: vec![],
        samples,
        ground_truth,
        camera_times_secs: vec![],
    }
}

type Imported = Result<(RoverLog, usize), String>;

/// `import_bag` on another thread, or `None` when it has not returned
/// within `limit` (a hang) or panicked.
fn import_within(path: &Path, map: &TopicMap, limit: Duration) -> Option<Imported> {
    let (tx, rx) = mpsc::channel();
    let (path, map): (PathBuf, TopicMap) = (path.to_path_buf(), map.clone());
    std::thread::spawn(move || {
        let out = import_bag(&path, "x", &map)
            .map(|(log, report)| (log, report.rows))
            .map_err(|e| e.to_string());
        let _ = tx.send(out);
    });
    rx.recv_timeout(limit).ok()
}

/// One message as stored: topic, receive time, bytes.
type Message = (String, u64, Vec<u8>);

/// Every message of the bag at `path` (and what was skipped) on another
/// thread, or `None` when it has not returned within `limit` or panicked.
fn messages_within(
    path: &Path,
    on_damage: OnDamage,
    limit: Duration,
) -> Option<Result<(Vec<Message>, Damage), String>> {
    let (tx, rx) = mpsc::channel();
    let path = path.to_path_buf();
    std::thread::spawn(move || {
        let mut messages = Vec::new();
        let out = visit_messages_with(&path, on_damage, |m| {
            messages.push((m.topic.to_string(), m.log_time_ns, m.data.to_vec()));
        })
        .map(|v| (messages, v.damage))
        .map_err(|e| e.to_string());
        let _ = tx.send(out);
    });
    rx.recv_timeout(limit).ok()
}

/// Whether `part` is `whole` with some runs of messages left out.
fn is_subsequence(part: &[Message], whole: &[Message]) -> bool {
    let mut rest = whole.iter();
    part.iter().all(|m| rest.any(|w| w == m))
}

#[test]
fn damaged_bytes_and_truncations_give_the_intact_rows_or_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let log = straight();
    let bag = write_mcap(&log, tmp.path()).unwrap();
    let map = written_topic_map(&log, 10.0);
    let start = Instant::now();
    let (intact, rows) = import_bag(&bag.path, "x", &map).unwrap();
    assert_eq!(rows.rows, 600);
    // Generous: only a hang trips it.
    let limit = (start.elapsed() * 100).max(Duration::from_secs(5));
    let (all, none) = messages_within(&bag.path, OnDamage::Stop, limit)
        .unwrap()
        .unwrap();
    assert!(none.is_empty());
    let bytes = std::fs::read(&bag.path).unwrap();
    let damaged = tmp.path().join("damaged.mcap");
    let mut rng = ChaCha8Rng::seed_from_u64(39);
    let mut cases: Vec<Vec<u8>> = (0..200)
        .map(|_| {
            let mut b = bytes.clone();
            let at = rng.random_range(0..b.len() - 8);
            b[at..at + 8].copy_from_slice(&rng.random::<u64>().to_le_bytes());
            b
        })
        .collect();
    cases.extend((0..20).map(|_| bytes[..rng.random_range(0..bytes.len())].to_vec()));
    let (mut failed, mut same, mut recovered, mut lossless) = (0, 0, 0, 0);
    for (k, case) in cases.iter().enumerate() {
        std::fs::write(&damaged, case).unwrap();
        match import_within(&damaged, &map, limit) {
            None => panic!("case {k}: no answer within {limit:?} (a hang or a panic)"),
            Some(Err(e)) => {
                assert!(e.contains("damaged.mcap"), "case {k}: {e}");
                failed += 1;
            }
            Some(Ok((got, _))) => {
                assert_eq!(got.samples, intact.samples, "case {k}: different rows");
                assert_eq!(got.ground_truth, intact.ground_truth, "case {k}");
                same += 1;
            }
        }
        // Skipping: what is read is the intact file less whole chunks, and
        // the count of what was lost is right.
        match messages_within(&damaged, OnDamage::Skip, limit) {
            None => panic!("case {k}: no answer when skipping (a hang or a panic)"),
            Some(Err(e)) => assert!(e.contains("damaged.mcap"), "case {k}: {e}"),
            Some(Ok((got, damage))) => {
                assert!(
                    is_subsequence(&got, &all),
                    "case {k}: messages not in the file"
                );
                if damage.is_empty() {
                    assert_eq!(got, all, "case {k}: messages lost without a word");
                }
                if let Some(lost) = damage.messages_lost {
                    assert_eq!(lost as usize, all.len() - got.len(), "case {k}: {damage}");
                }
                if got.len() == all.len() {
                    lossless += 1;
                } else if !got.is_empty() {
                    recovered += 1;
                }
            }
        }
    }
    // Every byte is covered by a CRC or a length check, so stopping fails
    // nearly every case; skipping keeps every message of the intact
    // chunks.
    assert!(failed >= 200, "{failed} failed, {same} identical");
    assert!(
        recovered >= 80 && lossless >= 80,
        "skipping: {recovered} kept part, {lossless} kept everything"
    );
}

#[test]
fn a_damaged_chunk_is_named_or_skipped_with_what_it_held() {
    let tmp = tempfile::tempdir().unwrap();
    let log = straight();
    let bag = write_mcap(&log, tmp.path()).unwrap();
    let mut bytes = std::fs::read(&bag.path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    assert!(
        summary.chunk_indexes.len() >= 5,
        "{}",
        summary.chunk_indexes.len()
    );
    let chunk = summary.chunk_indexes[2].clone();
    let (all, _) = messages_within(&bag.path, OnDamage::Stop, Duration::from_secs(20))
        .unwrap()
        .unwrap();
    let held = all
        .iter()
        .filter(|m| (chunk.message_start_time..=chunk.message_end_time).contains(&m.1))
        .count();
    // Its stored CRC changed (after opcode, length, two stamps and the
    // uncompressed size): the data decompress, but disagree with it.
    let crc_at = chunk.chunk_start_offset as usize + 9 + 24;
    let saved = u32::from_le_bytes(bytes[crc_at..crc_at + 4].try_into().unwrap());
    bytes[crc_at..crc_at + 4].copy_from_slice(&(saved ^ 0xFFFF).to_le_bytes());
    let damaged = tmp.path().join("damaged.mcap");
    std::fs::write(&damaged, &bytes).unwrap();
    let e = messages_within(&damaged, OnDamage::Stop, Duration::from_secs(20))
        .unwrap()
        .unwrap_err();
    let secs = |ns: u64| format!("{:.3}", ns as f64 * 1e-9);
    let names_the_chunk = |e: &str| {
        e.contains("damaged.mcap")
            && e.contains(&format!("chunk at byte {}", chunk.chunk_start_offset))
            && e.contains(&secs(chunk.message_start_time))
            && e.contains(&secs(chunk.message_end_time))
            && e.contains("skip_damaged: true")
    };
    assert!(
        names_the_chunk(&e)
            && e.contains(&format!(
                "its CRC is {:08X}, its data give {saved:08X}",
                saved ^ 0xFFFF
            )),
        "{e}"
    );
    // Eight bytes in the middle of its compressed data: zstd finds them.
    bytes[crc_at..crc_at + 4].copy_from_slice(&saved.to_le_bytes());
    let at = (chunk.chunk_start_offset + chunk.chunk_length / 2) as usize;
    bytes[at..at + 8].copy_from_slice(&0x0123_4567_89ab_cdef_u64.to_le_bytes());
    std::fs::write(&damaged, &bytes).unwrap();
    let e = messages_within(&damaged, OnDamage::Stop, Duration::from_secs(20))
        .unwrap()
        .unwrap_err();
    assert!(names_the_chunk(&e) && e.contains("decompression"), "{e}");
    let (got, damage) = messages_within(&damaged, OnDamage::Skip, Duration::from_secs(20))
        .unwrap()
        .unwrap();
    assert_eq!(damage.chunks_skipped, 1, "{damage}");
    assert_eq!(damage.messages_lost, Some(held as u64), "{damage}");
    assert_eq!(got.len(), all.len() - held);
    let span = (chunk.message_end_time - chunk.message_start_time) as f64 * 1e-9;
    assert!((damage.seconds_lost - span).abs() < 1e-9, "{damage}");
    // The import goes on past the chunk when asked, and says what it lost.
    let mut map = written_topic_map(&log, 10.0);
    assert!(import_bag(&damaged, "x", &map).is_err());
    map.skip_damaged = true;
    let (imported, report) = import_bag(&damaged, "x", &map).unwrap();
    assert!(imported.samples.len() < 600 && report.rows_dropped > 0);
    let note = report.damage.to_string();
    assert!(
        note.starts_with(&format!(
            "skipped 1 damaged chunk: {held} messages and {span:.3} s of recording lost"
        )),
        "{note}"
    );
    // So does `bag info`, which counts against the summary.
    let info = gpodo_datasets::bags::BagInfo::read_with(&damaged, OnDamage::Skip).unwrap();
    let text = info.to_text();
    assert!(
        text.contains("Damage:") && text.contains("the summary declares"),
        "{text}"
    );
}

/// The damage of case `k` of 220 to a file of `len` bytes: 20 cuts at
/// seeded lengths, then 8 bytes overwritten at 200 seeded offsets, 40 of
/// them in the first 256 bytes (magic, header, the first records), 40 in
/// the last eighth (indexes, summary, footer) and the rest anywhere.
fn case(k: usize, len: usize, rng: &mut ChaCha8Rng) -> (Option<usize>, Option<usize>) {
    if k < 20 {
        return (Some(rng.random_range(0..len)), None);
    }
    let at = match k {
        20..60 => rng.random_range(0..256.min(len - 8)),
        60..100 => rng.random_range(len - len / 8..len - 8),
        _ => rng.random_range(0..len - 8),
    };
    (None, Some(at))
}

#[test]
fn the_shipped_fixtures_damaged_give_their_messages_or_a_clear_error() {
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let tmp = tempfile::tempdir().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let mut names = vec!["messages.mcap", "messages.bag"];
    if cfg!(feature = "db3") {
        names.push("messages.db3");
    }
    for name in names {
        let bytes = std::fs::read(fixtures.join(name)).unwrap();
        let intact = messages_within(&fixtures.join(name), OnDamage::Stop, Duration::from_secs(5))
            .unwrap()
            .unwrap()
            .0;
        let damaged = tmp.path().join(format!("damaged-{name}"));
        let (mut refused, mut equal, mut payload) = (0, 0, 0);
        for k in 0..220 {
            let mut b = bytes.clone();
            let (cut, at) = case(k, bytes.len(), &mut rng);
            if let Some(len) = cut {
                b.truncate(len);
            }
            if let Some(at) = at {
                b[at..at + 8].copy_from_slice(&rng.random::<u64>().to_le_bytes());
            }
            std::fs::write(&damaged, &b).unwrap();
            match messages_within(&damaged, OnDamage::Stop, Duration::from_secs(5)) {
                None => panic!("{name} case {k}: no answer (a hang or a panic)"),
                Some(Err(e)) => {
                    assert!(e.contains("damaged-"), "{name} case {k}: {e}");
                    refused += 1;
                }
                Some(Ok((read, _))) => {
                    // Every message is there, on its topic at its time. A
                    // container without checksums (this MCAP stores CRC 0,
                    // a ROS 1 bag and SQLite have none) cannot tell damage
                    // inside one message's bytes from data: at most the
                    // messages those 8 bytes touch may differ, and only
                    // where the damage fell.
                    assert_eq!(
                        read.len(),
                        intact.len(),
                        "{name} case {k}: at {at:?} cut {cut:?}, {:?}",
                        read.iter().map(|m| (&m.0, m.1)).collect::<Vec<_>>()
                    );
                    let differ: Vec<usize> =
                        (0..read.len()).filter(|&i| read[i] != intact[i]).collect();
                    for &i in &differ {
                        assert_eq!(
                            (&read[i].0, read[i].1),
                            (&intact[i].0, intact[i].1),
                            "{name} case {k}: message {i} moved"
                        );
                    }
                    let in_payload = at.is_some_and(|at| {
                        differ.iter().all(|&i| {
                            let payload = &intact[i].2;
                            payload.len() >= 8
                                && bytes
                                    .windows(payload.len())
                                    .position(|w| w == payload)
                                    .is_some_and(|p| at + 8 > p && at < p + payload.len())
                        })
                    });
                    assert!(
                        differ.is_empty() || (differ.len() <= 2 && in_payload),
                        "{name} case {k}: messages {differ:?} differ from the intact file's, not where the damage fell"
                    );
                    if differ.is_empty() {
                        equal += 1;
                    } else {
                        payload += 1;
                    }
                }
            }
        }
        eprintln!(
            "{name}: of 220 cases, {refused} refused, {equal} read intact, {payload} read with the damage inside one message's bytes"
        );
    }
}

#[test]
fn a_stamp_far_outside_the_recording_or_a_rate_typo_is_refused_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    let mut log = straight();
    // One sample (and its pose) stamped 30 years after the others: the
    // file's CRCs are right, its stamps are not.
    log.samples[599].time_secs = 1.0e9;
    let bag = write_mcap(&log, tmp.path()).unwrap();
    let map = written_topic_map(&log, 10.0);
    match import_within(&bag.path, &map, Duration::from_secs(20)) {
        Some(Err(e)) => assert!(e.contains("rate_hz") && e.contains("stamps"), "{e}"),
        other => panic!("expected a refusal, got {other:?}"),
    }
    // `bag info` gives the topics' real rate, and says the stamps are far
    // apart, instead of a rate of 0.00 Hz over 30 years.
    let info = gpodo_datasets::bags::BagInfo::read(&bag.path).unwrap();
    let imu = info.topics.iter().find(|t| t.topic == "/imu/data").unwrap();
    assert!((imu.typical_rate_hz().unwrap() - 10.0).abs() < 1e-6);
    let text = info.to_text();
    assert!(
        text.contains("stamps far apart") && !text.contains(" 0.00 Hz "),
        "{text}"
    );
    let log = straight();
    let bag = write_mcap(&log, tmp.path()).unwrap();
    let mut map = written_topic_map(&log, 10.0);
    map.rate_hz = 1.0e9;
    let e = import_bag(&bag.path, "x", &map).unwrap_err();
    assert!(matches!(e, ImportError::TooManyRows { .. }), "{e}");
    assert!(e.to_string().contains("`rate_hz: 1000000000`"), "{e}");
}

#[test]
fn bag_info_says_which_checksums_the_file_had_and_a_damaged_summary_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let bag = write_mcap(&straight(), tmp.path()).unwrap();
    let info = gpodo_datasets::bags::BagInfo::read(&bag.path).unwrap();
    let sums = info.checksums.unwrap();
    assert!(
        sums.chunks_checked > 1 && sums.chunks_without == 0,
        "{sums:?}"
    );
    assert_eq!((sums.data_section, sums.summary), (Some(true), Some(true)));
    assert!(
        info.checked().contains("the CRCs of") && !info.checked().contains("none stored"),
        "{}",
        info.checked()
    );
    // Rates from the summary's statistics too: 600 IMU messages over the
    // 59.9 s the summary declares.
    let imu = info.topics.iter().find(|t| t.topic == "/imu/data").unwrap();
    let rate = imu.summary_rate_hz.unwrap();
    assert!((rate - 600.0 / 59.9).abs() < 1e-6, "{rate}");
    assert!(
        info.to_text()
            .contains("the summary: 10.02 Hz over the recording")
    );
    // The shipped MCAP fixture stores 0 for every CRC: said, not claimed.
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/messages.mcap");
    let info = gpodo_datasets::bags::BagInfo::read(&fixture).unwrap();
    assert!(
        info.checked()
            .contains("no CRCs: the file stores none for 1 chunk"),
        "{}",
        info.checked()
    );
    // Damage in the summary section (between the data end and the footer).
    let mut bytes = std::fs::read(&bag.path).unwrap();
    let footer = bytes.len() - 8 - 9 - 20;
    let summary_start = u64::from_le_bytes(bytes[footer + 9..footer + 17].try_into().unwrap());
    let at = (summary_start as usize + footer) / 2;
    for b in &mut bytes[at..at + 4] {
        *b ^= 0x5a;
    }
    let damaged = tmp.path().join("damaged-summary.mcap");
    std::fs::write(&damaged, &bytes).unwrap();
    let e = gpodo_datasets::bags::BagInfo::read(&damaged)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("damaged-summary.mcap") && e.contains("summary"),
        "{e}"
    );
}
