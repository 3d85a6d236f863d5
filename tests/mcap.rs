//! `run.mcap` read back with the `mcap` crate: channels, schemas, message counts, time
//! order and metadata of a yoga-mat run; `uncoil inspect`; `--no-mcap`; and Ctrl-C, which
//! must still leave a finished file.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use assert_cmd::Command;
use predicates::prelude::*;
use prost_reflect::{DescriptorPool, DynamicMessage, SerializeOptions};
use serde_json::Value;
use uncoil::output::view::ViewObserver;
use uncoil::output::view::channels::STATE_RELATIVE_ERROR;
use uncoil::output::{CSV_COLUMNS, CsvObserver};
use uncoil::run::{RunReport, run};
use uncoil::scene::Scene;

const YOGA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/yoga-mat.toml");

struct Logged {
    dir: PathBuf,
    report: RunReport,
    scene: Scene,
}

/// One yoga-mat run with the CSV and MCAP observers, shared by the tests of this file.
fn logged() -> &'static Logged {
    static RUN: OnceLock<Logged> = OnceLock::new();
    RUN.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("mcap-yoga-mat");
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let scene = Scene::from_file(YOGA).unwrap();
        let mut csv = CsvObserver::new(&dir);
        let mut mcap = ViewObserver::new(&dir);
        let report = run(&scene, &mut [&mut csv, &mut mcap]).unwrap();
        Logged { dir, report, scene }
    })
}

struct Read {
    /// topic -> (schema name, schema encoding, message encoding, schema text)
    channels: BTreeMap<String, (String, String, String, Vec<u8>)>,
    /// topic -> (log time ns, the message as JSON) in file order
    messages: BTreeMap<String, Vec<(u64, Value)>>,
    summary: mcap::read::Summary,
    metadata: BTreeMap<String, BTreeMap<String, String>>,
}

/// A protobuf message decoded with the schema its channel carries, by a generic reader,
/// as JSON with the schema's field names and every field present.
fn decode(schema: &mcap::Schema, data: &[u8]) -> Value {
    assert_eq!(schema.encoding, "protobuf", "{}", schema.name);
    let pool = DescriptorPool::decode(schema.data.as_ref()).expect("a descriptor set");
    let desc = pool
        .get_message_by_name(&schema.name)
        .expect("the named message");
    let message = DynamicMessage::decode(desc, data).expect("a message of its schema");
    let options = SerializeOptions::new()
        .use_proto_field_name(true)
        .skip_default_fields(false)
        .stringify_64_bit_integers(false);
    message
        .serialize_with_options(serde_json::value::Serializer, &options)
        .unwrap()
}

fn read(path: &Path) -> Read {
    let bytes = std::fs::read(path).unwrap();
    let summary = mcap::read::Summary::read(&bytes)
        .unwrap()
        .expect("a finished file has a summary");
    let mut channels = BTreeMap::new();
    let mut messages: BTreeMap<String, Vec<(u64, Value)>> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let schema = m
            .channel
            .schema
            .as_ref()
            .expect("every channel has a schema");
        channels.insert(
            m.channel.topic.clone(),
            (
                schema.name.clone(),
                schema.encoding.clone(),
                m.channel.message_encoding.clone(),
                schema.data.to_vec(),
            ),
        );
        assert_eq!(m.log_time, m.publish_time, "stamped once, with sim time");
        let json = decode(schema, &m.data);
        messages
            .entry(m.channel.topic.clone())
            .or_default()
            .push((m.log_time, json));
    }
    let metadata = summary
        .metadata_indexes
        .iter()
        .map(|i| {
            let m = mcap::read::metadata(&bytes, i).unwrap();
            (m.name, m.metadata)
        })
        .collect();
    Read {
        channels,
        messages,
        summary,
        metadata,
    }
}

fn ns(t_s: f64) -> u64 {
    (t_s * 1e9).round() as u64
}

