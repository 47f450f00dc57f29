//! The bag's container: its files, its MCAP records with their chunks decompressed, and its channels.

use std::collections::{BTreeMap, HashMap};
use std::io::Read;
use std::path::{Path, PathBuf};

use mcap::records::Record;

use crate::error::{Error, Result};

/// A channel of the bag, as its schema and channel records say.
pub(super) struct Channel {
    pub(super) topic: String,
    /// The message type, `package/msg/Name`.
    pub(super) kind: String,
    pub(super) encoding: String,
}

/// What each message of the bag is, by channel.
#[derive(Default)]
pub(super) struct Channels {
    schemas: HashMap<u16, String>,
    pub(super) channels: BTreeMap<u16, Channel>,
}

/// The bytes of the bag's files ([`bag_files`]), in order, at most `limit_bytes` of them together.
pub(super) fn read_bag_files(path: &Path, limit_bytes: u64) -> Result<Vec<(PathBuf, Vec<u8>)>> {
    let mut data = Vec::new();
    let mut left = limit_bytes;
    for f in bag_files(path)? {
        let bytes = crate::io::read_file(&f, left)?;
        left = left.saturating_sub(bytes.len() as u64);
        data.push((f, bytes));
    }
    Ok(data)
}

/// The earliest log time of the bag's messages, nanoseconds (`u64::MAX` for a bag without any): the origin of
/// the times its options count from.
pub(super) fn first_log_time(data: &[(PathBuf, Vec<u8>)], limit_bytes: u64) -> Result<u64> {
    let mut first = u64::MAX;
    for_each_message(data, limit_bytes, &mut Channels::default(), &mut |_, _, h, _| {
        first = first.min(h.log_time);
        Ok(())
    })?;
    Ok(first)
}

/// The bag's files: the `.mcap` itself, or a folder's `metadata.yaml`'s `relative_file_paths`.
fn bag_files(path: &Path) -> Result<Vec<PathBuf>> {
    if !path.is_dir() {
        return Ok(vec![path.to_path_buf()]);
    }
    let metadata = path.join("metadata.yaml");
    let text = oeg_files::read_text(&metadata)?;
    let files = relative_file_paths(&text);
    if files.is_empty() {
        return Err(Error::parse(
            &metadata,
            "no `relative_file_paths` entries: is this a rosbag2 folder's metadata?",
        ));
    }
    files
        .into_iter()
        .map(|f| {
            // rosbag2 writes names relative to the bag's folder; one that leaves it (an absolute path, `..`) is
            // not a file of this bag.
            let inside = Path::new(&f)
                .components()
                .all(|c| matches!(c, std::path::Component::Normal(_) | std::path::Component::CurDir));
            if inside {
                Ok(path.join(&f))
            } else {
                Err(Error::parse(
                    &metadata,
                    format!(
                        "`relative_file_paths` entry `{f}` leaves the bag's folder; expected a file name inside it"
                    ),
                ))
            }
        })
        .collect()
}

/// The entries of `relative_file_paths:` in a rosbag2 `metadata.yaml`, in block (`- a.mcap`) or flow
/// (`[a.mcap, b.mcap]`) style. The rest of the file is not read: the bag's own records say what it holds.
fn relative_file_paths(text: &str) -> Vec<String> {
    let unquote = |s: &str| s.trim().trim_matches(|c| c == '"' || c == '\'').to_string();
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        let Some(rest) = line.trim_start().strip_prefix("relative_file_paths:") else {
            continue;
        };
        let indent = line.len() - line.trim_start().len();
        let rest = rest.trim();
        if let Some(flow) = rest.strip_prefix('[') {
            return flow
                .trim_end_matches(']')
                .split(',')
                .map(unquote)
                .filter(|s| !s.is_empty())
                .collect();
        }
        return lines
            .take_while(|l| {
                let t = l.trim_start();
                t.starts_with("- ") && l.len() - t.len() >= indent
            })
            .map(|l| unquote(&l.trim_start()[2..]))
            .collect();
    }
    Vec::new()
}

/// What is done with each message: its file, its channel, its record header and its bytes.
pub(super) type OnMessage<'a> =
    dyn FnMut(&Path, &Channel, &mcap::records::MessageHeader, &[u8]) -> Result<()> + 'a;

/// Calls `f` with every message of the bag's files (`data`, in order), chunks decompressed, with its channel
/// (`channels` gathers them as their records come).
pub(super) fn for_each_message(
    data: &[(PathBuf, Vec<u8>)],
    limit_bytes: u64,
    channels: &mut Channels,
    f: &mut OnMessage,
) -> Result<()> {
    for (file, bytes) in data {
        file_messages(file, bytes, limit_bytes, channels, f)?;
    }
    Ok(())
}

