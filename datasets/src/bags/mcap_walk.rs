//! An MCAP file read record by record, with everything a damaged byte
//! could upset checked before it is trusted:
//!
//! * every record's length against the file, and a chunk's sizes against
//!   [`mcap_record_limit`] (a damaged length is an error, not an
//!   allocation that aborts the process);
//! * every chunk's CRC against its uncompressed data, before any of its
//!   messages is visited (a chunk is read whole, then visited);
//! * the data section's CRC (where the writer stored one), which also
//!   covers the schema, channel and index records between the chunks;
//! * every message's receive time against the recording's declared span
//!   (the summary's statistics).
//!
//! With [`OnDamage::Skip`] a damaged chunk is left out and the walk goes on
//! at the next record; a record whose length cannot be trusted is skipped
//! to the next chunk the summary's chunk index names.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::Path;

use mcap::read::{ChannelAccumulator, Summary, parse_record};
use mcap::records::{self, Record, op};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

use super::damage::{Checksums, Damage, OnDamage};
use super::{BagError, BagFormat, RawMessage, Visited};

/// The most bytes one MCAP record (a chunk's uncompressed data included)
/// may claim in a file of `file_len` bytes: 64 times the file, at least
/// 64 MiB, at most 4 GiB (writers cut chunks at a few MiB).
fn mcap_record_limit(file_len: usize) -> usize {
    file_len.saturating_mul(64).clamp(64 << 20, 4 << 30)
}

/// A message read out of a chunk, kept until the chunk proves intact.
struct Pending<'a> {
    channel: u16,
    sequence: u32,
    log_time: u64,
    data: Cow<'a, [u8]>,
}

/// One walk over a file.
struct Walk<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    on_damage: OnDamage,
    summary: Option<Summary>,
    channels: ChannelAccumulator<'static>,
    damage: Damage,
    /// Which checksums were there to check.
    checksums: Checksums,
    /// Messages visited.
    visited: usize,
    /// The latest receive time visited (ns).
    last_ns: u64,
}

