//! Reading input files with serde so that a table is only ever a table.
//!
//! serde's derived structs accept a sequence as well as a map: the elements are taken for the
//! fields in order and any more are ignored, so `axes.ry = [-1, 1, 99, "x"]` in a scenario would
//! read as `{ min = -1, max = 1 }` and `objective = [1, 2, 3]` would set the first three weights.
//! [`deserialize`] wraps a format's deserializer so that every struct, at any depth (and every
//! struct variant of an enum), refuses a sequence with serde's "invalid type: sequence, expected
//! struct …", and tracks the field path as `serde_path_to_error` does. Sequences where the type
//! expects one (vectors, `[lower, upper]` parameters, lists of tasks) are untouched.

use serde::de::{
    self, Deserialize, DeserializeSeed, Deserializer, EnumAccess, MapAccess, SeqAccess,
    VariantAccess, Visitor,
};
use std::fmt;

/// Deserialises a `T` from `de`, refusing a sequence wherever a struct is expected; the error
/// carries the path of the field at fault (`robot.uniform.axes.ry`).
pub fn deserialize<'de, D, T>(de: D) -> Result<T, serde_path_to_error::Error<D::Error>>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    serde_path_to_error::deserialize(Strict(de))
}

/// The path of a [`deserialize`] error's field, as `serde_path_to_error` writes it
/// (`targets[5].path`), without the segments it could not name (a syntax error where a key
/// should be: `targets[5].?`), and `.` for the whole value.
pub fn path<E>(e: &serde_path_to_error::Error<E>) -> String {
    use serde_path_to_error::Segment;
    let mut out = String::new();
    for segment in e.path() {
        match segment {
            Segment::Seq { index } => out.push_str(&format!("[{index}]")),
            Segment::Map { key } | Segment::Enum { variant: key } => {
                if !out.is_empty() {
                    out.push('.');
                }
                out.push_str(key);
            }
            Segment::Unknown => {}
        }
    }
    if out.is_empty() {
        out.push('.');
    }
    out
}

/// The message of a [`deserialize`] error: `path: what`, or only `what` when the whole value is
/// at fault (its path is `.`).
pub fn message<E: fmt::Display>(e: &serde_path_to_error::Error<E>) -> String {
    let path = path(e);
    if path == "." {
        e.inner().to_string()
    } else {
        format!("{path}: {}", e.inner())
    }
}

/// A deserializer whose structs take only maps.
struct Strict<D>(D);

/// A visitor passed on to the wrapped deserializer; with `table`, a sequence is refused.
struct Wrap<V> {
    visitor: V,
    table: bool,
}

impl<V> Wrap<V> {
    fn any(visitor: V) -> Self {
        Wrap {
            visitor,
            table: false,
        }
    }

    fn table(visitor: V) -> Self {
        Wrap {
            visitor,
            table: true,
        }
    }
}

/// A seed whose deserializer is wrapped in turn.
struct Seed<S>(S);

/// Sequence, map, enum and variant access whose values are deserialised strictly.
struct Access<A>(A);

macro_rules! forward_deserialize {
    ($($method:ident)*) => {
        $(
            fn $method<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, D::Error> {
                self.0.$method(Wrap::any(visitor))
            }
        )*
    };
}

