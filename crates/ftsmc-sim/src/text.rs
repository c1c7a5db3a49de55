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

/// Longest list of known keys in an unknown-field message, characters:
/// with a file path, the parser's position and the quoted source line, the
/// message's one line stays within 300 characters (the CLI's bound).
const MAX_KNOWN_KEYS_CHARS: usize = 60;

/// serde's `unknown field `k`, expected one of `a`, `b`, …` (every known
/// key: 50 of them at a scenario's top level, a first line over 300
/// characters cut before its end) made short: the closest known key as a
/// remedy when one is near (`did you mean `mass`?`), the known keys as far
/// as [`MAX_KNOWN_KEYS_CHARS`] allows, then how many more and where they
/// are documented. `None` for any other message.
pub(crate) fn shorten_unknown_field(message: &str) -> Option<String> {
    let message: String = message.split_whitespace().collect::<Vec<_>>().join(" ");
    let rest = message.strip_prefix("unknown field `")?;
    let (field, rest) = rest.split_once('`')?;
    let known: Vec<&str> = rest.strip_prefix(", expected one of ")?.split(", ").map(|k| k.trim_matches('`')).collect();
    let mut out = format!("unknown field `{}`", show_str(field));
    if let Some(near) = closest(field, &known) {
        out.push_str(&format!(" (did you mean `{near}`?)"));
    }
    out.push_str(", expected one of ");
    let mut listed = 0;
    let mut list = String::new();
    for key in &known {
        let item = format!("{}`{key}`", if listed == 0 { "" } else { ", " });
        if list.chars().count() + item.chars().count() > MAX_KNOWN_KEYS_CHARS {
            break;
        }
        list.push_str(&item);
        listed += 1;
    }
    out.push_str(&list);
    if listed < known.len() {
        out.push_str(&format!(", … ({} more; docs/scenarios.md)", known.len() - listed));
    }
    Some(out)
}

/// The known key nearest `field` by edit distance, when it is near: at most
/// one edit in four characters (at least one), or `field` is a prefix of it
/// or it of `field` (`wind` for `wind_speeds`).
fn closest<'a>(field: &str, known: &[&'a str]) -> Option<&'a str> {
    let field_chars: Vec<char> = field.chars().collect();
    let allowed = (field_chars.len() / 4).max(1);
    known
        .iter()
        .map(|k| (edit_distance(&field_chars, &k.chars().collect::<Vec<_>>()), *k))
        .filter(|(d, k)| *d <= allowed || (k.len() >= 3 && (field.starts_with(k) || k.starts_with(field))))
        .min_by_key(|(d, _)| *d)
        .map(|(_, k)| k)
}

/// Levenshtein distance (insertions, deletions, substitutions).
fn edit_distance(a: &[char], b: &[char]) -> usize {
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let next = (diagonal + usize::from(ca != cb)).min(row[j] + 1).min(row[j + 1] + 1);
            diagonal = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unknown_field_names_the_nearest_key_and_a_bounded_list() {
        let known: Vec<String> = (0..50).map(|i| format!("`key_number_{i}`")).collect();
        let message = format!("unknown field `key_numbr_7`, expected one of {}", known.join(", "));
        let short = shorten_unknown_field(&message).unwrap();
        assert!(short.starts_with("unknown field `key_numbr_7` (did you mean `key_number_7`?), expected one of "));
        assert!(short.ends_with("more; docs/scenarios.md)"), "{short}");
        assert!(short.chars().count() < 160, "{} characters: {short}", short.chars().count());
        let listed = short.matches("`key_number_").count() - 1;
        assert!(short.contains(&format!("({} more;", 50 - listed)), "{short}");
        // A short list is kept whole; a far name gets no suggestion.
        let short = shorten_unknown_field("unknown field `zzz`, expected one of `mass`, `gravity`").unwrap();
        assert_eq!(short, "unknown field `zzz`, expected one of `mass`, `gravity`");
        assert_eq!(
            shorten_unknown_field("unknown field `mas`, expected one of `mass`, `gravity`").unwrap(),
            "unknown field `mas` (did you mean `mass`?), expected one of `mass`, `gravity`"
        );
        assert_eq!(shorten_unknown_field("missing field `mass`"), None);
    }

    #[test]
    fn edit_distance_counts_single_character_edits() {
        let d = |a: &str, b: &str| edit_distance(&a.chars().collect::<Vec<_>>(), &b.chars().collect::<Vec<_>>());
        assert_eq!((d("", ""), d("a", ""), d("kitten", "sitting"), d("wind_sped", "wind_speed")), (0, 1, 3, 1));
    }
}
