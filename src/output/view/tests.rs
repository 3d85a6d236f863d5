use std::fs;

use prost::Message as _;
use prost_reflect::{DescriptorPool, DynamicMessage, Kind, Value};

use super::channels::{EventMessage, STATE_RELATIVE_ERROR, State, schema_named};
use super::paint::{Kept, MAX_LINE_POINTS, drawn, drawn_wound};
use super::*;
use crate::model::BangEnd;

fn scene() -> Scene {
    Scene::from_toml_str(
        "[tape]\nouter_radius_m = 0.02\nthickness_m = 0.004\nmass_kg = 0.2\n\
         [push]\ncontact_speed_m_s = 0.3\n[discretisation]\nlinks_per_turn = 8\n",
        "small",
    )
    .expect("valid scene")
}

/// The message a schema names, read from its descriptor set by a generic reader.
fn descriptor(schema: &foxglove::Schema) -> prost_reflect::MessageDescriptor {
    assert_eq!(schema.encoding, "protobuf");
    let pool = DescriptorPool::decode(schema.data.as_ref()).expect("a valid descriptor set");
    pool.get_message_by_name(&schema.name)
        .unwrap_or_else(|| panic!("{} is not in its own descriptor set", schema.name))
}

fn state_descriptor() -> prost_reflect::MessageDescriptor {
    descriptor(&<State as foxglove::Encode>::get_schema().unwrap())
}

#[test]
fn the_state_schema_is_the_sample_field_by_field() {
    // `uncoil.State`'s fields are the CSV columns, in order, numbered from 1, all floats.
    let state = state_descriptor();
    assert_eq!(state.full_name(), "uncoil.State");
    let names: Vec<String> = state.fields().map(|f| f.name().to_owned()).collect();
    assert_eq!(names, *crate::output::CSV_COLUMNS);
    for (k, f) in state.fields().enumerate() {
        assert_eq!(f.number() as usize, k + 1, "{}", f.name());
        assert_eq!(f.kind(), Kind::Float, "{}", f.name());
    }
}

#[test]
fn a_sample_decodes_to_its_values_nan_included() {
    let sample = Sample {
        t_s: 1.25,
        r_m: 0.0123,
        r_ref_m: f64::NAN,
        ..Sample::default()
    };
    let mut bytes = Vec::new();
    foxglove::Encode::encode(&State(sample), &mut bytes).unwrap();
    let m = DynamicMessage::decode(state_descriptor(), bytes.as_slice()).unwrap();
    assert_eq!(m.get_field_by_name("t_s").unwrap().as_f32(), Some(1.25));
    // Every field but `t_s` keeps STATE_MANTISSA_BITS: 0.0123 within its stated error.
    let r = f64::from(m.get_field_by_name("r_m").unwrap().as_f32().unwrap());
    assert!((r - 0.0123).abs() <= STATE_RELATIVE_ERROR * 0.0123, "{r}");
    assert!(
        m.get_field_by_name("r_ref_m")
            .unwrap()
            .as_f32()
            .unwrap()
            .is_nan()
    );
    // A zero is not written; it reads back as zero.
    assert!(!m.has_field_by_name("x_m"));
    assert_eq!(m.get_field_by_name("x_m").unwrap().as_f32(), Some(0.0));
}

#[test]
fn an_event_decodes_with_its_kind_and_only_its_fields() {
    let event = Event::BangEnd {
        t_s: 2.5,
        started_s: 2.25,
        dissipated_j: 0.9,
        ended_by: BangEnd::Rest,
    };
    let mut bytes = Vec::new();
    foxglove::Encode::encode(&EventMessage::from(&event), &mut bytes).unwrap();
    let desc = descriptor(&schema_named::<EventMessage>("uncoil", "Event"));
    assert_eq!(desc.full_name(), "uncoil.Event");
    let m = DynamicMessage::decode(desc.clone(), bytes.as_slice()).unwrap();
    let kind = m.get_field_by_name("kind").unwrap();
    let Value::EnumNumber(k) = kind.as_ref() else {
        panic!("kind is {kind:?}")
    };
    let kinds = desc.get_field_by_name("kind").unwrap().kind();
    let name = kinds.as_enum().unwrap().get_value(*k).unwrap();
    assert_eq!(name.name(), "BangEnd");
    assert_eq!(
        m.get_field_by_name("started_s").unwrap().as_f64(),
        Some(2.25)
    );
    // The other kinds' fields are absent, not zero.
    assert!(!m.has_field_by_name("kinetic_j"));
    assert!(!m.has_field_by_name("links"));
}

