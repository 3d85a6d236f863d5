//! The four channels of a run's view and the message types of the two that are the
//! project's own. `/scene` and `/tf` carry the SDK's `foxglove.SceneUpdate` and
//! `foxglove.FrameTransforms`. `/state` carries [`State`], a [`Sample`] in protobuf with a
//! schema made from the sample's own fields; `/events` carries [`EventMessage`], whose
//! schema the SDK's derive makes. They are named `uncoil.State` and `uncoil.Event`.

use std::sync::{Arc, OnceLock};

use foxglove::bytes::BufMut;
use foxglove::messages::{FrameTransforms, SceneUpdate};
use foxglove::{Channel, ChannelBuilder, Context, Encode, Schema};
use prost::Message as _;
use prost_types::field_descriptor_proto::{Label, Type};
use prost_types::{DescriptorProto, FieldDescriptorProto, FileDescriptorProto, FileDescriptorSet};

use crate::output::fields::{NotFlat, fields};

use super::{EVENTS_TOPIC, SCENE_TOPIC, STATE_TOPIC, TF_TOPIC};
use crate::run::Sample;
use crate::run::frame::Event;

/// The channels, registered in one run's context.
pub struct Channels {
    /// `/scene`.
    pub scene: Channel<Drawing>,
    /// `/state`.
    pub state: Channel<State>,
    /// `/events`.
    pub events: Channel<EventMessage>,
    /// `/tf`.
    pub tf: Channel<FrameTransforms>,
}

impl Channels {
    /// Registers the channels in `context`.
    pub fn new(context: &Arc<Context>) -> Self {
        Self {
            scene: ChannelBuilder::new(SCENE_TOPIC).context(context).build(),
            state: ChannelBuilder::new(STATE_TOPIC).context(context).build(),
            events: ChannelBuilder::new(EVENTS_TOPIC)
                .context(context)
                .schema(schema_named::<EventMessage>("uncoil", "Event"))
                .build(),
            tf: ChannelBuilder::new(TF_TOPIC).context(context).build(),
        }
    }
}

/// A scene drawing as a `/scene` message: the SDK's `foxglove.SceneUpdate`, its schema and
/// its bytes, but encoded into a plain vector and handed to the SDK in one piece. The SDK's
/// buffer checks its capacity on every put, and a drawing is thousands of small fields: this
/// way costs a third of the instructions (measured with callgrind on the yoga mat).
#[derive(Debug, Clone)]
pub struct Drawing(pub SceneUpdate);

impl Encode for Drawing {
    type Error = std::convert::Infallible;

    fn get_schema() -> Option<Schema> {
        SceneUpdate::get_schema()
    }

    fn get_message_encoding() -> String {
        SceneUpdate::get_message_encoding()
    }

    fn encode(&self, buf: &mut impl BufMut) -> Result<(), Self::Error> {
        buf.put_slice(&self.0.encode_to_vec());
        Ok(())
    }
}

/// The schema `T`'s derive makes, its message renamed `package.message`.
///
/// The derive names a type's schema after the type (`sample.Sample`); the log keeps the names
/// its readers know. The message's own fields and nested enums are untouched, and they refer
/// to each other by relative names, so only the file's package and the message's name change.
pub fn schema_named<T: Encode>(package: &str, message: &str) -> Schema {
    let derived = T::get_schema().expect("a derived type has a schema");
    let mut set = prost_types::FileDescriptorSet::decode(derived.data.as_ref())
        .expect("the derive writes a valid descriptor set");
    // The type's own file is the last; those before it are well-known types it uses.
    let file = set.file.last_mut().expect("one file at least");
    file.package = Some(package.to_owned());
    file.name = Some(format!("{package}/{message}.proto"));
    file.message_type[0].name = Some(message.to_owned());
    Schema::new(
        format!("{package}.{message}"),
        "protobuf",
        set.encode_to_vec(),
    )
}