impl<'de, D: Deserializer<'de>> Deserializer<'de> for Strict<D> {
    type Error = D::Error;

    forward_deserialize! {
        deserialize_any deserialize_bool deserialize_i8 deserialize_i16 deserialize_i32
        deserialize_i64 deserialize_i128 deserialize_u8 deserialize_u16 deserialize_u32
        deserialize_u64 deserialize_u128 deserialize_f32 deserialize_f64 deserialize_char
        deserialize_str deserialize_string deserialize_bytes deserialize_byte_buf
        deserialize_option deserialize_unit deserialize_seq deserialize_map
        deserialize_identifier deserialize_ignored_any
    }

    fn deserialize_unit_struct<V: Visitor<'de>>(
        self,
        name: &'static str,
        visitor: V,
    ) -> Result<V::Value, D::Error> {
        self.0.deserialize_unit_struct(name, Wrap::any(visitor))
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(
        self,
        name: &'static str,
        visitor: V,
    ) -> Result<V::Value, D::Error> {
        self.0.deserialize_newtype_struct(name, Wrap::any(visitor))
    }

    fn deserialize_tuple<V: Visitor<'de>>(
        self,
        len: usize,
        visitor: V,
    ) -> Result<V::Value, D::Error> {
        self.0.deserialize_tuple(len, Wrap::any(visitor))
    }

    fn deserialize_tuple_struct<V: Visitor<'de>>(
        self,
        name: &'static str,
        len: usize,
        visitor: V,
    ) -> Result<V::Value, D::Error> {
        self.0
            .deserialize_tuple_struct(name, len, Wrap::any(visitor))
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        name: &'static str,
        fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, D::Error> {
        self.0
            .deserialize_struct(name, fields, Wrap::table(visitor))
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        name: &'static str,
        variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, D::Error> {
        self.0.deserialize_enum(name, variants, Wrap::any(visitor))
    }

    fn is_human_readable(&self) -> bool {
        self.0.is_human_readable()
    }
}

macro_rules! forward_visit {
    ($($method:ident: $ty:ty)*) => {
        $(
            fn $method<E: de::Error>(self, v: $ty) -> Result<V::Value, E> {
                self.visitor.$method(v)
            }
        )*
    };
}

impl<'de, V: Visitor<'de>> Visitor<'de> for Wrap<V> {
    type Value = V::Value;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        self.visitor.expecting(f)
    }

    forward_visit! {
        visit_bool: bool
        visit_i8: i8
        visit_i16: i16
        visit_i32: i32
        visit_i64: i64
        visit_i128: i128
        visit_u8: u8
        visit_u16: u16
        visit_u32: u32
        visit_u64: u64
        visit_u128: u128
        visit_f32: f32
        visit_f64: f64
        visit_char: char
        visit_str: &str
        visit_borrowed_str: &'de str
        visit_string: String
        visit_bytes: &[u8]
        visit_borrowed_bytes: &'de [u8]
        visit_byte_buf: Vec<u8>
    }

    fn visit_none<E: de::Error>(self) -> Result<V::Value, E> {
        self.visitor.visit_none()
    }

    fn visit_unit<E: de::Error>(self) -> Result<V::Value, E> {
        self.visitor.visit_unit()
    }

    fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<V::Value, D::Error> {
        self.visitor.visit_some(Strict(d))
    }

    fn visit_newtype_struct<D: Deserializer<'de>>(self, d: D) -> Result<V::Value, D::Error> {
        self.visitor.visit_newtype_struct(Strict(d))
    }

    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<V::Value, A::Error> {
        if self.table {
            return Err(de::Error::invalid_type(de::Unexpected::Seq, &self));
        }
        self.visitor.visit_seq(Access(seq))
    }

    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<V::Value, A::Error> {
        self.visitor.visit_map(Access(map))
    }

    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<V::Value, A::Error> {
        self.visitor.visit_enum(Access(data))
    }
}

impl<'de, S: DeserializeSeed<'de>> DeserializeSeed<'de> for Seed<S> {
    type Value = S::Value;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<S::Value, D::Error> {
        self.0.deserialize(Strict(d))
    }
}

impl<'de, A: SeqAccess<'de>> SeqAccess<'de> for Access<A> {
    type Error = A::Error;

    fn next_element_seed<T: DeserializeSeed<'de>>(
        &mut self,
        seed: T,
    ) -> Result<Option<T::Value>, A::Error> {
        self.0.next_element_seed(Seed(seed))
    }

    fn size_hint(&self) -> Option<usize> {
        self.0.size_hint()
    }
}

impl<'de, A: MapAccess<'de>> MapAccess<'de> for Access<A> {
    type Error = A::Error;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, A::Error> {
        self.0.next_key_seed(Seed(seed))
    }

    fn next_value_seed<T: DeserializeSeed<'de>>(&mut self, seed: T) -> Result<T::Value, A::Error> {
        self.0.next_value_seed(Seed(seed))
    }

    fn size_hint(&self) -> Option<usize> {
        self.0.size_hint()
    }
}

impl<'de, A: EnumAccess<'de>> EnumAccess<'de> for Access<A> {
    type Error = A::Error;
    type Variant = Access<A::Variant>;

    fn variant_seed<T: DeserializeSeed<'de>>(
        self,
        seed: T,
    ) -> Result<(T::Value, Self::Variant), A::Error> {
        let (value, variant) = self.0.variant_seed(Seed(seed))?;
        Ok((value, Access(variant)))
    }
}

