//! Text in error messages and exact-length arrays in TOML: how a value or a
//! piece of user text is shown (bounded, escaped), a TOML parse error as one
//! line, and `#[serde(with = "exact_array")]`. Used by every parameter
//! struct's validation; imports nothing from the crate.

/// Longest value echoed in an error message, characters (longer ones are
/// cut and end in `…`).
pub const MAX_SHOWN_CHARS: usize = 40;

/// A number for an error message: the ordinary decimal form when it is
/// short (`0.74`, `-3`), scientific otherwise (`1e308`, `5e-324`, never 309
/// digits), at most [`MAX_SHOWN_CHARS`] characters.
pub fn show(v: f64) -> String {
    let plain = v.to_string();
    if plain.len() <= 24 && (v == 0.0 || (1e-4..1e6).contains(&v.abs())) {
        plain
    } else {
        show_str(&format!("{v:e}"))
    }
}

/// Longest parser message kept in an error, characters.
const MAX_PARSE_MESSAGE_CHARS: usize = 300;

/// A TOML error as one bounded line: `TOML parse error at line L, column C (`source line`): message`
/// (the parser's own text spans several lines and quotes the source line).
pub(crate) fn parse_message(text: &str, e: &toml::de::Error) -> String {
    let mut message: String = e.message().split_whitespace().collect::<Vec<_>>().join(" ");
    if message.chars().count() > MAX_PARSE_MESSAGE_CHARS {
        message = message.chars().take(MAX_PARSE_MESSAGE_CHARS - 1).collect();
        message.push('…');
    }
    match e.span() {
        Some(span) => {
            let before = &text.as_bytes()[..span.start.min(text.len())];
            let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
            let column = before.iter().rev().take_while(|&&b| b != b'\n').count() + 1;
            let source = text.lines().nth(line - 1).unwrap_or("").trim();
            format!("TOML parse error at line {line}, column {column} (`{}`): {message}", show_str(source))
        }
        None => format!("TOML parse error: {message}"),
    }
}

/// Where a TOML parse error is, without quoting the file:
/// `not valid TOML at line L, column C`.
pub(crate) fn parse_position(text: &str, e: &toml::de::Error) -> String {
    match e.span() {
        Some(span) => {
            let before = &text.as_bytes()[..span.start.min(text.len())];
            let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
            let column = before.iter().rev().take_while(|&&b| b != b'\n').count() + 1;
            format!("not valid TOML at line {line}, column {column}")
        }
        None => "not valid TOML".to_string(),
    }
}

/// A piece of user text for an error message: control characters escaped,
/// at most [`MAX_SHOWN_CHARS`] characters (then `…`).
pub fn show_str(s: &str) -> String {
    let escaped: String = s.chars().flat_map(char::escape_debug).collect();
    if escaped.chars().count() <= MAX_SHOWN_CHARS {
        escaped
    } else {
        let mut cut: String = escaped.chars().take(MAX_SHOWN_CHARS - 1).collect();
        cut.push('…');
        cut
    }
}

/// `#[serde(with = "exact_array")]` for fixed-size arrays in scenario files:
/// serde's own `[T; N]` reads the first N elements and, in TOML, silently
/// ignores the rest (`position = [0.5, 0.25, 0.0, 99.0, "junk", [1]]` was a
/// valid position). This reads the whole array and errors on too few or too
/// many elements, naming the length found and the length wanted.
pub mod exact_array {
    use core::fmt;
    use core::marker::PhantomData;

    use serde::de::{self, IgnoredAny, SeqAccess, Visitor};
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    struct Exact<T, const N: usize>(PhantomData<T>);

    impl<'de, T: Deserialize<'de>, const N: usize> Visitor<'de> for Exact<T, N> {
        type Value = [T; N];

        fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            write!(f, "an array of exactly {N} numbers")
        }

        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[T; N], A::Error> {
            let mut items = Vec::with_capacity(N);
            while items.len() < N {
                match seq.next_element::<T>()? {
                    Some(v) => items.push(v),
                    None => return Err(de::Error::invalid_length(items.len(), &self)),
                }
            }
            let mut extra = 0usize;
            while seq.next_element::<IgnoredAny>()?.is_some() {
                extra += 1;
            }
            if extra > 0 {
                return Err(de::Error::invalid_length(N + extra, &self));
            }
            items.try_into().map_err(|_| de::Error::invalid_length(N, &self))
        }
    }

    /// Serialize as an ordinary array.
    pub fn serialize<S: Serializer, T: Serialize, const N: usize>(v: &[T; N], s: S) -> Result<S::Ok, S::Error> {
        v.as_slice().serialize(s)
    }

    /// Deserialize exactly `N` elements.
    pub fn deserialize<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
        d: D,
    ) -> Result<[T; N], D::Error> {
        d.deserialize_seq(Exact::<T, N>(PhantomData))
    }

    /// The same for an optional array (`#[serde(default, with = "exact_array::option")]`).
    pub mod option {
        use super::*;

        struct Wrap<T, const N: usize>([T; N]);

        impl<'de, T: Deserialize<'de>, const N: usize> Deserialize<'de> for Wrap<T, N> {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                super::deserialize(d).map(Wrap)
            }
        }

        /// Serialize as an ordinary optional array.
        pub fn serialize<S: Serializer, T: Serialize, const N: usize>(
            v: &Option<[T; N]>,
            s: S,
        ) -> Result<S::Ok, S::Error> {
            match v {
                Some(a) => s.serialize_some(a.as_slice()),
                None => s.serialize_none(),
            }
        }

        /// Deserialize `Some` of exactly `N` elements.
        pub fn deserialize<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
            d: D,
        ) -> Result<Option<[T; N]>, D::Error> {
            Option::<Wrap<T, N>>::deserialize(d).map(|o| o.map(|w| w.0))
        }
    }
}
