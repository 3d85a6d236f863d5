//! `uncoil inspect run.mcap`: reads a run's MCAP log back with the `mcap` crate and tells
//! its channels, message counts, time range, metadata and energy ledger, and of the final
//! bang's drawings how many there are and where the tape crosses itself in them
//! ([`bang`]). It reads an unfinished file (`run.mcap.partial` after a crash) as far as its
//! data goes. It writes nothing.

pub mod bang;

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context as _;
use mcap::records::Record;

/// One channel as read back.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChannelInfo {
    /// Topic, e.g. `/state`.
    pub topic: String,
    /// Schema name, e.g. `foxglove.SceneUpdate`.
    pub schema: String,
    /// Schema encoding, e.g. `jsonschema`.
    pub schema_encoding: String,
    /// Message encoding, e.g. `json`.
    pub message_encoding: String,
    /// Messages read.
    pub messages: u64,
    /// Their bytes, before the file's compression.
    pub message_bytes: u64,
}

/// What a file holds, read message by message.
#[derive(Debug, Clone, PartialEq)]
pub struct Inventory {
    /// File size (bytes).
    pub bytes: u64,
    /// The writing library named in the header.
    pub library: String,
    /// Whether the file has its summary section: a finished file.
    pub finished: bool,
    /// Channels by topic.
    pub channels: BTreeMap<String, ChannelInfo>,
    /// First and last log time (ns), if any message was read.
    pub time_range_ns: Option<(u64, u64)>,
    /// Whether every channel's log times never decrease.
    pub time_ordered: bool,
    /// Metadata records by name (keys and values as written).
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// Why reading stopped early, for an unfinished or damaged file.
    pub read_error: Option<String>,
}

/// Reads a file and takes its inventory.
pub fn read_inventory(path: &Path) -> anyhow::Result<Inventory> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    inventory(&bytes)
}

/// Reads a file, takes its inventory and counts its final bang's drawings (`None` where
/// its ledger names no release).
pub fn read_with_bang(path: &Path) -> anyhow::Result<(Inventory, Option<bang::BangDrawings>)> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let inv = inventory(&bytes)?;
    let bang = bang::bang_drawings(&bytes, &inv)?;
    Ok((inv, bang))
}

/// Takes the inventory of an MCAP file in memory.
pub fn inventory(bytes: &[u8]) -> anyhow::Result<Inventory> {
    anyhow::ensure!(
        bytes.starts_with(mcap::MAGIC),
        "not an MCAP file (it does not start with the MCAP magic bytes)"
    );
    let finished = matches!(mcap::read::Summary::read(bytes), Ok(Some(_)));
    let mut library = String::new();
    let mut metadata = BTreeMap::new();
    let mut read_error = None;
    for record in mcap::read::LinearReader::new(bytes).context("not an MCAP file")? {
        match record {
            Ok(Record::Header(h)) => library = h.library,
            Ok(Record::Metadata(m)) => {
                metadata.insert(m.name, m.metadata);
            }
            Ok(_) => {}
            Err(e) => {
                read_error = Some(e.to_string());
                break;
            }
        }
    }
    let mut channels: BTreeMap<String, ChannelInfo> = BTreeMap::new();
    let mut range: Option<(u64, u64)> = None;
    let mut last: BTreeMap<String, u64> = BTreeMap::new();
    let mut time_ordered = true;
    for message in mcap::MessageStream::new(bytes).context("not an MCAP file")? {
        let m = match message {
            Ok(m) => m,
            Err(e) => {
                read_error.get_or_insert_with(|| e.to_string());
                break;
            }
        };
        let topic = m.channel.topic.clone();
        let entry = channels
            .entry(topic.clone())
            .or_insert_with(|| ChannelInfo {
                topic: topic.clone(),
                schema: m
                    .channel
                    .schema
                    .as_ref()
                    .map_or_else(String::new, |s| s.name.clone()),
                schema_encoding: m
                    .channel
                    .schema
                    .as_ref()
                    .map_or_else(String::new, |s| s.encoding.clone()),
                message_encoding: m.channel.message_encoding.clone(),
                messages: 0,
                message_bytes: 0,
            });
        entry.messages += 1;
        entry.message_bytes += m.data.len() as u64;
        if last.get(&topic).is_some_and(|&t| t > m.log_time) {
            time_ordered = false;
        }
        last.insert(topic, m.log_time);
        range = Some(range.map_or((m.log_time, m.log_time), |(a, b)| {
            (a.min(m.log_time), b.max(m.log_time))
        }));
    }
    Ok(Inventory {
        bytes: bytes.len() as u64,
        library,
        finished,
        channels,
        time_range_ns: range,
        time_ordered,
        metadata,
        read_error,
    })
}

fn secs(ns: u64) -> f64 {
    ns as f64 * 1e-9
}

/// The readable report of `uncoil inspect`.
pub fn describe(path: &Path, inv: &Inventory) -> String {
    let mut o = String::new();
    let _ = writeln!(
        o,
        "{}: {} bytes, written by {}",
        path.display(),
        inv.bytes,
        if inv.library.is_empty() {
            "(unknown)"
        } else {
            &inv.library
        }
    );
    if inv.finished {
        let _ = writeln!(o, "  finished: yes (summary section present)");
    } else {
        let _ = writeln!(
            o,
            "  finished: no (no summary section): read as far as the data goes"
        );
    }
    if let Some(e) = &inv.read_error {
        let _ = writeln!(o, "  reading stopped early: {e}");
    }
    match inv.time_range_ns {
        Some((a, b)) => {
            let _ = writeln!(
                o,
                "  time range: {:.6} s .. {:.6} s of simulated time",
                secs(a),
                secs(b)
            );
        }
        None => {
            let _ = writeln!(o, "  no messages");
        }
    }
    let _ = writeln!(
        o,
        "  time order: {}",
        if inv.time_ordered {
            "every channel in order"
        } else {
            "OUT OF ORDER"
        }
    );
    let _ = writeln!(o);
    let _ = writeln!(o, "Channels:");
    let _ = writeln!(
        o,
        "  {:<10} {:<25} {:<11} {:<9} {:>9} {:>15}",
        "topic", "schema", "schema enc", "enc", "messages", "uncompressed"
    );
    for c in inv.channels.values() {
        let _ = writeln!(
            o,
            "  {:<10} {:<25} {:<11} {:<9} {:>9} {:>15}",
            c.topic,
            c.schema,
            c.schema_encoding,
            c.message_encoding,
            c.messages,
            format!("{} bytes", c.message_bytes)
        );
    }
    for (name, map) in &inv.metadata {
        let _ = writeln!(o);
        let _ = writeln!(o, "Metadata \"{name}\":");
        for (k, v) in map {
            if v.contains('\n') {
                let _ = writeln!(o, "  {k}: {} lines of text", v.lines().count());
            } else {
                let _ = writeln!(o, "  {k} = {v}");
            }
        }
    }
    if !inv.metadata.contains_key("ledger") {
        let _ = writeln!(o);
        let _ = writeln!(o, "No ledger: the run did not finish writing this file.");
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn garbage_is_not_an_mcap_file() {
        assert!(inventory(b"not an mcap file at all").is_err());
    }
}
