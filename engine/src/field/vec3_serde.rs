//! The RON spellings of a vector inside a variant: `Direction(0.0, 1.0, 0.0)` and
//! `Direction((0.0, 1.0, 0.0))` (and `Point(...)` alike) read as the same `[f64; 3]`.
//!
//! Input: a serde deserializer at a 3-vector; output: the vector. Cost: O(1).
//! Serialization is unchanged (the plain array).

use std::fmt;

use serde::de::{self, Deserializer, SeqAccess, Visitor};

/// Deserializes a 3-vector given as three numbers or as one tuple of three numbers.
pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 3], D::Error> {
    d.deserialize_tuple(3, Vec3Visitor)
}

/// A number or a nested 3-vector: one element of the outer sequence.
enum Item {
    Number(f64),
    Vector([f64; 3]),
}

impl<'de> serde::Deserialize<'de> for Item {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(ItemVisitor)
    }
}

struct ItemVisitor;

impl<'de> Visitor<'de> for ItemVisitor {
    type Value = Item;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a number or a vector (x, y, z)")
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Item, E> {
        Ok(Item::Number(v))
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Item, E> {
        Ok(Item::Number(v as f64))
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Item, E> {
        Ok(Item::Number(v as f64))
    }

    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Item, A::Error> {
        Vec3Visitor.visit_seq(seq).map(Item::Vector)
    }
}

struct Vec3Visitor;

impl<'de> Visitor<'de> for Vec3Visitor {
    type Value = [f64; 3];

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("three numbers (x, y, z)")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[f64; 3], A::Error> {
        let mut out = [0.0; 3];
        for (i, slot) in out.iter_mut().enumerate() {
            match seq.next_element::<Item>()? {
                Some(Item::Number(v)) => *slot = v,
                // `((x, y, z))`: the whole vector as the one element.
                Some(Item::Vector(v)) if i == 0 => {
                    if seq.next_element::<Item>()?.is_some() {
                        return Err(de::Error::invalid_length(2, &self));
                    }
                    return Ok(v);
                }
                Some(Item::Vector(_)) => return Err(de::Error::invalid_length(i, &self)),
                None => return Err(de::Error::invalid_length(i, &self)),
            }
        }
        if seq.next_element::<Item>()?.is_some() {
            return Err(de::Error::invalid_length(4, &self));
        }
        Ok(out)
    }
}