/// A sample as a `/state` message: protobuf message `uncoil.State`, one `float` field per
/// column of `samples.csv`, numbered from 1 in the sample's field order ([`fields`]), so the
/// sample is the one definition of both.
///
/// The log is for viewing; `samples.csv` keeps 10 significant digits. A `float` keeps 7, in
/// half the bytes of a `double`, and every field but `t_s` is rounded further, to
/// [`STATE_MANTISSA_BITS`] bits (a relative step of 1.5e-5, finer than a plot 4,000 pixels
/// high shows by a factor of 16): the low bits of a simulation's numbers are noise that no
/// compressor can shorten, and zeroing them makes the log a quarter smaller. `t_s` keeps its
/// `float`, the time a reader aligns the rows by. A quantity that does not exist (a
/// reference past its end) is `NaN`; a zero is not written, as proto3 omits default values.
#[derive(Debug, Clone, Copy)]
pub struct State(pub Sample);

/// Mantissa bits a `/state` field keeps, `t_s` aside (a `float` has 23).
pub const STATE_MANTISSA_BITS: u32 = 15;

/// The largest relative error of a `/state` field against the sample, `t_s` aside: the
/// rounding to [`STATE_MANTISSA_BITS`] bits after the rounding to a `float`.
pub const STATE_RELATIVE_ERROR: f64 =
    1.0 / (1u64 << (STATE_MANTISSA_BITS + 1)) as f64 + 1.0 / (1u64 << 24) as f64;

/// `value` rounded to [`STATE_MANTISSA_BITS`] mantissa bits, to nearest (a tie away from
/// zero); infinities and `NaN` as they are.
fn coarse(value: f32) -> f32 {
    const DROP: u32 = 23 - STATE_MANTISSA_BITS;
    if !value.is_finite() {
        return value;
    }
    let bits = (value.to_bits() + (1 << (DROP - 1))) & !((1 << DROP) - 1);
    let rounded = f32::from_bits(bits);
    // Within a step of f32::MAX the rounding would carry into infinity: kept as it is.
    if rounded.is_finite() { rounded } else { value }
}

impl Encode for State {
    type Error = NotFlat;

    fn get_schema() -> Option<Schema> {
        static SCHEMA: OnceLock<Schema> = OnceLock::new();
        Some(SCHEMA.get_or_init(state_schema).clone())
    }

    fn get_message_encoding() -> String {
        "protobuf".into()
    }

    fn encode(&self, buf: &mut impl BufMut) -> Result<(), NotFlat> {
        // Gathered in a plain vector first and handed over in one piece: the SDK's buffer
        // checks its capacity on every put, which cost more than the encoding itself.
        let fields = fields(&self.0)?;
        let mut bytes = Vec::with_capacity(7 * fields.len());
        for (number, (_, value)) in (1u64..).zip(fields) {
            // Field 1 is `t_s`.
            let value = if number == 1 {
                value as f32
            } else {
                coarse(value as f32)
            };
            if value != 0.0 {
                // Wire type 5: 32-bit.
                prost::encoding::encode_varint(number << 3 | 5, &mut bytes);
                bytes.extend_from_slice(&value.to_le_bytes());
            }
        }
        buf.put_slice(&bytes);
        Ok(())
    }
}

/// The descriptor set of `uncoil.State`, from the sample's field names.
fn state_schema() -> Schema {
    let names = fields(&Sample::default()).expect("a sample is a flat record");
    let field = (1..)
        .zip(names)
        .map(|(number, (name, _))| FieldDescriptorProto {
            name: Some(name.to_owned()),
            number: Some(number),
            label: Some(Label::Optional as i32),
            r#type: Some(Type::Float as i32),
            ..FieldDescriptorProto::default()
        })
        .collect();
    let set = FileDescriptorSet {
        file: vec![FileDescriptorProto {
            name: Some("uncoil/State.proto".into()),
            package: Some("uncoil".into()),
            syntax: Some("proto3".into()),
            message_type: vec![DescriptorProto {
                name: Some("State".into()),
                field,
                ..DescriptorProto::default()
            }],
            ..FileDescriptorProto::default()
        }],
    };
    Schema::new("uncoil.State", "protobuf", set.encode_to_vec())
}

/// What kind of event a message is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Encode)]
pub enum EventKind {
    /// Links left the coil.
    Detach,
    /// The final bang began.
    BangStart,
    /// The final bang ended: the end of the run.
    BangEnd,
    /// Something a user should know.
    Warning,
}