impl Walk<'_> {
    /// Damage at `detail`: an error when stopping, a recorded part (with
    /// the seconds it spans) when skipping.
    fn damaged(&mut self, detail: String, span_ns: Option<(u64, u64)>) -> Result<(), BagError> {
        match self.on_damage {
            OnDamage::Stop => Err(BagError::Corrupt {
                path: self.path.to_path_buf(),
                index: self.visited,
                detail: format!(
                    "{detail} (to skip damaged chunks and go on: `skip_damaged: true` in the topic map, or `gpodo bag info --skip-damaged`)"
                ),
            }),
            OnDamage::Skip => {
                if let Some((start, end)) = span_ns {
                    self.damage.seconds_lost += end.saturating_sub(start) as f64 * 1e-9;
                }
                self.damage.parts.push(detail);
                Ok(())
            }
        }
    }

    /// The recording's declared span of receive times (ns), from the
    /// summary's statistics.
    fn declared_span(&self) -> Option<(u64, u64)> {
        self.summary
            .as_ref()
            .and_then(|s| s.stats.as_ref())
            .filter(|s| s.message_count > 0)
            .map(|s| (s.message_start_time, s.message_end_time))
    }

    /// The messages' time range of the chunk at byte `at`: the summary's
    /// chunk index when it has the chunk, else the chunk's own `header`
    /// (kept within the declared span: a damaged header can say anything).
    fn chunk_span(&self, at: usize, header: Option<&records::ChunkHeader>) -> Option<(u64, u64)> {
        let indexed = self.summary.as_ref().and_then(|s| {
            s.chunk_indexes
                .iter()
                .find(|c| c.chunk_start_offset == at as u64)
                .map(|c| (c.message_start_time, c.message_end_time))
        });
        indexed.or_else(|| {
            let h = header?;
            let (lo, hi) = self.declared_span().unwrap_or((0, u64::MAX));
            Some((
                h.message_start_time.clamp(lo, hi),
                h.message_end_time.clamp(lo, hi),
            ))
        })
    }

    /// Every record of the chunk `record` (the whole record, opcode and
    /// length included), read with its CRC checked before any record is
    /// given out and every length bounded; or what is wrong with it.
    fn read_chunk(
        &self,
        record: &[u8],
    ) -> Result<(Vec<Record<'static>>, Vec<Pending<'static>>), String> {
        let options = LinearReaderOptions::default()
            .with_skip_start_magic(true)
            .with_skip_end_magic(true)
            .with_prevalidate_chunk_crcs(true)
            .with_record_length_limit(mcap_record_limit(self.bytes.len()));
        let mut reader = LinearReader::new_with_options(options);
        let mut rest = record;
        let mut definitions = Vec::new();
        let mut messages = Vec::new();
        while let Some(event) = reader.next_event() {
            let event = event.map_err(|e| match e {
                mcap::McapError::BadChunkCrc { saved, calculated } => {
                    format!("its CRC is {saved:08X}, its data give {calculated:08X}")
                }
                e => e.to_string(),
            })?;
            let (opcode, data) = match event {
                LinearReadEvent::ReadRequest(need) => {
                    let len = need.min(rest.len());
                    reader.insert(len).copy_from_slice(&rest[..len]);
                    reader.notify_read(len);
                    rest = &rest[len..];
                    continue;
                }
                LinearReadEvent::Record { data, opcode } => (opcode, data),
            };
            match parse_record(opcode, data).map_err(|e| e.to_string())? {
                Record::Message { header, data } => messages.push(Pending {
                    channel: header.channel_id,
                    sequence: header.sequence,
                    log_time: header.log_time,
                    data: Cow::Owned(data.into_owned()),
                }),
                r @ (Record::Schema { .. } | Record::Channel(_)) => {
                    definitions.push(r.into_owned());
                }
                _ => {}
            }
        }
        Ok((definitions, messages))
    }

    /// Adds a schema or channel record to the channels known.
    fn define(&mut self, record: Record<'_>) -> Result<(), String> {
        match record {
            Record::Schema { header, data } => self
                .channels
                .add_schema_from_slice(header, &data)
                .map_err(|e| e.to_string()),
            Record::Channel(channel) => self
                .channels
                .add_channel(channel)
                .map_err(|e| e.to_string()),
            _ => Ok(()),
        }
    }

    /// What is wrong with `messages` (an unknown channel, a stamp outside
    /// the declared span), if anything.
    fn check_messages(&self, messages: &[Pending<'_>]) -> Result<(), String> {
        let span = self.declared_span();
        for m in messages {
            if self.channels.get(m.channel).is_none() {
                return Err(format!(
                    "message {} names channel {}, which no channel record defines",
                    m.sequence, m.channel
                ));
            }
            if let Some((start, end)) = span
                && !(start..=end).contains(&m.log_time)
            {
                return Err(format!(
                    "a message stamped {} ns, outside the recording's declared span {start} … {end} ns (its summary statistics)",
                    m.log_time
                ));
            }
        }
        Ok(())
    }

    /// Visits `messages`, which have been checked.
    fn visit_all(&mut self, messages: Vec<Pending<'_>>, visit: &mut dyn FnMut(RawMessage<'_>)) {
        for m in messages {
            let Some(channel) = self.channels.get(m.channel) else {
                continue;
            };
            visit(RawMessage {
                index: self.visited,
                topic: &channel.topic,
                message_type: channel.schema.as_ref().map_or("", |s| s.name.as_str()),
                encoding: &channel.message_encoding,
                log_time_ns: m.log_time,
                data: &m.data,
            });
            self.visited += 1;
            self.last_ns = self.last_ns.max(m.log_time);
        }
    }

    /// A chunk record at byte `at` with body `body`: visited whole if it
    /// is intact, else damage.
    fn chunk(
        &mut self,
        at: usize,
        body: &[u8],
        visit: &mut dyn FnMut(RawMessage<'_>),
    ) -> Result<(), BagError> {
        let header = match parse_record(op::CHUNK, body) {
            Ok(Record::Chunk { header, .. }) => header,
            Ok(_) => return Ok(()),
            Err(e) => {
                let span = self.chunk_span(at, None);
                self.damage.chunks_skipped += 1;
                return self.damaged(format!("the chunk at byte {at} is unreadable ({e})"), span);
            }
        };
        if header.uncompressed_crc == 0 {
            self.checksums.chunks_without += 1;
        } else {
            self.checksums.chunks_checked += 1;
        }
        let span = self.chunk_span(at, Some(&header));
        let record = &self.bytes[at..at + 9 + body.len()];
        let read = self.read_chunk(record).and_then(|(definitions, messages)| {
            for d in definitions {
                self.define(d)?;
            }
            self.check_messages(&messages)?;
            Ok(messages)
        });
        match read {
            Ok(messages) => {
                self.visit_all(messages, visit);
                Ok(())
            }
            Err(why) => {
                self.damage.chunks_skipped += 1;
                let stamped = span.map_or_else(String::new, |(s, e)| {
                    format!(
                        ", holding messages stamped {:.3} … {:.3} s",
                        s as f64 * 1e-9,
                        e as f64 * 1e-9
                    )
                });
                self.damaged(
                    format!("the chunk at byte {at}{stamped} is damaged: {why}"),
                    span,
                )
            }
        }
    }

    /// Checks the summary section's CRC, which the footer at byte `at`
    /// (with `body`) stores: over the bytes from the summary's start
    /// through the footer's `summary_offset_start` field.
    fn check_summary_crc(&mut self, at: usize, body: &[u8]) -> Result<(), BagError> {
        let Ok(Record::Footer(footer)) = parse_record(op::FOOTER, body) else {
            return Ok(());
        };
        if footer.summary_start == 0 {
            return Ok(());
        }
        self.checksums.summary = Some(footer.summary_crc != 0);
        // The footer's body: summary_start, summary_offset_start, then the CRC.
        let end = at + 9 + 16;
        let Some(covered) = usize::try_from(footer.summary_start)
            .ok()
            .and_then(|start| self.bytes.get(start..end))
        else {
            return self.damaged(
                format!(
                    "the footer puts the summary at byte {}, outside the file",
                    footer.summary_start
                ),
                None,
            );
        };
        let calculated = crc32fast::hash(covered);
        if footer.summary_crc != 0 && footer.summary_crc != calculated && self.damage.is_empty() {
            return self.damaged(
                format!(
                    "the summary section's CRC is {:08X}, its bytes give {calculated:08X}: the statistics or indexes after the messages are damaged",
                    footer.summary_crc
                ),
                None,
            );
        }
        Ok(())
    }

    /// Where to go on after a record at byte `at` whose length cannot be
    /// trusted: the next chunk the summary indexes (the chunk holding `at`
    /// counted as lost), or `None` for the end of the file.
    fn resume_after(&mut self, at: usize) -> Option<usize> {
        let chunks = self.summary.as_ref().map(|s| &s.chunk_indexes)?;
        let holding = chunks
            .iter()
            .find(|c| {
                c.chunk_start_offset <= at as u64
                    && (at as u64) < c.chunk_start_offset.saturating_add(c.chunk_length)
            })
            .map(|c| (c.message_start_time, c.message_end_time));
        let next = chunks
            .iter()
            .map(|c| c.chunk_start_offset)
            .filter(|&o| o > at as u64)
            .min()
            .and_then(|o| usize::try_from(o).ok());
        if let Some((start, end)) = holding {
            self.damage.chunks_skipped += 1;
            self.damage.seconds_lost += end.saturating_sub(start) as f64 * 1e-9;
        }
        next
    }
}