/// The bang's drawings (log times, ns) against its pace, over its `steps`: the first at its
/// first step, each of its first `BANG_DRAWN_STEPS` steps drawn (at least 200 drawings in
/// all where it took as many steps), at least 10 in its first millisecond, the last at the
/// run's end; after its
/// first `BANG_DRAWN_STEPS` steps, none before it is due: each one either grew the time
/// since the release by the factor `bang_frame_growth` since the drawing before, or is a
/// drawing of the scene rate, or the last.
fn check_bang_pace(bang: &[u64], release: f64, rate: f64, (t_end, steps): (f64, usize)) {
    let since: Vec<f64> = bang.iter().map(|&t| t as f64 * 1e-9 - release).collect();
    let first_ms = since.iter().filter(|&&s| s <= 1e-3).count();
    let drawn = (uncoil::run::BANG_DRAWN_STEPS as usize).min(steps);
    assert!(
        since.len() >= drawn.min(200) && first_ms >= 10,
        "{} drawings of the bang over its {steps} steps, {first_ms} in its first millisecond",
        since.len()
    );
    assert!(since[0] > 0.0 && since[0] < 1e-4, "first at {} s", since[0]);
    assert_eq!(*bang.last().unwrap(), ns(t_end), "the last step is drawn");
    let growth = uncoil::run::bang_frame_growth();
    // Stamps are whole nanoseconds.
    let ns_slack = 2e-9;
    for k in uncoil::run::BANG_DRAWN_STEPS as usize + 1..since.len() - 1 {
        let grew = since[k] + ns_slack >= growth * since[k - 1];
        let tick = |s: f64| ((release + s) * rate + 1e-9).floor();
        assert!(
            grew || tick(since[k]) > tick(since[k - 1]),
            "drawing {k} of the bang at {:.3e} s after the release, {:.3e} s after the one before",
            since[k],
            since[k] - since[k - 1]
        );
    }
}