impl<'de, A: VariantAccess<'de>> VariantAccess<'de> for Access<A> {
    type Error = A::Error;

    fn unit_variant(self) -> Result<(), A::Error> {
        self.0.unit_variant()
    }

    fn newtype_variant_seed<T: DeserializeSeed<'de>>(self, seed: T) -> Result<T::Value, A::Error> {
        self.0.newtype_variant_seed(Seed(seed))
    }

    fn tuple_variant<V: Visitor<'de>>(self, len: usize, visitor: V) -> Result<V::Value, A::Error> {
        self.0.tuple_variant(len, Wrap::any(visitor))
    }

    fn struct_variant<V: Visitor<'de>>(
        self,
        fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, A::Error> {
        self.0.struct_variant(fields, Wrap::table(visitor))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Range {
        min: f64,
        max: f64,
    }

    #[derive(Debug, PartialEq, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Outer {
        point: [f64; 3],
        #[serde(default)]
        ranges: Vec<Range>,
        #[serde(default)]
        range: Option<Range>,
    }

    fn json(text: &str) -> Result<Outer, String> {
        deserialize(&mut serde_json::Deserializer::from_str(text)).map_err(|e| e.to_string())
    }

    fn toml(text: &str) -> Result<Outer, String> {
        deserialize(toml::de::Deserializer::parse(text).unwrap()).map_err(|e| e.to_string())
    }

    /// A syntax error where a key should be names the value it lies in, without the `?`
    /// segment `serde_path_to_error` writes for the key it could not read.
    #[test]
    fn paths_leave_out_unnamed_segments() {
        let text = r#"{"point": [0, 0, 0], "ranges": [{"min": 1, 7: 2}]}"#;
        let e = deserialize::<_, Outer>(&mut serde_json::Deserializer::from_str(text)).unwrap_err();
        assert_eq!(e.path().to_string(), "ranges[0].?");
        assert_eq!(path(&e), "ranges[0]");
        assert!(
            message(&e).starts_with("ranges[0]: key must be a string"),
            "{}",
            message(&e)
        );
        let e =
            deserialize::<_, Outer>(&mut serde_json::Deserializer::from_str("{7: 1}")).unwrap_err();
        assert_eq!(path(&e), ".");
        let text = r#"{"point": [0, 0, 0], "range": {"min": "x", "max": 1}}"#;
        let e = deserialize::<_, Outer>(&mut serde_json::Deserializer::from_str(text)).unwrap_err();
        assert_eq!(path(&e), "range.min");
    }

    #[test]
    fn tables_given_as_arrays_are_refused_at_any_depth() {
        let good = Outer {
            point: [1.0, 2.0, 3.0],
            ranges: vec![Range { min: 0.0, max: 1.0 }],
            range: Some(Range {
                min: -1.0,
                max: 1.0,
            }),
        };
        let text = r#"{"point":[1,2,3],"ranges":[{"min":0,"max":1}],"range":{"min":-1,"max":1}}"#;
        assert_eq!(json(text).unwrap(), good);
        let text = "point = [1, 2, 3]\nrange = { min = -1, max = 1 }\n[[ranges]]\nmin = 0\nmax = 1";
        assert_eq!(toml(text).unwrap(), good);
        // serde's own reading takes the elements for the fields.
        let plain: Outer = serde_json::from_str(r#"{"point":[1,2,3],"range":[-1,1]}"#).unwrap();
        assert_eq!(
            plain.range,
            Some(Range {
                min: -1.0,
                max: 1.0
            })
        );
        for (e, field) in [
            (json(r#"{"point":[1,2,3],"range":[-1,1,9]}"#), "range"),
            (json(r#"{"point":[1,2,3],"ranges":[[0,1]]}"#), "ranges[0]"),
            (json(r#"[[1,2,3]]"#), ""),
            (toml("point = [1, 2, 3]\nrange = [-1, 1]"), "range"),
            (toml("point = [1, 2, 3]\nranges = [[]]"), "ranges[0]"),
        ] {
            let e = e.unwrap_err();
            assert!(
                e.starts_with(field) && e.contains("invalid type: sequence, expected struct"),
                "{e}"
            );
        }
    }
}
