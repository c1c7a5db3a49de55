//! The `seed` key: a u64 that always round-trips through TOML.
//!
//! TOML integers are signed 64-bit (TOML 1.0, "Integer"), so a seed from
//! 2^63 to 2^64 − 1 — half of all Monte Carlo row seeds — has no TOML
//! integer. Such a seed is written as a decimal string
//! (`seed = "18446744073709551615"`); smaller seeds stay integers. Reading
//! accepts an integer from 0 to 2^63 − 1, or a string holding a decimal
//! (0 … 2^64 − 1) or `0x` hexadecimal u64.

use serde::{de, Deserializer, Serializer};

/// Write `seed` as a TOML integer when it fits in an i64, else as a decimal string.
pub fn serialize<S: Serializer>(seed: &u64, s: S) -> Result<S::Ok, S::Error> {
    match i64::try_from(*seed) {
        Ok(v) => s.serialize_i64(v),
        Err(_) => s.serialize_str(&seed.to_string()),
    }
}

/// Parse a seed string: decimal or `0x` hexadecimal, 0 … 2^64 − 1.
pub fn parse(text: &str) -> Option<u64> {
    let t = text.trim();
    match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(hex) => u64::from_str_radix(hex, 16).ok(),
        None => t.parse().ok(),
    }
}

struct SeedVisitor;

const EXPECTED: &str = "an integer >= 0, or a string holding a u64 (decimal or 0x hex) for seeds >= 2^63";

impl de::Visitor<'_> for SeedVisitor {
    type Value = u64;

    fn expecting(&self, f: &mut core::fmt::Formatter) -> core::fmt::Result {
        f.write_str(EXPECTED)
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<u64, E> {
        Ok(v)
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> Result<u64, E> {
        u64::try_from(v).map_err(|_| E::invalid_value(de::Unexpected::Signed(v), &EXPECTED))
    }

    fn visit_str<E: de::Error>(self, v: &str) -> Result<u64, E> {
        parse(v).ok_or_else(|| E::invalid_value(de::Unexpected::Str(&crate::text::show_str(v)), &EXPECTED))
    }
}

/// Read a seed written by [`serialize`] (or by hand; see the module docs).
pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
    d.deserialize_any(SeedVisitor)
}
