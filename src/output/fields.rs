//! A flat record of numbers read through serde: the names and values of a struct's fields
//! in declaration order, as its `Serialize` derive gives them. `samples.csv`'s header and
//! cells, the `/state` schema's check and the inspect tool all take the sample's columns
//! from here, so the struct is their one definition. It formats nothing.

use std::fmt;

use serde::Serialize;
use serde::ser::{self, Impossible, SerializeStruct};

/// Why a value is not a flat record of numbers.
#[derive(Debug)]
pub struct NotFlat(String);

impl fmt::Display for NotFlat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "not a flat record of numbers: {}", self.0)
    }
}

impl std::error::Error for NotFlat {}

impl ser::Error for NotFlat {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        Self(msg.to_string())
    }
}

/// The fields of `row`, a struct whose fields are all numbers (or options of numbers, a
/// `None` read as `NaN`), by name, in declaration order.
///
/// # Errors
///
/// If `row` is not a struct or one of its fields is not a number.
pub fn fields<T: Serialize>(row: &T) -> Result<Vec<(&'static str, f64)>, NotFlat> {
    row.serialize(Record)
}

/// The serializer of the record itself: it accepts only a struct.
struct Record;

/// The fields gathered so far.
struct Gather(Vec<(&'static str, f64)>);

/// The serializer of one field's value: it accepts only a number.
struct Number;

macro_rules! refuse {
    ($($method:ident($($arg:ty),*) -> $ret:ty;)*) => {
        $(fn $method(self, $(_: $arg),*) -> Result<$ret, NotFlat> {
            Err(NotFlat(stringify!($method).into()))
        })*
    };
}

/// The methods both serializers refuse: every shape but a struct or a number.
macro_rules! refuse_shapes {
    ($ok:ty) => {
        refuse! {
            serialize_bool(bool) -> $ok;
            serialize_char(char) -> $ok;
            serialize_str(&str) -> $ok;
            serialize_bytes(&[u8]) -> $ok;
            serialize_unit() -> $ok;
            serialize_unit_struct(&'static str) -> $ok;
            serialize_unit_variant(&'static str, u32, &'static str) -> $ok;
            serialize_seq(Option<usize>) -> Self::SerializeSeq;
            serialize_tuple(usize) -> Self::SerializeTuple;
            serialize_tuple_struct(&'static str, usize) -> Self::SerializeTupleStruct;
            serialize_tuple_variant(&'static str, u32, &'static str, usize) -> Self::SerializeTupleVariant;
            serialize_map(Option<usize>) -> Self::SerializeMap;
            serialize_struct_variant(&'static str, u32, &'static str, usize) -> Self::SerializeStructVariant;
        }
        fn serialize_newtype_variant<V: ?Sized + Serialize>(
            self,
            _: &'static str,
            _: u32,
            variant: &'static str,
            _: &V,
        ) -> Result<$ok, NotFlat> {
            Err(NotFlat(format!("variant {variant}")))
        }
    };
}

/// The numeric methods of [`Number`]: every integer and float is read as `f64`.
macro_rules! numbers {
    ($($method:ident($ty:ty)),*) => {
        $(
            fn $method(self, v: $ty) -> Result<f64, NotFlat> {
                Ok(v as f64)
            }
        )*
    };
}

impl ser::Serializer for Record {
    type Ok = Vec<(&'static str, f64)>;
    type Error = NotFlat;
    type SerializeSeq = Impossible<Self::Ok, NotFlat>;
    type SerializeTuple = Impossible<Self::Ok, NotFlat>;
    type SerializeTupleStruct = Impossible<Self::Ok, NotFlat>;
    type SerializeTupleVariant = Impossible<Self::Ok, NotFlat>;
    type SerializeMap = Impossible<Self::Ok, NotFlat>;
    type SerializeStruct = Gather;
    type SerializeStructVariant = Impossible<Self::Ok, NotFlat>;

    refuse_shapes!(Self::Ok);
    refuse! {
        serialize_i8(i8) -> Self::Ok;
        serialize_i16(i16) -> Self::Ok;
        serialize_i32(i32) -> Self::Ok;
        serialize_i64(i64) -> Self::Ok;
        serialize_u8(u8) -> Self::Ok;
        serialize_u16(u16) -> Self::Ok;
        serialize_u32(u32) -> Self::Ok;
        serialize_u64(u64) -> Self::Ok;
        serialize_f32(f32) -> Self::Ok;
        serialize_f64(f64) -> Self::Ok;
        serialize_none() -> Self::Ok;
    }

    fn serialize_some<V: ?Sized + Serialize>(self, _: &V) -> Result<Self::Ok, NotFlat> {
        Err(NotFlat("an option".into()))
    }

    fn serialize_newtype_struct<V: ?Sized + Serialize>(
        self,
        _: &'static str,
        value: &V,
    ) -> Result<Self::Ok, NotFlat> {
        value.serialize(self)
    }

    fn serialize_struct(self, _: &'static str, len: usize) -> Result<Gather, NotFlat> {
        Ok(Gather(Vec::with_capacity(len)))
    }
}

impl SerializeStruct for Gather {
    type Ok = Vec<(&'static str, f64)>;
    type Error = NotFlat;

    fn serialize_field<V: ?Sized + Serialize>(
        &mut self,
        key: &'static str,
        value: &V,
    ) -> Result<(), NotFlat> {
        let v = value
            .serialize(Number)
            .map_err(|e| NotFlat(format!("field {key}: {}", e.0)))?;
        self.0.push((key, v));
        Ok(())
    }

    fn end(self) -> Result<Self::Ok, NotFlat> {
        Ok(self.0)
    }
}

impl ser::Serializer for Number {
    type Ok = f64;
    type Error = NotFlat;
    type SerializeSeq = Impossible<f64, NotFlat>;
    type SerializeTuple = Impossible<f64, NotFlat>;
    type SerializeTupleStruct = Impossible<f64, NotFlat>;
    type SerializeTupleVariant = Impossible<f64, NotFlat>;
    type SerializeMap = Impossible<f64, NotFlat>;
    type SerializeStruct = Impossible<f64, NotFlat>;
    type SerializeStructVariant = Impossible<f64, NotFlat>;

    refuse_shapes!(f64);
    numbers!(
        serialize_i8(i8),
        serialize_i16(i16),
        serialize_i32(i32),
        serialize_i64(i64),
        serialize_u8(u8),
        serialize_u16(u16),
        serialize_u32(u32),
        serialize_u64(u64),
        serialize_f32(f32),
        serialize_f64(f64)
    );

    fn serialize_none(self) -> Result<f64, NotFlat> {
        Ok(f64::NAN)
    }

    fn serialize_some<V: ?Sized + Serialize>(self, value: &V) -> Result<f64, NotFlat> {
        value.serialize(self)
    }

    fn serialize_newtype_struct<V: ?Sized + Serialize>(
        self,
        _: &'static str,
        value: &V,
    ) -> Result<f64, NotFlat> {
        value.serialize(self)
    }

    fn serialize_struct(
        self,
        name: &'static str,
        _: usize,
    ) -> Result<Self::SerializeStruct, NotFlat> {
        Err(NotFlat(format!("struct {name}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize)]
    struct Row {
        t_s: f64,
        bodies: usize,
        maybe: Option<f64>,
    }

    #[test]
    fn a_flat_struct_reads_as_its_fields_in_order() {
        let row = Row {
            t_s: 0.5,
            bodies: 3,
            maybe: None,
        };
        let got = fields(&row).unwrap();
        assert_eq!(got.len(), 3);
        assert_eq!((got[0].0, got[0].1), ("t_s", 0.5));
        assert_eq!((got[1].0, got[1].1), ("bodies", 3.0));
        assert!(got[2].0 == "maybe" && got[2].1.is_nan());
    }

    #[test]
    fn anything_else_is_refused() {
        #[derive(Serialize)]
        struct Nested {
            name: String,
        }
        assert!(fields(&1.0_f64).is_err());
        let e = fields(&Nested { name: "x".into() }).unwrap_err();
        assert!(e.to_string().contains("field name"), "{e}");
    }
}