#[test]
fn the_scene_and_tf_channels_carry_the_sdk_schemas() {
    let context = foxglove::Context::new();
    let channels = channels::Channels::new(&context);
    let scene = channels.scene.schema().unwrap();
    assert_eq!(scene.name, "foxglove.SceneUpdate");
    assert_eq!(descriptor(scene).full_name(), "foxglove.SceneUpdate");
    assert_eq!(
        channels.tf.schema().unwrap().name,
        "foxglove.FrameTransforms"
    );
    assert_eq!(channels.state.schema().unwrap().name, "uncoil.State");
    assert_eq!(channels.events.schema().unwrap().name, "uncoil.Event");
}

#[test]
fn painted_entities_carry_time_frame_and_lines() {
    let mut painter = Painter::new(&scene());
    let frame = Frame {
        t_s: 1.5,
        contact_x_m: 0.01,
        off_coil_m: vec![[0.0, 0.002], [0.01, 0.002]],
        on_coil: crate::spiral::Placed::default(),
        eq7: None,
        exact: None,
    };
    let msg = painter.paint(&frame);
    let ids: Vec<&str> = msg.entities.iter().map(|e| e.id.as_str()).collect();
    assert_eq!(ids, ["floor", "tape/off_coil", "tape/on_coil"]);
    for e in &msg.entities {
        let t = e.timestamp.unwrap();
        assert_eq!((t.sec(), t.nsec()), (1, 500_000_000));
        assert_eq!(e.frame_id, "world");
    }
    assert_eq!(msg.entities[1].lines[0].points.len(), 2);
    // Both ghosts are absent: both are deleted.
    let deleted: Vec<&str> = msg.deletions.iter().map(|d| d.id.as_str()).collect();
    assert_eq!(deleted, ["ghost/eq7", "ghost/exact"]);
}

#[test]
fn drawing_drops_straight_runs_keeps_bends_and_caps_the_points() {
    // A flat run, a step up, a flat run: 2 + 2 corners survive, nothing else.
    let mut nodes: Vec<[f64; 2]> = (0..100).map(|k| [f64::from(k) * 1e-3, 0.0]).collect();
    nodes.extend((100..200).map(|k| [f64::from(k) * 1e-3, 0.01]));
    let d = drawn(&nodes, 1e-4);
    let xy: Vec<(f64, f64)> = d.iter().map(|p| (p.x, p.y)).collect();
    assert_eq!(
        xy,
        [(0.0, 0.0), (0.099, 0.0), (0.1, 0.01), (0.199, 0.01)],
        "kept {xy:?}"
    );
    // A circle keeps every node it needs, up to the cap, and both ends.
    let circle: Vec<[f64; 2]> = (0..=10_000)
        .map(|k| {
            let a = f64::from(k) * 2.0 * std::f64::consts::PI / 10_000.0;
            [a.cos(), a.sin()]
        })
        .collect();
    let d = drawn(&circle, 0.0);
    assert!(d.len() <= MAX_LINE_POINTS + 1, "{} points", d.len());
    assert!(d.len() > MAX_LINE_POINTS / 2, "{} points", d.len());
    assert!((d.last().unwrap().x - 1.0).abs() < 1e-9, "the end is kept");
}

#[test]
fn a_crash_leaves_the_completed_chunks_readable() {
    let dir = tempfile::tempdir().unwrap();
    let mut view = ViewObserver::new(dir.path());
    view.observe_init(&scene()).unwrap();
    // Enough for about four chunks: drawings of a zigzag tape, 1000 nodes that all stay in
    // the drawing (about 20 kB each, and a /tf message each), and a sample between them.
    let nodes = 1000;
    let frame_bytes = 20 * nodes;
    let frames = 4 * file::CHUNK_SIZE / frame_bytes;
    let mut n = 0u64;
    for k in 0..frames {
        let t = 1e-3 * k as f64;
        let off_coil_m = (0..nodes)
            .map(|j| {
                let x = 1e-3 * j as f64 + t;
                [x, if j % 2 == 0 { 0.0 } else { 0.01 }]
            })
            .collect();
        let frame = Frame {
            t_s: t,
            contact_x_m: t,
            off_coil_m,
            on_coil: crate::spiral::Placed::default(),
            eq7: None,
            exact: None,
        };
        view.observe_frame(&frame).unwrap();
        view.observe_sample(&Sample {
            t_s: t,
            r_m: t.sin(),
            ..Sample::default()
        })
        .unwrap();
        n += 3;
    }
    // A crash: nothing is flushed or finished, the buffered tail is lost.
    std::mem::forget(view);
    let bytes = fs::read(dir.path().join("run.mcap.partial")).unwrap();
    let mut read = 0u64;
    let mut last = None;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        match m {
            Ok(m) => {
                assert!(last.is_none_or(|t| t <= m.log_time), "time order");
                last = Some(m.log_time);
                read += 1;
            }
            Err(_) => break,
        }
    }
    // All but the last, unfinished chunk: at least three fifths, as before.
    assert!(
        read >= 3 * n / 5 && read < n,
        "{read} of {n} messages readable after a crash, expected the completed chunks"
    );
    assert!(!dir.path().join("run.mcap").exists(), "no finished file");
}