#[test]
fn yoga_mat_log_reads_back_with_its_channels_counts_order_and_metadata() {
    let logged = logged();
    let path = logged.dir.join("run.mcap");
    assert!(
        !logged.dir.join("run.mcap.partial").exists(),
        "the partial file was renamed"
    );
    let r = read(&path);

    // Channels and schemas.
    let expect = [
        ("/events", "uncoil.Event"),
        ("/scene", "foxglove.SceneUpdate"),
        ("/state", "uncoil.State"),
        ("/tf", "foxglove.FrameTransforms"),
    ];
    assert_eq!(
        r.channels.keys().map(String::as_str).collect::<Vec<_>>(),
        expect.map(|e| e.0)
    );
    for (topic, schema) in expect {
        let (name, schema_enc, msg_enc, _) = &r.channels[topic];
        assert_eq!(name, schema, "{topic}");
        assert_eq!(schema_enc, "protobuf", "{topic}");
        assert_eq!(msg_enc, "protobuf", "{topic}");
    }
    let sdk = <foxglove::messages::SceneUpdate as foxglove::Encode>::get_schema().unwrap();
    assert_eq!(
        r.channels["/scene"].3,
        sdk.data.as_ref(),
        "/scene carries the SDK's schema unchanged"
    );

    // Counts: /state has one message per CSV row; the summary agrees with what was read.
    let csv = std::fs::read_to_string(logged.dir.join("samples.csv")).unwrap();
    let rows = csv.lines().count() - 1;
    assert_eq!(
        r.messages["/state"].len(),
        rows,
        "/state vs samples.csv rows"
    );
    // Foxglove Studio reads no chunk without message indexes (a chunk of schemas and
    // channels alone would be one).
    assert!(!r.summary.chunk_indexes.is_empty());
    for c in &r.summary.chunk_indexes {
        assert!(
            c.message_index_length > 0,
            "chunk at {} has no message index",
            c.chunk_start_offset
        );
    }
    let stats = r.summary.stats.as_ref().unwrap();
    let total: usize = r.messages.values().map(Vec::len).sum();
    assert_eq!(stats.message_count, total as u64);
    let t_end = logged.report.sim_time_s;
    let rate = logged.scene.output.scene_rate_hz;
    let scene_n = r.messages["/scene"].len();
    // Up to the release, one drawing at t = 0 and one per 1 / rate.
    let release = logged.report.ledger.bang_time_s.unwrap();
    let times: Vec<u64> = r.messages["/scene"].iter().map(|(t, _)| *t).collect();
    let before = times.iter().filter(|&&t| t <= ns(release)).count();
    let frames = (release * rate).floor() as usize;
    assert!(
        (frames + 1..=frames + 2).contains(&before),
        "/scene: {before} messages up to the release at {release:.4} s at {rate} Hz, expected {} \
         or {}",
        frames + 1,
        frames + 2
    );
    let steps = logged.report.bang.as_ref().unwrap().solve.steps as usize;
    check_bang_pace(&times[before..], release, rate, (t_end, steps));
    assert_eq!(stats.message_start_time, 0, "the first drawing is at t = 0");
    // One transform of the frame `contact` with each drawing, following the contact line.
    assert_eq!(r.messages["/tf"].len(), scene_n);
    let tf_last = &r.messages["/tf"].last().unwrap().1["transforms"][0];
    assert_eq!(tf_last["child_frame_id"], "contact");
    let x_state = r.messages["/state"].last().unwrap().1["x_m"]
        .as_f64()
        .unwrap();
    let x_tf = tf_last["translation"]["x"].as_f64().unwrap();
    assert!(
        // /tf's translation is a double; /state's x_m keeps fewer bits, by design.
        (x_tf - x_state).abs() <= 1e-6 + STATE_RELATIVE_ERROR * x_tf && x_tf > 1.0,
        "contact frame at {x_tf} m, last sample's x_m {x_state} m"
    );
    assert_eq!(stats.message_end_time, ns(t_end));

    // Time order, and each /state message stamped with its own t_s.
    for (topic, msgs) in &r.messages {
        assert!(
            msgs.windows(2).all(|w| w[0].0 <= w[1].0),
            "{topic} is out of time order"
        );
    }
    // /state fields are the CSV columns as floats; an empty CSV cell is a NaN.
    let mut cells = csv.lines().skip(1);
    for (t, state) in &r.messages["/state"] {
        let t_s = state["t_s"].as_f64().unwrap();
        assert!(
            (*t as f64 * 1e-9 - t_s).abs() <= 1e-7 * t_s.max(1.0),
            "t = {t} ns"
        );
        let row: Vec<&str> = cells.next().unwrap().split(',').collect();
        assert_eq!(state.as_object().unwrap().len(), row.len());
        for (col, cell) in CSV_COLUMNS.iter().zip(&row) {
            let value = &state[*col];
            if cell.is_empty() {
                assert_eq!(
                    value, "NaN",
                    "t = {t} ns: {col} is NaN where its CSV cell is empty"
                );
                continue;
            }
            let want: f64 = cell.parse().unwrap();
            let got = value.as_f64().unwrap_or_else(|| panic!("{col}: {value}"));
            // `t_s` is a float; the other fields keep fewer bits, by design.
            let relative = if *col == "t_s" {
                6e-8
            } else {
                STATE_RELATIVE_ERROR
            };
            assert!(
                (got - want).abs() <= relative * want.abs() + f64::from(f32::MIN_POSITIVE),
                "t = {t} ns: {col} = {got} in /state, {want} in the CSV"
            );
        }
    }

    // Events: every link that left the rolling coil, one bang start, one bang end whose
    // dissipated energy is the ledger's.
    let events: Vec<&Value> = r.messages["/events"].iter().map(|(_, v)| v).collect();
    let kind = |k: &str| events.iter().filter(|e| e["kind"] == k).count();
    let detached: u64 = events
        .iter()
        .filter(|e| e["kind"] == "Detach")
        .map(|e| e["links"].as_u64().unwrap())
        .sum();
    let last_detached = events
        .iter()
        .rev()
        .find(|e| e["kind"] == "Detach")
        .map(|e| e["detached"].as_u64().unwrap())
        .unwrap();
    assert_eq!(
        detached, last_detached,
        "detach events cover every link shed"
    );
    assert!(detached > 100 && detached < logged.report.links as u64);
    assert_eq!(kind("BangStart"), 1);
    assert_eq!(kind("BangEnd"), 1);
    let end = events.iter().find(|e| e["kind"] == "BangEnd").unwrap();
    assert_eq!(end["ended_by"], "Rest", "the yoga mat's bang comes to rest");
    let dissipated = end["dissipated_j"].as_f64().unwrap();
    let ledger = logged.report.ledger.dissipated_by_bang_j;
    assert!(
        (dissipated - ledger).abs() <= 1e-12 * ledger.abs(),
        "bang event {dissipated} J, ledger {ledger} J"
    );

    // Drawings: the whole tape wound at t = 0, the whole tape off the coil at the end.
    let entity = |msg: &Value, id: &str| -> Option<Value> {
        msg["entities"]
            .as_array()
            .unwrap()
            .iter()
            .find(|e| e["id"] == id)
            .cloned()
    };
    let points = |e: &Value| e["lines"][0]["points"].as_array().unwrap().len();
    let nodes = logged.report.links + 1;
    let first = &r.messages["/scene"][0].1;
    let last = &r.messages["/scene"].last().unwrap().1;
    // Lines are thinned for drawing: the wound spiral through chords within b/4 of its
    // nodes, which keeps one node in two or three of the yoga mat's 32 per turn; the laid
    // tape, flat on the floor, within b/20, which keeps far fewer, but it still spans the
    // whole tape.
    let on0 = points(&entity(first, "tape/on_coil").unwrap());
    assert!(
        on0 > nodes / 4 && on0 < nodes / 2,
        "{on0} of {nodes} wound nodes drawn"
    );
    assert_eq!(points(&entity(first, "tape/off_coil").unwrap()), 0);
    assert_eq!(points(&entity(last, "tape/on_coil").unwrap()), 0);
    let off = entity(last, "tape/off_coil").unwrap();
    let off_n = points(&off);
    assert!(
        off_n >= 2 && off_n < nodes,
        "{off_n} of {nodes} laid nodes drawn"
    );
    let xs: Vec<f64> = off["lines"][0]["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["x"].as_f64().unwrap())
        .collect();
    let span =
        xs.iter().copied().fold(f64::MIN, f64::max) - xs.iter().copied().fold(f64::MAX, f64::min);
    assert!(span > 2.0, "laid tape drawn over {span} m");
    for id in ["floor", "ghost/eq7", "ghost/exact"] {
        assert!(entity(first, id).is_some(), "{id} drawn at t = 0");
    }
    // The exact-geometry model is tabulated down to half the bang radius (t = 2.27 s),
    // before the bang settles on the exact chain (2.38 s): its ghost is deleted. Eq. (7)'s
    // coil runs out later (t = 2.44 s), so its ghost is still drawn at the end.
    let deleted: Vec<&str> = last["deletions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["id"].as_str().unwrap())
        .collect();
    assert!(
        entity(last, "ghost/exact").is_none(),
        "ghost/exact still drawn at the end"
    );
    assert!(
        deleted.contains(&"ghost/exact"),
        "ghost/exact not deleted: {deleted:?}"
    );
    assert!(
        entity(last, "ghost/eq7").is_some() && !deleted.contains(&"ghost/eq7"),
        "ghost/eq7 gone at t = {} s, before eq. (7)'s coil runs out (2.44 s)",
        logged.report.sim_time_s
    );
    // At t = 0 both ghosts touch the floor where the tape does. The exact coil is drawn in
    // its body frame, from the inner end out to the contact point, and placed by its pose.
    let exact_line = &entity(first, "ghost/exact").unwrap()["lines"][0];
    let contact = in_world(
        exact_line,
        exact_line["points"].as_array().unwrap().last().unwrap(),
    );
    let b = logged.scene.tape.thickness_m;
    let big_r = logged.scene.tape.outer_radius_m;
    assert!(contact[0].abs() < 1e-6, "{contact:?}");
    assert!((contact[1] - 0.5 * b).abs() < 1e-6, "{contact:?}");
    // The wound coil repeats its body-frame points from drawing to drawing while it rolls:
    // a drawing keeps the one before's points from the inner end out, all but the last
    // few, where the tape left the coil. Only the pose moves.
    let scenes = &r.messages["/scene"];
    for k in [1, 50, 100] {
        let line = |m: &Value| entity(m, "tape/on_coil").unwrap()["lines"][0].clone();
        let (before, after) = (line(&scenes[k].1), line(&scenes[k + 1].1));
        let (pb, pa) = (
            before["points"].as_array().unwrap(),
            after["points"].as_array().unwrap(),
        );
        let same = pb.iter().zip(pa).take_while(|(x, y)| x == y).count();
        assert!(
            pa.len() <= pb.len() && same + 3 >= pa.len() && pa.len() > 10,
            "drawing {k}: {same} of {} points repeated, {} before",
            pa.len(),
            pb.len()
        );
        assert_ne!(before["pose"], after["pose"], "drawing {k}: the coil moved");
        // The outermost wound node, placed, is where the tape meets the floor: within a
        // link's length of it.
        let outer = in_world(&after, pa.last().unwrap());
        let link = 2.0 * std::f64::consts::PI * big_r / 32.0;
        assert!(outer[1] > 0.0 && outer[1] < link, "drawing {k}: {outer:?}");
    }
    // Eq. (7)'s coil is a disc of radius R standing on y = 0, its spoke pointing down.
    let eq7 = entity(first, "ghost/eq7").unwrap();
    let spoke = &eq7["lines"][0]["points"];
    assert!(
        spoke[1]["x"].as_f64().unwrap().abs() < 1e-6,
        "spoke points down"
    );
    assert!(
        spoke[1]["y"].as_f64().unwrap().abs() < 1e-6,
        "spoke ends on y = 0"
    );
    assert!((spoke[0]["y"].as_f64().unwrap() - big_r).abs() < 1e-6);
    let disc = &eq7["cylinders"][0];
    assert!((disc["pose"]["position"]["y"].as_f64().unwrap() - big_r).abs() < 1e-6);
    assert!((disc["size"]["x"].as_f64().unwrap() - 2.0 * big_r).abs() < 1e-6);
    assert!((disc["size"]["y"].as_f64().unwrap() - 2.0 * big_r).abs() < 1e-6);
    for e in first["entities"].as_array().unwrap() {
        assert_eq!(e["frame_id"], "world");
    }

    // Metadata.
    let md = &r.metadata;
    assert_eq!(
        md.keys().map(String::as_str).collect::<Vec<_>>(),
        ["ledger", "resolution", "run", "scene", "solver", "tool"]
    );
    assert_eq!(md["scene"]["text"], std::fs::read_to_string(YOGA).unwrap());
    assert_eq!(md["scene"]["name"], "yoga-mat");
    assert_eq!(md["tool"]["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(md["resolution"]["links_per_turn"], "32");
    assert_eq!(md["solver"]["iterations"], "4");
    assert_eq!(md["run"]["stop_reason"], logged.report.stop.to_string());
    let e0: f64 = md["ledger"]["e0_j"].parse().unwrap();
    assert!((e0 - logged.report.ledger.e0_j).abs() <= 1e-12 * e0);
}

#[test]
fn inspect_prints_channels_counts_time_range_metadata_and_ledger() {
    let path = logged().dir.join("run.mcap");
    Command::cargo_bin("uncoil")
        .unwrap()
        .arg("inspect")
        .arg(&path)
        .assert()
        .success()
        .stdout(predicate::str::contains("finished: yes"))
        .stdout(predicate::str::contains("/scene"))
        .stdout(predicate::str::contains("foxglove.SceneUpdate"))
        .stdout(predicate::str::contains("/state"))
        .stdout(predicate::str::contains("/events"))
        .stdout(predicate::str::contains("time range: 0.000000 s"))
        .stdout(predicate::str::contains("Metadata \"ledger\":"))
        .stdout(predicate::str::contains("dissipated_by_bang_j = "))
        .stdout(predicate::str::contains(
            "time order: every channel in order",
        ));
}

#[test]
fn inspect_counts_the_bang_s_drawings_and_where_the_tape_crosses_itself() {
    let logged = logged();
    let path = logged.dir.join("run.mcap");
    let bytes = std::fs::read(&path).unwrap();
    let release = logged.report.ledger.bang_time_s.unwrap();
    // Every drawing after the release, as a plain reader of the file counts them.
    let mut after = 0;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        after += usize::from(m.channel.topic == "/scene" && m.log_time > ns(release));
    }
    let inv = uncoil::output::inspect::inventory(&bytes).unwrap();
    let bang = uncoil::output::inspect::bang::bang_drawings(&bytes, &inv)
        .unwrap()
        .expect("the yoga mat has a bang");
    assert_eq!(bang.drawn, after);
    assert!(bang.crossing <= bang.drawn && (bang.crossing > 0) == (bang.most.0 > 0));
    assert_eq!(bang.thickness_m, logged.scene.tape.thickness_m);
    Command::cargo_bin("uncoil")
        .unwrap()
        .arg("inspect")
        .arg(&path)
        .assert()
        .success()
        .stdout(predicate::str::contains(format!(
            "The final bang's drawings (/scene after the release at t = {release:.6} s):\n  \
             drawn: {after} ("
        )))
        .stdout(predicate::str::contains(format!(
            "the tape's drawn midline crosses itself in {} of them, at most {} times in one",
            bang.crossing, bang.most.0
        )))
        .stdout(predicate::str::contains("closest approach"));
}

#[test]
fn the_yoga_mat_s_bang_is_drawn_with_its_layers_apart() {
    // The tape has a thickness in the bang: its drawn midline never crosses itself, and two
    // of its segments at least pi b apart along it never come closer than the overlap
    // guard's bound lets them, b / 2.
    let bytes = std::fs::read(logged().dir.join("run.mcap")).unwrap();
    let inv = uncoil::output::inspect::inventory(&bytes).unwrap();
    let bang = uncoil::output::inspect::bang::bang_drawings(&bytes, &inv)
        .unwrap()
        .expect("the yoga mat has a bang");
    assert_eq!(bang.crossing, 0, "{bang:?}");
    let (closest, _) = bang.closest.expect("its turns come within b of each other");
    assert!(closest >= 0.5 * bang.thickness_m, "{bang:?}");
}

#[test]
fn the_drawn_tape_reads_back_from_its_outer_end() {
    use uncoil::output::view::drawings::tape_drawings;
    let logged = logged();
    let bytes = std::fs::read(logged.dir.join("run.mcap")).unwrap();
    let (drawings, cut) = tape_drawings(&bytes, None).unwrap();
    assert!(cut.is_none());
    let b = logged.scene.tape.thickness_m;
    // At t = 0 the whole tape is wound: its outer end touches the floor at the origin, its
    // midline half a thickness up.
    let first = &drawings[0];
    assert_eq!(first.t_s, 0.0);
    assert_eq!(first.thickness_m, b);
    let outer = first.midline_m[0];
    assert!(
        outer[0].abs() < 1e-6 && (outer[1] - 0.5 * b).abs() < 0.05 * b,
        "{outer:?}"
    );
    // At the end the whole tape is laid, from its outer end near the origin to its inner
    // end where the bang left it.
    let last = drawings.last().unwrap();
    assert!((last.t_s - logged.report.sim_time_s).abs() < 1e-9);
    let start = last.midline_m[0];
    assert!(
        start[0].abs() < b && (start[1] - 0.5 * b).abs() < 0.05 * b,
        "{start:?}"
    );
    let end = last.midline_m.last().unwrap();
    let x_end = logged.report.bang.as_ref().unwrap().end_x_m;
    assert!((end[0] - x_end).abs() < 1e-5, "{end:?} against {x_end}");
}

#[test]
fn inspect_reads_a_cut_off_file_as_far_as_its_data_goes() {
    // A file cut in half, as a crash leaves it: no summary, but the chunks before the cut.
    let bytes = std::fs::read(logged().dir.join("run.mcap")).unwrap();
    let whole = uncoil::output::inspect::inventory(&bytes).unwrap();
    let half = uncoil::output::inspect::inventory(&bytes[..bytes.len() / 2]).unwrap();
    assert!(whole.finished && !half.finished);
    // Each channel's uncompressed bytes, as a plain reader of the file counts them.
    let mut state_bytes = 0;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        if m.channel.topic == "/state" {
            state_bytes += m.data.len() as u64;
        }
    }
    assert!(state_bytes > 0);
    assert_eq!(whole.channels["/state"].message_bytes, state_bytes);
    assert!(half.read_error.is_some());
    let count = |inv: &uncoil::output::inspect::Inventory| -> u64 {
        inv.channels.values().map(|c| c.messages).sum()
    };
    assert!(
        count(&half) > count(&whole) / 4 && count(&half) < count(&whole),
        "{} of {} messages read from half the file",
        count(&half),
        count(&whole)
    );
    assert!(half.time_ordered);
    assert!(
        half.metadata.contains_key("scene"),
        "metadata before the cut"
    );
    assert!(
        !half.metadata.contains_key("ledger"),
        "the ledger comes last"
    );
}

#[test]
fn inspect_of_a_file_that_is_not_mcap_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.mcap");
    std::fs::write(&path, "not an MCAP file").unwrap();
    Command::cargo_bin("uncoil")
        .unwrap()
        .arg("inspect")
        .arg(&path)
        .assert()
        .code(2)
        .stderr(predicate::str::ends_with(
            "x.mcap: a file that is not MCAP (no MCAP magic bytes); expected an MCAP log, e.g. \
             runs/yoga-mat/run.mcap\n",
        ));
}

/// A small scene that runs for a long time: a tiny step over a long push.
const SLOW: &str = r#"name = "slow"
[tape]
outer_radius_m = 0.06
thickness_m = 0.005
mass_kg = 1.5
[push]
contact_speed_m_s = 0.3
[solver]
max_dt_s = 0.00001
"#;

#[test]
fn no_mcap_flag_writes_no_log() {
    let dir = tempfile::tempdir().unwrap();
    let scene = small_scene(dir.path());
    let out = dir.path().join("out");
    Command::cargo_bin("uncoil")
        .unwrap()
        .args(["run", "--no-mcap", "--out"])
        .arg(&out)
        .arg(&scene)
        .assert()
        .success();
    assert!(out.join("samples.csv").exists());
    assert!(!out.join("run.mcap").exists());
    assert!(!out.join("run.mcap.partial").exists());
}

/// Sends `signal` (`kill -SIGNAL`) to a running run: it stops, finishes its files, names the
/// signal in its report and log, and exits with `128 +` the signal's number.
fn a_signal_stops_the_run_and_leaves_a_finished_log(signal: &str, code: i32) {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("slow.toml");
    std::fs::write(&scene, SLOW).unwrap();
    let out = dir.path().join("out");
    let bin = assert_cmd::cargo::cargo_bin("uncoil");
    let child = std::process::Command::new(bin)
        .arg("run")
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // The handler is installed before the run opens its files.
    let partial = out.join("run.mcap.partial");
    let start = Instant::now();
    while !partial.exists() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the run never started"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(300));
    let killed = std::process::Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(code), "stderr: {stderr}");
    let named = format!("interrupted by SIG{signal}");
    assert!(stderr.contains(&named), "stderr: {stderr}");
    assert!(!partial.exists(), "the partial file was renamed");
    let r = read(&out.join("run.mcap"));
    assert_eq!(r.metadata["run"]["stop_reason"], named);
    assert!(r.metadata.contains_key("ledger"));
    let last_event = &r.messages["/events"].last().unwrap().1;
    assert_eq!(last_event["kind"], "Warning");
    assert!(!r.messages["/state"].is_empty());
    // The run stopped long before its natural end (about 2.3 s simulated).
    let t_end = r.summary.stats.as_ref().unwrap().message_end_time;
    assert!(t_end < ns(2.0), "stopped at {t_end} ns");
    let report: Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["stop"]["reason"], "interrupted");
    assert_eq!(report["stop"]["signal"], format!("SIG{signal}"));
    for file in std::fs::read_dir(&out).unwrap() {
        let name = file.unwrap().file_name();
        assert!(
            !name.to_string_lossy().ends_with(".partial"),
            "{name:?} left behind"
        );
    }
}