/// [`for_each_message`] for one file.
fn file_messages(
    file: &Path,
    bytes: &[u8],
    limit_bytes: u64,
    channels: &mut Channels,
    f: &mut OnMessage,
) -> Result<()> {
    let container = |e: mcap::McapError| Error::parse(file, format!("not a readable MCAP file: {e}"));
    for record in mcap::read::LinearReader::new(bytes).map_err(container)? {
        match record.map_err(container)? {
            Record::Chunk { header, data } => {
                let records = decompress(file, &header, &data, limit_bytes)?;
                for inner in mcap::read::LinearReader::sans_magic(&records) {
                    visit(file, inner.map_err(container)?, channels, f)?;
                }
            }
            other => visit(file, other, channels, f)?,
        }
    }
    Ok(())
}

fn visit(file: &Path, record: Record, channels: &mut Channels, f: &mut OnMessage) -> Result<()> {
    match record {
        Record::Schema { header, .. } => {
            channels.schemas.insert(header.id, header.name);
        }
        Record::Channel(c) => {
            let kind = channels.schemas.get(&c.schema_id).cloned().unwrap_or_default();
            channels.channels.insert(
                c.id,
                Channel {
                    topic: c.topic,
                    kind,
                    encoding: c.message_encoding,
                },
            );
        }
        Record::Message { header, data } => {
            let Some(c) = channels.channels.get(&header.channel_id) else {
                return Err(Error::parse(
                    file,
                    format!(
                        "a message on channel {} before that channel's record (a corrupt or truncated file?)",
                        header.channel_id
                    ),
                ));
            };
            f(file, c, &header, &data)?;
        }
        _ => {}
    }
    Ok(())
}

/// A chunk's records, decompressed (none, zstd or lz4) and checked against its declared size and CRC.
fn decompress(
    file: &Path,
    header: &mcap::records::ChunkHeader,
    data: &[u8],
    limit_bytes: u64,
) -> Result<Vec<u8>> {
    let size = header.uncompressed_size;
    let at = format!(
        "a chunk ({} compression, {size} bytes uncompressed)",
        header.compression
    );
    if size > limit_bytes {
        return Err(Error::parse(
            file,
            format!("{at}: over the memory limit of {limit_bytes} bytes"),
        ));
    }
    // Grown as it decodes: a lying size within the limit allocates no more than the data makes.
    let mut out = Vec::with_capacity((size as usize).min(data.len().saturating_mul(4)));
    let read = match header.compression.as_str() {
        "" => {
            out.extend_from_slice(data);
            Ok(out.len())
        }
        "zstd" => ruzstd::decoding::StreamingDecoder::new(data)
            .map_err(|e| std::io::Error::other(e.to_string()))
            .and_then(|d| d.take(size + 1).read_to_end(&mut out)),
        "lz4" => lz4_flex::frame::FrameDecoder::new(data)
            .take(size + 1)
            .read_to_end(&mut out),
        other => {
            return Err(Error::parse(
                file,
                format!("{at}: unknown compression `{other}` (expected none, zstd or lz4)"),
            ));
        }
    };
    read.map_err(|e| Error::parse(file, format!("{at}: corrupt compressed data: {e}")))?;
    if out.len() as u64 != size {
        return Err(Error::parse(
            file,
            format!(
                "{at}: decompresses to {} bytes, not the {size} it declares",
                out.len()
            ),
        ));
    }
    if header.uncompressed_crc != 0 && crc32fast::hash(&out) != header.uncompressed_crc {
        return Err(Error::parse(
            file,
            format!("{at}: its CRC does not match (corrupt)"),
        ));
    }
    Ok(out)
}

pub(super) fn topic_list(channels: &Channels, counts: &BTreeMap<u16, u64>) -> Vec<(String, String, u64)> {
    let mut topics: BTreeMap<(String, String), u64> = BTreeMap::new();
    for (id, c) in &channels.channels {
        *topics.entry((c.topic.clone(), c.kind.clone())).or_default() += counts.get(id).copied().unwrap_or(0);
    }
    topics.into_iter().map(|((t, k), n)| (t, k, n)).collect()
}

#[cfg(test)]
mod tests {
    use super::relative_file_paths;

    #[test]
    fn the_metadata_lists_its_files_in_either_style() {
        let block = "rosbag2_bagfile_information:\n  relative_file_paths:\n    - run_0.mcap\n    - 'run_1.mcap'\n  \
                     starting_time:\n    nanoseconds_since_epoch: 0\n";
        assert_eq!(relative_file_paths(block), ["run_0.mcap", "run_1.mcap"]);
        let flow = "rosbag2_bagfile_information:\n  relative_file_paths: [a.mcap, \"b.mcap\"]\n";
        assert_eq!(relative_file_paths(flow), ["a.mcap", "b.mcap"]);
        assert!(relative_file_paths("version: 5\n").is_empty());
    }
}