#[test]
fn a_file_less_view_without_a_server_logs_nowhere_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let mut view = ViewObserver::without_file();
    view.observe_init(&scene()).unwrap();
    view.observe_sample(&Sample::default()).unwrap();
    assert_eq!(view.viewers(), 0);
    assert!(view.path().is_none());
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn the_derived_schema_is_renamed_but_keeps_its_fields() {
    let derived = <EventMessage as foxglove::Encode>::get_schema().unwrap();
    assert_eq!(derived.name, "eventmessage.EventMessage");
    let renamed = schema_named::<EventMessage>("uncoil", "Event");
    let a = prost_types::FileDescriptorSet::decode(derived.data.as_ref()).unwrap();
    let b = prost_types::FileDescriptorSet::decode(renamed.data.as_ref()).unwrap();
    assert_eq!(
        a.file.last().unwrap().message_type[0].field,
        b.file.last().unwrap().message_type[0].field
    );
}

/// Distance of `p` from the segment from `a` to `b` (m).
fn distance_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let s = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - s * dx).hypot(p[1] - a[1] - s * dy)
}

#[test]
fn a_drawn_spiral_passes_its_nodes_within_tolerance_and_keeps_its_points_as_it_shrinks() {
    // Ten turns of an Archimedean spiral, 32 nodes a turn, from the centre out, as a wound
    // coil is drawn; 0.25 of a 1 mm pitch, as the wound tape is.
    let pitch = 1e-3;
    let nodes: Vec<[f64; 2]> = (1..=320)
        .map(|k| {
            let a = f64::from(k) * 2.0 * std::f64::consts::PI / 32.0;
            let r = pitch * a / (2.0 * std::f64::consts::PI);
            [r * a.cos(), r * a.sin()]
        })
        .collect();
    let tol = 0.25 * pitch;
    let d: Vec<[f64; 2]> = drawn(&nodes, tol).iter().map(|p| [p.x, p.y]).collect();
    assert!(
        d.len() < nodes.len() / 2,
        "{} of {} kept",
        d.len(),
        nodes.len()
    );
    // Every node lies within the tolerance (and the 1 um rounding) of the drawn line.
    for p in &nodes {
        let near = d
            .windows(2)
            .map(|w| distance_to_segment(*p, w[0], w[1]))
            .fold(f64::INFINITY, f64::min);
        assert!(near <= tol + 2e-6, "{p:?} is {near} m off the drawn line");
    }
    // The coil sheds its outer turns: what stays is drawn through the same points, but the
    // last.
    for m in [300, 200, 101] {
        let e: Vec<[f64; 2]> = drawn(&nodes[..m], tol).iter().map(|p| [p.x, p.y]).collect();
        let same = e.iter().zip(&d).take_while(|(a, b)| a == b).count();
        assert!(
            same + 1 >= e.len(),
            "{m} nodes: {same} of {} as before",
            e.len()
        );
    }
    // A wound coil's drawing reuses the walk of the drawing before: the same points as a
    // fresh walk, as the coil sheds, and after a line that is not its continuation.
    let mut kept = Kept::default();
    let moved: Vec<[f64; 2]> = nodes.iter().map(|p| [p[0] + 1e-3, p[1]]).collect();
    for (line, m) in [
        (&nodes, 320),
        (&nodes, 300),
        (&nodes, 101),
        (&moved, 200),
        (&nodes, 30),
    ] {
        let reused = drawn_wound(&line[..m], tol, &mut kept);
        let fresh = drawn_wound(&line[..m], tol, &mut Kept::default());
        assert_eq!(reused, fresh, "{m} nodes");
        let end = super::paint::point(line[m - 1]);
        assert_eq!(fresh.last().map(|p| (p.x, p.y)), Some((end.x, end.y)));
    }
}