/// What ended the final bang, on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Encode)]
pub enum EndedBy {
    /// Not a `bang_end`.
    None,
    /// The tape came to rest.
    Rest,
    /// The bang's time cap passed.
    Cap,
}

/// An [`Event`] as a `/events` message: its kind, its time, and the fields of that kind (the
/// others absent).
#[derive(Debug, Clone, PartialEq, Encode)]
pub struct EventMessage {
    /// What happened.
    pub kind: EventKind,
    /// Simulated time (s).
    pub t_s: f64,
    /// `detach`: index of the first link that left in this step, 0 = the outer end.
    pub first_link: Option<u64>,
    /// `detach`: links that left in this step.
    pub links: Option<u64>,
    /// `detach`: links off the coil after this step.
    pub detached: Option<u64>,
    /// `detach`: energy lost by these detaches (J), negative if gained.
    pub energy_lost_j: Option<f64>,
    /// `bang_start`: kinetic energy carried into the bang (J).
    pub kinetic_j: Option<f64>,
    /// `bang_start`: mechanical energy above the flat rest state (J).
    pub available_j: Option<f64>,
    /// `bang_end`: when the bang began (s).
    pub started_s: Option<f64>,
    /// `bang_end`: energy dissipated from the start of the bang on (J).
    pub dissipated_j: Option<f64>,
    /// `bang_end`: what ended it.
    pub ended_by: EndedBy,
    /// `warning`: what happened.
    pub message: String,
}

impl From<&Event> for EventMessage {
    fn from(event: &Event) -> Self {
        let mut m = Self {
            kind: EventKind::Warning,
            t_s: event.t_s(),
            first_link: None,
            links: None,
            detached: None,
            energy_lost_j: None,
            kinetic_j: None,
            available_j: None,
            started_s: None,
            dissipated_j: None,
            ended_by: EndedBy::None,
            message: String::new(),
        };
        match event {
            Event::Detach {
                first_link,
                links,
                detached,
                energy_lost_j,
                ..
            } => {
                m.kind = EventKind::Detach;
                m.first_link = Some(*first_link as u64);
                m.links = Some(*links as u64);
                m.detached = Some(*detached as u64);
                m.energy_lost_j = Some(*energy_lost_j);
            }
            Event::BangStart {
                kinetic_j,
                available_j,
                ..
            } => {
                m.kind = EventKind::BangStart;
                m.kinetic_j = Some(*kinetic_j);
                m.available_j = Some(*available_j);
            }
            Event::BangEnd {
                started_s,
                dissipated_j,
                ended_by,
                ..
            } => {
                m.kind = EventKind::BangEnd;
                m.started_s = Some(*started_s);
                m.dissipated_j = Some(*dissipated_j);
                m.ended_by = match ended_by {
                    crate::model::BangEnd::Rest => EndedBy::Rest,
                    crate::model::BangEnd::Cap => EndedBy::Cap,
                };
            }
            Event::Warning { message, .. } => message.clone_into(&mut m.message),
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_field_keeps_its_bits_within_the_stated_error() {
        let mut x: u64 = 0x2545_f491_4f6c_dd1d;
        for _ in 0..100_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = f64::from_bits(x);
            if !v.is_finite() || v.abs() > f64::from(f32::MAX) / 2.0 {
                continue;
            }
            let got = f64::from(coarse(v as f32));
            assert!(
                (got - v).abs() <= STATE_RELATIVE_ERROR * v.abs() + f64::from(f32::MIN_POSITIVE),
                "{v:e} became {got:e}"
            );
        }
        // What already fits is kept; NaN stays NaN; the trailing bits are zero.
        for v in [0.0_f32, 1.0, -2.5, 0.001_953_125, 1e30] {
            assert_eq!(coarse(coarse(v)), coarse(v));
        }
        assert_eq!(coarse(1.5), 1.5);
        assert_eq!(coarse(f32::MAX), f32::MAX);
        assert_eq!(coarse(-f32::MAX), -f32::MAX);
        assert!(coarse(f32::NAN).is_nan());
        assert_eq!(coarse(0.1).to_bits() & 0xff, 0);
    }
}