/// Visits every message of the MCAP file at `path` in file order; returns
/// how many were visited, what was skipped and the summary's counts.
pub(super) fn visit_mcap(
    path: &Path,
    on_damage: OnDamage,
    visit: &mut dyn FnMut(RawMessage<'_>),
) -> Result<Visited, BagError> {
    let bytes = std::fs::read(path).map_err(|source| BagError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut walk = Walk {
        path,
        bytes: &bytes,
        on_damage,
        summary: None,
        channels: ChannelAccumulator::default(),
        damage: Damage::default(),
        checksums: Checksums::default(),
        visited: 0,
        last_ns: 0,
    };
    match Summary::read(&bytes) {
        Ok(summary) => walk.summary = summary,
        Err(e) => walk.damaged(
            format!(
                "the summary section (statistics and indexes after the messages) is unreadable ({e}): the file is truncated, still being recorded, or damaged"
            ),
            None,
        )?,
    }
    if on_damage == OnDamage::Skip
        && let Some(summary) = &walk.summary
    {
        // Channels defined inside a skipped chunk are still known.
        walk.channels = ChannelAccumulator::from_summary(summary);
    }
    let mut at = mcap::MAGIC.len();
    let mut footer = false;
    while at < bytes.len() {
        let framed = bytes.get(at..at.saturating_add(9)).and_then(|head| {
            let len = u64::from_le_bytes(head[1..9].try_into().ok()?);
            let end = usize::try_from(len).ok()?.checked_add(at + 9)?;
            (end <= bytes.len()).then_some((head[0], end))
        });
        let Some((opcode, end)) = framed else {
            walk.damaged(
                format!(
                    "the record at byte {at} runs past the end of the file ({} bytes): truncated, or its length is damaged",
                    bytes.len()
                ),
                None,
            )?;
            match walk.resume_after(at) {
                Some(next) => {
                    at = next;
                    continue;
                }
                None => break,
            }
        };
        let body = &bytes[at + 9..end];
        match opcode {
            op::CHUNK => walk.chunk(at, body, visit)?,
            op::SCHEMA | op::CHANNEL => {
                if let Err(why) = parse_record(opcode, body)
                    .map_err(|e| e.to_string())
                    .and_then(|r| walk.define(r))
                {
                    walk.damaged(
                        format!("the schema or channel record at byte {at} is damaged: {why}"),
                        None,
                    )?;
                }
            }
            op::MESSAGE => {
                let message = match parse_record(opcode, body) {
                    Ok(Record::Message { header, data }) => Ok(Pending {
                        channel: header.channel_id,
                        sequence: header.sequence,
                        log_time: header.log_time,
                        data,
                    }),
                    Ok(_) => Err("not a message".to_string()),
                    Err(e) => Err(e.to_string()),
                };
                match message
                    .and_then(|m| walk.check_messages(std::slice::from_ref(&m)).map(|()| m))
                {
                    Ok(m) => walk.visit_all(vec![m], visit),
                    Err(why) => walk.damaged(
                        format!("the message record at byte {at} is damaged: {why}"),
                        None,
                    )?,
                }
            }
            op::DATA_END => {
                if let Ok(Record::DataEnd(d)) = parse_record(opcode, body) {
                    walk.checksums.data_section = Some(d.data_section_crc != 0);
                    let calculated = crc32fast::hash(&bytes[..at]);
                    if d.data_section_crc != 0
                        && d.data_section_crc != calculated
                        && walk.damage.is_empty()
                    {
                        walk.damaged(
                            format!(
                                "the data section's CRC is {:08X}, its bytes give {calculated:08X}: a record between the chunks (a schema, channel or index) is damaged",
                                d.data_section_crc
                            ),
                            None,
                        )?;
                    }
                }
            }
            op::FOOTER => {
                footer = true;
                walk.check_summary_crc(at, body)?;
                break;
            }
            _ => {}
        }
        at = end;
    }
    if !footer && walk.damage.is_empty() {
        walk.damaged(
            format!(
                "the file ends at byte {} without its footer: truncated, or still being recorded",
                bytes.len()
            ),
            None,
        )?;
    }
    // A damaged opcode turns a chunk into a record of unknown kind, which
    // the format says to pass over: only the summary's count notices.
    if walk.damage.is_empty()
        && let Some(s) = walk.summary.as_ref().and_then(|s| s.stats.as_ref())
        && s.message_count != walk.visited as u64
    {
        walk.damaged(
            format!(
                "the summary declares {} messages, the records hold {}: a record's opcode or length is damaged",
                s.message_count, walk.visited
            ),
            None,
        )?;
    }
    let declared_span_ns = walk.declared_span();
    let mut damage = walk.damage;
    if !damage.is_empty() {
        let stats = walk.summary.as_ref().and_then(|s| s.stats.as_ref());
        damage.messages_lost = match stats {
            Some(s) => Some(s.message_count.saturating_sub(walk.visited as u64)),
            // Every record was walked and no chunk was left out.
            None if footer && damage.chunks_skipped == 0 => Some(0),
            None => None,
        };
        if !footer && let Some(s) = stats {
            damage.seconds_lost += s.message_end_time.saturating_sub(walk.last_ns) as f64 * 1e-9;
        }
    }
    Ok(Visited {
        format: BagFormat::Mcap,
        messages: walk.visited,
        damage,
        declared_counts: walk.summary.as_ref().and_then(declared_counts),
        checksums: Some(walk.checksums),
        declared_span_ns,
    })
}

/// The topics' message counts a summary declares in its statistics, by
/// topic; `None` without statistics, or with a count for a channel it does
/// not define.
fn declared_counts(summary: &Summary) -> Option<BTreeMap<String, u64>> {
    let stats = summary.stats.as_ref()?;
    let mut counts = BTreeMap::new();
    for (id, n) in &stats.channel_message_counts {
        let channel = summary.channels.get(id)?;
        *counts.entry(channel.topic.clone()).or_insert(0) += n;
    }
    Some(counts)
}
