//! Arbitrary strings through every writer of user text, parsed back: a
//! TOML comment (the command line of a tuned file) adds no key, a CSV
//! field reads back the same, a Markdown table row keeps its columns, an
//! SVG stays well-formed XML with no element added. The strings mix
//! newlines, quotes, `]]>`, `<`, `&`, `|`, backslashes, control characters
//! and any Unicode.

use proptest::prelude::*;

use crate::console::Table;
use crate::svg::{Anchor, Font, Svg};
use ftsmc_sim::escape::{command_line, toml_comment};

/// Strings built from the characters that break formats, and any others.
fn hostile() -> impl Strategy<Value = String> {
    let piece = prop_oneof![
        Just("\n".to_string()),
        Just("\r\n".to_string()),
        Just("\"".to_string()),
        Just("'".to_string()),
        Just("]]>".to_string()),
        Just("<b>".to_string()),
        Just("&amp;".to_string()),
        Just("|".to_string()),
        Just("\\".to_string()),
        Just("#".to_string()),
        Just("seed = 4242".to_string()),
        Just("[limits]".to_string()),
        Just("\u{2028}".to_string()),
        Just("\u{FFFF}".to_string()),
        any::<char>().prop_map(String::from),
        "[\\x00-\\x1f\\x7f]".prop_map(|s: String| s),
        "\\PC{0,4}",
    ];
    proptest::collection::vec(piece, 0..12).prop_map(|v| v.concat())
}

/// `s` as the writers show it: control characters and line separators as
/// visible escapes.
fn visible(s: &str) -> String {
    s.chars()
        .flat_map(|c| {
            if c.is_control() || matches!(c, '\u{2028}' | '\u{2029}' | '\u{FFFE}' | '\u{FFFF}') {
                c.escape_default().collect::<Vec<_>>()
            } else {
                vec![c]
            }
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn a_toml_comment_adds_no_key(s in hostile()) {
        // As `ftsmc tune` writes its command line into a tuned file.
        let command = command_line(&["ftsmc", "tune", s.as_str(), "--out", s.as_str()]);
        let text = format!("# Made by: {}\n# {}\nname = \"x\"\n", toml_comment(&command), toml_comment(&s));
        let parsed: toml::Table = toml::from_str(&text).map_err(|e| TestCaseError::fail(format!("{e}: {text:?}")))?;
        prop_assert_eq!(parsed.keys().collect::<Vec<_>>(), vec!["name"]);
        prop_assert_eq!(text.lines().count(), 3);
        // A path as a TOML value (`extends = "<path>"`) reads back the same.
        let mut t = toml::Table::new();
        t.insert("extends".into(), toml::Value::String(s.clone()));
        let back: toml::Table = toml::from_str(&toml::to_string(&t).unwrap()).unwrap();
        prop_assert_eq!(back["extends"].as_str(), Some(s.as_str()));
    }

    #[test]
    fn a_csv_field_reads_back_the_same(s in hostile()) {
        // Every CSV writer of the CLI goes through csv::Writer, and every
        // file starts with its fixed header row: user text never opens a
        // file (where a reader drops a leading U+FEFF as a byte-order mark).
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(["a", "b"]).unwrap();
        w.write_record([s.as_str(), "x"]).unwrap();
        w.write_record(["y", s.as_str()]).unwrap();
        let bytes = w.into_inner().unwrap();
        let mut r = csv::ReaderBuilder::new().has_headers(true).from_reader(bytes.as_slice());
        let rows: Vec<csv::StringRecord> = r.records().collect::<Result<_, _>>().unwrap();
        prop_assert_eq!(rows.len(), 2);
        prop_assert_eq!(&rows[0][0], s.as_str());
        prop_assert_eq!(&rows[1][1], s.as_str());
    }

    #[test]
    fn a_markdown_row_keeps_its_columns(s in hostile()) {
        let mut t = Table::new([s.as_str(), "b"]);
        t.row(vec![s.clone(), "x".into()]);
        t.row(vec!["y".into(), s.clone()]);
        let md = t.render();
        prop_assert_eq!(md.lines().count(), 4, "{:?}", md);
        for line in md.lines() {
            // Cell separators: `|` not escaped by a backslash.
            let mut bars = 0;
            let mut escaped = false;
            for c in line.chars() {
                match c {
                    '\\' if !escaped => escaped = true,
                    '|' if !escaped => bars += 1,
                    _ => escaped = false,
                }
                if c != '\\' {
                    escaped = false;
                }
            }
            prop_assert_eq!(bars, 3, "{:?}", line);
        }
    }

    #[test]
    fn an_svg_stays_well_formed_with_the_text_as_written(s in hostile()) {
        let mut svg = Svg::new(100.0, 50.0, "px");
        svg.group(&s);
        svg.text(10.0, 10.0, &s, &Font::new(10.0, Anchor::Start));
        svg.end_group();
        let text = svg.finish();
        let doc = resvg::usvg::roxmltree::Document::parse(&text)
            .map_err(|e| TestCaseError::fail(format!("{e}: {text:?}")))?;
        let g = doc.descendants().find(|n| n.has_tag_name("g")).unwrap();
        let shown = visible(&s);
        prop_assert_eq!(g.attribute("class"), Some(shown.as_str()));
        let texts: Vec<_> = doc.descendants().filter(|n| n.has_tag_name("text")).collect();
        let elements = doc.descendants().filter(|n| n.is_element()).count();
        if s.is_empty() {
            prop_assert!(texts.is_empty());
        } else {
            prop_assert_eq!(texts.len(), 1);
            prop_assert_eq!(texts[0].text(), Some(shown.as_str()));
        }
        // svg, the background rect, g, and the text: nothing injected.
        prop_assert_eq!(elements, 3 + texts.len());
    }
}

/// The input proptest found: a field that is a lone U+FEFF. At the start
/// of a file a CSV reader takes it for a byte-order mark; after the header
/// row, where ftsmc's user text goes, it reads back as written.
#[test]
fn a_byte_order_mark_in_a_field_after_the_header_reads_back() {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(["a", "b"]).unwrap();
    w.write_record(["\u{feff}", "x"]).unwrap();
    let bytes = w.into_inner().unwrap();
    let mut r = csv::Reader::from_reader(bytes.as_slice());
    let rows: Vec<csv::StringRecord> = r.records().collect::<Result<_, _>>().unwrap();
    assert_eq!(&rows[0][0], "\u{feff}");
}