#[test]
fn ctrl_c_stops_the_run_and_leaves_a_finished_log() {
    a_signal_stops_the_run_and_leaves_a_finished_log("INT", 130);
}

#[test]
fn sigterm_stops_the_run_as_ctrl_c_does_and_exits_143() {
    // What Slurm sends at a time limit, on scancel and on preemption.
    a_signal_stops_the_run_and_leaves_a_finished_log("TERM", 143);
}

#[test]
fn sighup_stops_the_run_as_ctrl_c_does_and_exits_129() {
    a_signal_stops_the_run_and_leaves_a_finished_log("HUP", 129);
}

#[test]
fn a_live_run_without_a_viewer_does_not_wait_and_pace_needs_live() {
    let dir = tempfile::tempdir().unwrap();
    let scene = small_scene(dir.path());
    let out = dir.path().join("out");
    // Port 0: any free port. Nobody connects; the run goes on and finishes its files.
    Command::cargo_bin("uncoil")
        .unwrap()
        .args(["run", "--live", "127.0.0.1:0", "--out"])
        .arg(&out)
        .arg(&scene)
        .timeout(Duration::from_secs(120))
        .assert()
        .success()
        .stderr(predicate::str::contains(
            "serving the run live at ws://127.0.0.1:",
        ));
    assert!(out.join("samples.csv").exists());
    assert!(out.join("run.mcap").exists());
    Command::cargo_bin("uncoil")
        .unwrap()
        .args(["run", "--pace", "0.1"])
        .arg(&scene)
        .assert()
        .code(2);
    Command::cargo_bin("uncoil")
        .unwrap()
        .args(["run", "--live", "127.0.0.1:0", "--pace=0"])
        .arg(&scene)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("a pace is a positive number"));
}

/// A point of a line primitive placed in the world by the line's pose (a rotation about z).
fn in_world(line: &Value, p: &Value) -> [f64; 2] {
    let num = |v: &Value| v.as_f64().unwrap_or(0.0);
    let (o, q) = (&line["pose"]["position"], &line["pose"]["orientation"]);
    let angle = 2.0 * num(&q["z"]).atan2(num(&q["w"]));
    let (sin, cos) = angle.sin_cos();
    let (x, y) = (num(&p["x"]), num(&p["y"]));
    [
        num(&o["x"]) + cos * x - sin * y,
        num(&o["y"]) + sin * x + cos * y,
    ]
}

/// A small scene file in `dir`: a few turns, quick to run.
fn small_scene(dir: &Path) -> PathBuf {
    let scene = dir.join("small.toml");
    std::fs::write(
        &scene,
        "[tape]\nouter_radius_m = 0.02\nthickness_m = 0.004\nmass_kg = 0.2\n\
         [push]\ncontact_speed_m_s = 0.3\n",
    )
    .unwrap();
    scene
}
