//! `oeg run --mcap`: the recording reads back with the `mcap` crate, every message validates against the
//! JSON schema stored with its channel, the topics and frames are the documented ones (`docs/mcap.md`), and
//! the file is the same bytes on one and two threads.
#![allow(clippy::disallowed_methods, reason = "tests read back the files they wrote")]

mod common;

use std::collections::{BTreeMap, BTreeSet};

use common::{oeg_with_threads, root, s, temp_dir};
use serde_json::Value;

/// Checks `value` against the subset of JSON Schema the recording's schemas use: `type`, `properties`,
/// `required`, `items`, `minimum`, `maximum` and `contentEncoding: base64`. Returns the first problem.
fn validate(value: &Value, schema: &Value, at: &str) -> Result<(), String> {
    let want = schema["type"].as_str();
    let ok = match want {
        Some("object") => value.is_object(),
        Some("array") => value.is_array(),
        Some("string") => value.is_string(),
        Some("integer") => value.is_u64() || value.is_i64(),
        Some("number") => value.is_number(),
        Some(other) => return Err(format!("{at}: unknown type {other} in the schema")),
        None => true,
    };
    if !ok {
        return Err(format!("{at}: {value} is not of type {want:?}"));
    }
    if let Some(min) = schema["minimum"].as_f64()
        && value.as_f64().is_some_and(|v| v < min)
    {
        return Err(format!("{at}: {value} < {min}"));
    }
    if let Some(max) = schema["maximum"].as_f64()
        && value.as_f64().is_some_and(|v| v > max)
    {
        return Err(format!("{at}: {value} > {max}"));
    }
    if schema["contentEncoding"] == "base64" {
        let text = value.as_str().unwrap_or_default();
        let valid = text.len().is_multiple_of(4)
            && text
                .bytes()
                .all(|b| b.is_ascii_alphanumeric() || b == b'+' || b == b'/' || b == b'=');
        if !valid {
            return Err(format!("{at}: not base64"));
        }
    }
    if let Some(required) = schema["required"].as_array() {
        for r in required {
            let key = r.as_str().unwrap_or_default();
            if value.get(key).is_none() {
                return Err(format!("{at}: {key} is missing"));
            }
        }
    }
    if let (Some(props), Some(object)) = (schema["properties"].as_object(), value.as_object()) {
        for (key, v) in object {
            let Some(sub) = props.get(key) else {
                return Err(format!("{at}: {key} is not in the schema"));
            };
            validate(v, sub, &format!("{at}.{key}"))?;
        }
    }
    if let (Some(items), Some(array)) = (schema.get("items"), value.as_array()) {
        for (k, v) in array.iter().enumerate() {
            validate(v, items, &format!("{at}[{k}]"))?;
        }
    }
    Ok(())
}

fn decoded_len(base64: &str) -> usize {
    base64.len() / 4 * 3 - base64.bytes().rev().take_while(|b| *b == b'=').count()
}

/// A message read back from a recording, checked against its channel's schema.
struct Message {
    topic: String,
    schema_title: String,
    value: Value,
    log_time: u64,
}

/// Every message of an MCAP file, each checked: its channel has a JSON schema, the message is JSON, and it
/// validates against the schema.
fn validated_messages(bytes: &[u8]) -> Vec<Message> {
    mcap::MessageStream::new(bytes)
        .expect("an MCAP file")
        .map(|message| {
            let message = message.expect("a message");
            let channel = &message.channel;
            let schema = channel.schema.as_ref().expect("every channel has a schema");
            assert_eq!(schema.encoding, "jsonschema");
            assert_eq!(channel.message_encoding, "json");
            let schema: Value = serde_json::from_slice(&schema.data).expect("the schema is JSON");
            let value: Value = serde_json::from_slice(&message.data).expect("the message is JSON");
            validate(&value, &schema, &channel.topic).unwrap_or_else(|e| panic!("{e}"));
            Message {
                topic: channel.topic.clone(),
                schema_title: schema["title"].as_str().unwrap_or_default().to_string(),
                value,
                log_time: message.log_time,
            }
        })
        .collect()
}

#[test]
fn oeg_record_writes_the_poses_scans_and_truth_as_mcap_the_same_bytes_on_any_thread_count() {
    let dir = temp_dir("recording", "record");
    let scene = root().join("tests/scenes/person_standing.toml");
    let mut bytes = Vec::new();
    for threads in ["2", "1"] {
        let out = dir.join(format!("threads{threads}.mcap"));
        let o = oeg_with_threads(
            &["record", s(&scene), "--format", "mcap", "--out", s(&out)],
            Some(threads),
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        bytes.push(std::fs::read(&out).expect("the recording"));
    }
    assert!(bytes[0] == bytes[1], "1 and 2 threads give different recordings");
    let mut per_topic: BTreeMap<String, usize> = BTreeMap::new();
    for m in validated_messages(&bytes[0]) {
        *per_topic.entry(m.topic).or_default() += 1;
    }
    assert_eq!(per_topic.get("/truth/elevation"), Some(&1), "{per_topic:?}");
    assert_eq!(per_topic.get("/truth/truly_blocked"), Some(&1));
    // Three sensors, each at its rate over 6 s; the poses once a tick.
    let scans: Vec<&String> = per_topic.keys().filter(|t| t.starts_with("/scans/")).collect();
    assert_eq!(scans.len(), 3, "{per_topic:?}");
    assert!(scans.iter().all(|t| per_topic[*t] >= 6), "{per_topic:?}");
    assert!(per_topic["/tf"] >= 2 * 6, "{per_topic:?}");
    // A recording of the sensors: no map, no plans, no events.
    assert!(
        per_topic
            .keys()
            .all(|t| !t.starts_with("/map") && t != "/plan" && t != "/events"),
        "{per_topic:?}"
    );
}

#[test]
fn the_recording_reads_back_validates_against_its_schemas_and_is_the_same_bytes_on_any_thread_count() {
    let dir = temp_dir("recording", "nav_blind");
    let scene = root().join("tests/scenes/nav_blind.toml");
    let mut bytes = Vec::new();
    for threads in ["2", "1"] {
        let out = dir.join(format!("threads{threads}"));
        // Planning at every replanning time, so that the recording holds many paths.
        let periodic = ["--set", "navigation.replan=periodic"];
        let args = [
            "run",
            s(&scene),
            "--mcap",
            "--out",
            s(&out),
            periodic[0],
            periodic[1],
        ];
        let o = oeg_with_threads(&args, Some(threads));
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        bytes.push(std::fs::read(out.join("recording.mcap")).expect("recording.mcap"));
        assert!(
            std::fs::read_to_string(out.join("report.html"))
                .expect("page")
                .contains("href=\"recording.mcap\""),
            "the run's page links the recording"
        );
    }
    assert!(bytes[0] == bytes[1], "1 and 2 threads give different recordings");

    let mut per_topic: BTreeMap<String, usize> = BTreeMap::new();
    let mut frames = BTreeSet::new();
    let mut levels = BTreeSet::new();
    let mut last_time = 0;
    for m in validated_messages(&bytes[0]) {
        let (value, topic) = (&m.value, &m.topic);
        *per_topic.entry(topic.clone()).or_default() += 1;
        last_time = last_time.max(m.log_time);
        match m.schema_title.as_str() {
            "foxglove.Grid" => {
                let (stride, columns) = (value["row_stride"].as_u64(), value["column_count"].as_u64());
                let cell = value["cell_stride"].as_u64().expect("cell stride");
                assert_eq!(stride, columns.map(|c| c * cell));
                let n = decoded_len(value["data"].as_str().expect("data")) as u64;
                assert!(
                    n > 0 && n.is_multiple_of(stride.expect("stride")),
                    "{topic}: {n} bytes"
                );
                assert_eq!(value["frame_id"], "world");
            }
            "foxglove.PointCloud" => {
                assert_eq!(decoded_len(value["data"].as_str().expect("data")) % 12, 0);
            }
            "foxglove.FrameTransform" => {
                assert_eq!(value["parent_frame_id"], "world");
                frames.insert(value["child_frame_id"].as_str().expect("frame").to_string());
            }
            "foxglove.Log" => {
                levels.insert((
                    value["level"].as_u64(),
                    value["message"]
                        .as_str()
                        .map(|m| m.split(' ').next().map(str::to_string)),
                ));
            }
            _ => {}
        }
    }
    for topic in [
        "/tf",
        "/scans/laser_left",
        "/scans/laser_right",
        "/map/elevation",
        "/map/occupancy_probability",
        "/map/variance",
        "/map/decisions",
        "/truth/elevation",
        "/truth/truly_blocked",
        "/plan",
        "/events",
    ] {
        assert!(per_topic.contains_key(topic), "{topic} missing: {per_topic:?}");
    }
    assert_eq!(per_topic["/truth/elevation"], 1);
    // The layers once a simulated second and at the end; every replanning time's path.
    assert!(per_topic["/map/decisions"] >= 10, "{per_topic:?}");
    assert!(per_topic["/plan"] >= 5, "{per_topic:?}");
    assert_eq!(
        frames,
        BTreeSet::from(["base_link".to_string(), "base_link_estimated".to_string()])
    );
    // The contact with the curb is an error-level log message.
    assert!(
        levels.contains(&(Some(4), Some(Some("contact".to_string())))),
        "{levels:?}"
    );
    assert!(last_time > 10_000_000_000, "the run lasts beyond 10 s");
}

#[test]
fn a_recorded_run_maps_as_an_unrecorded_one_under_robust() {
    // The recording maps scan by scan, the run in batches; the robust map also takes the robot's stance (the
    // ground under it, footprint clearing) at the batches' ends, and the recorded run at the same scans.
    let dir = temp_dir("recording", "same_map");
    let scene = root().join("tests/scenes/nav_blind.toml");
    let mut maps = Vec::new();
    for mcap in [true, false] {
        let out = dir.join(if mcap { "recorded" } else { "plain" });
        let mut args = vec!["run", s(&scene), "--set", "map.preset=robust", "--out", s(&out)];
        if mcap {
            args.push("--mcap");
        }
        let o = oeg_with_threads(&args, Some("2"));
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        maps.push(std::fs::read(out.join("map.oeg")).expect("map.oeg"));
    }
    assert!(maps[0] == maps[1], "the recorded run's map differs");
}
