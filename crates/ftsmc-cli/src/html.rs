//! `report.html`: one self-contained page of a result folder, written by
//! every command that writes results (`reproduce`, `run`, `montecarlo`,
//! `tune`, `merge`, …) through [`report`].
//!
//! The page holds the command's Markdown report (its tables, verdicts and
//! notes, converted by the small subset of Markdown ftsmc writes: headings,
//! pipe tables, lists, code blocks, paragraphs, `code`, **bold**, links),
//! the provenance of `summary.json`, every figure of the folder as inline
//! SVG, links to every CSV/JSON/TOML/Markdown file, and a 3-D replay of
//! the recorded flights (`report.js`: plain JavaScript on a `<canvas>`,
//! data embedded and decimated). Everything is inline — no network, no
//! CDN — so the page works offline and can be mailed as one file; print
//! CSS (`report.css`) hides the replay controls and keeps figures whole.
//!
//! Hand-written rather than a templating or Markdown crate: the page needs
//! only the subset above, and the escaping (text and double-quoted
//! attributes, `ftsmc_sim::escape::xml_text`, shared with the SVG writer)
//! is the whole of what a template engine would add.

use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufRead as _, BufReader};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use ftsmc_sim::escape::xml_text as escape;
use ftsmc_sim::run::Recording;

/// Points per flight in the replay at most (the recording is decimated evenly).
const REPLAY_POINTS: usize = 400;
/// Flights in the replay at most (the first ones in path order).
const REPLAY_RUNS: usize = 24;
/// SVG files larger than this are linked, not inlined, bytes.
const MAX_INLINE_SVG: u64 = 4 << 20;

const CSS: &str = include_str!("report.css");
const JS: &str = include_str!("report.js");

/// A relative path as a URL path (`/`-separated, each part percent-encoded
/// where it is not a plain file-name character).
fn href(rel: &Path) -> String {
    let mut out = String::new();
    for (i, part) in rel.iter().enumerate() {
        if i > 0 {
            out.push('/');
        }
        for b in part.to_string_lossy().bytes() {
            if b.is_ascii_alphanumeric() || b"-_.~".contains(&b) {
                out.push(b as char);
            } else {
                let _ = write!(out, "%{b:02X}");
            }
        }
    }
    out
}

// ------------------------------------------------------------ Markdown

/// `text` escaped for HTML line by line, its line ends kept as line ends
/// (for `<pre>`: [`escape`] alone would show each newline as a literal `\n`).
fn escape_lines(text: &str) -> String {
    text.split('\n').map(escape).collect::<Vec<_>>().join("\n")
}

/// The character a Markdown entity reference at the start of `s` stands
/// for (`&lt;`, `&gt;`, `&amp;`, `&quot;`, `&#NN;`: the ones
/// [`ftsmc_sim::escape::markdown_cell`] writes, and the decimal form), with
/// its length in bytes.
fn entity(s: &str) -> Option<(char, usize)> {
    let end = s.find(';').filter(|&e| e <= 10)?;
    let c = match &s[1..end] {
        "lt" => '<',
        "gt" => '>',
        "amp" => '&',
        "quot" => '"',
        n => char::from_u32(n.strip_prefix('#')?.parse().ok()?)?,
    };
    Some((c, end + 1))
}

/// Inline Markdown of one line: `code`, **bold**, [text](url), backslash
/// escapes of ASCII punctuation and entity references (CommonMark 0.31,
/// sections 2.4 and 2.5: `\|` is a `|`, `&lt;` a `<`); the rest escaped.
fn inline(s: &str) -> String {
    let mut out = String::new();
    let mut rest = s;
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix('\\') {
            if let Some(c) = r.chars().next().filter(char::is_ascii_punctuation) {
                out.push_str(&escape(&c.to_string()));
                rest = &r[1..];
                continue;
            }
        }
        if rest.starts_with('&') {
            if let Some((c, len)) = entity(rest) {
                out.push_str(&escape(&c.to_string()));
                rest = &rest[len..];
                continue;
            }
        }
        if let Some(r) = rest.strip_prefix('`') {
            if let Some(end) = r.find('`') {
                let _ = write!(out, "<code>{}</code>", escape(&r[..end]));
                rest = &r[end + 1..];
                continue;
            }
        }
        if let Some(r) = rest.strip_prefix("**") {
            if let Some(end) = r.find("**") {
                let _ = write!(out, "<strong>{}</strong>", inline(&r[..end]));
                rest = &r[end + 2..];
                continue;
            }
        }
        if let Some(r) = rest.strip_prefix('[') {
            if let Some(close) = r.find("](") {
                if let Some(end) = r[close + 2..].find(')') {
                    let text = &r[..close];
                    let url = &r[close + 2..close + 2 + end];
                    let _ = write!(out, "<a href=\"{}\">{}</a>", escape(url), inline(text));
                    rest = &r[close + 2 + end + 1..];
                    continue;
                }
            }
        }
        let c = rest.chars().next().unwrap_or(' ');
        out.push_str(&escape(&c.to_string()));
        rest = &rest[c.len_utf8()..];
    }
    out
}

/// The cells of a table row, split at every `|` not escaped by a
/// backslash (an escaped `\|` stays in its cell, still escaped, for [`inline`]).
fn table_cells(line: &str) -> Vec<String> {
    let t = line.trim();
    let t = t.strip_prefix('|').unwrap_or(t);
    let mut cells = Vec::new();
    let mut cell = String::new();
    let mut chars = t.chars();
    while let Some(c) = chars.next() {
        match c {
            '\\' => {
                cell.push(c);
                if let Some(n) = chars.next() {
                    cell.push(n);
                }
            }
            '|' => cells.push(std::mem::take(&mut cell).trim().to_string()),
            c => cell.push(c),
        }
    }
    if !cell.trim().is_empty() {
        cells.push(cell.trim().to_string());
    }
    cells
}

fn is_separator(line: &str) -> bool {
    let t = line.trim();
    t.starts_with('|') && t.chars().all(|c| matches!(c, '|' | '-' | ':' | ' '))
}

/// HTML of the Markdown subset ftsmc writes (module docs).
pub fn markdown(md: &str) -> String {
    let lines: Vec<&str> = md.lines().collect();
    let mut out = String::new();
    let mut para: Vec<&str> = Vec::new();
    let flush = |para: &mut Vec<&str>, out: &mut String| {
        if !para.is_empty() {
            let _ = writeln!(out, "<p>{}</p>", inline(&para.join(" ")));
            para.clear();
        }
    };
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        let t = line.trim_start();
        if t.starts_with("```") {
            flush(&mut para, &mut out);
            let mut body = Vec::new();
            i += 1;
            while i < lines.len() && !lines[i].trim_start().starts_with("```") {
                body.push(lines[i]);
                i += 1;
            }
            let _ = writeln!(out, "<pre><code>{}</code></pre>", escape_lines(&body.join("\n")));
            i += 1;
            continue;
        }
        if t.starts_with('|') && i + 1 < lines.len() && is_separator(lines[i + 1]) {
            flush(&mut para, &mut out);
            out.push_str("<div class=\"table\"><table>\n<thead><tr>");
            for c in table_cells(t) {
                let _ = write!(out, "<th>{}</th>", inline(&c));
            }
            out.push_str("</tr></thead>\n<tbody>\n");
            i += 2;
            while i < lines.len() && lines[i].trim_start().starts_with('|') {
                out.push_str("<tr>");
                for c in table_cells(lines[i]) {
                    let _ = write!(out, "<td>{}</td>", inline(&c));
                }
                out.push_str("</tr>\n");
                i += 1;
            }
            out.push_str("</tbody></table></div>\n");
            continue;
        }
        let hashes = t.chars().take_while(|&c| c == '#').count();
        if (1..=6).contains(&hashes) && t[hashes..].starts_with(' ') {
            flush(&mut para, &mut out);
            // The page title is <h1>; Markdown headings start at <h2>.
            let level = (hashes + 1).min(6);
            let _ = writeln!(out, "<h{level}>{}</h{level}>", inline(t[hashes..].trim()));
            i += 1;
            continue;
        }
        let bullet = t.strip_prefix("- ").or_else(|| t.strip_prefix("* "));
        if bullet.is_some() {
            flush(&mut para, &mut out);
            out.push_str("<ul>\n");
            while i < lines.len() {
                let t = lines[i].trim_start();
                let Some(item) = t.strip_prefix("- ").or_else(|| t.strip_prefix("* ")) else {
                    break;
                };
                let mut text = item.to_string();
                i += 1;
                // Continuation lines (indented, not a new item).
                while i < lines.len()
                    && lines[i].starts_with("  ")
                    && !lines[i].trim_start().starts_with("- ")
                    && !lines[i].trim().is_empty()
                {
                    text.push(' ');
                    text.push_str(lines[i].trim());
                    i += 1;
                }
                let _ = writeln!(out, "<li>{}</li>", inline(&text));
            }
            out.push_str("</ul>\n");
            continue;
        }
        if t.is_empty() {
            flush(&mut para, &mut out);
        } else {
            para.push(t);
        }
        i += 1;
    }
    flush(&mut para, &mut out);
    out
}

// ------------------------------------------------------------ folder

/// Files under `root` (hidden entries skipped), relative, sorted.
fn files(root: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let mut stack = vec![PathBuf::new()];
    while let Some(rel) = stack.pop() {
        let dir = root.join(&rel);
        for entry in std::fs::read_dir(&dir).with_context(|| format!("cannot list {}", dir.display()))? {
            let entry = entry?;
            let name = entry.file_name();
            if name.to_string_lossy().starts_with('.') {
                continue;
            }
            let path = rel.join(&name);
            if entry.file_type()?.is_dir() {
                stack.push(path);
            } else {
                out.push(path);
            }
        }
    }
    out.sort();
    Ok(out)
}

fn ext(p: &Path) -> String {
    p.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default()
}

/// An SVG document ready to inline: its XML prolog dropped and its ids
/// (clip paths) prefixed with `prefix`, so the figures of one page do not
/// share ids.
fn inline_svg(svg: &str, prefix: &str) -> String {
    let start = svg.find("<svg").unwrap_or(0);
    svg[start..].replace("id=\"", &format!("id=\"{prefix}")).replace("url(#", &format!("url(#{prefix}"))
}

/// One recorded flight for the replay: `t`, position, attitude, reference,
/// decimated to at most [`REPLAY_POINTS`]; `None` for a CSV without those
/// columns or with fewer than two rows. The file at `path` is streamed
/// twice, counting its rows and then decoding and parsing only the picked
/// ones (the others are skipped without a copy): a 200 s
/// flight at 100 Hz has 20,000 rows of ~50 numbers, and reading it whole
/// and parsing every number cost more than writing it.
fn replay_track(rel: &Path, path: &Path) -> std::io::Result<Option<String>> {
    let open = || File::open(path).map(BufReader::new);
    let eol = |l: &str| l.trim_end_matches(['\n', '\r']).len();
    let mut reader = open()?;
    let mut line = String::new();
    reader.read_line(&mut line)?;
    let header: Vec<&str> = line[..eol(&line)].split(',').map(str::trim).collect();
    let Some(columns) = ReplayColumns::find(&header) else {
        return Ok(None);
    };
    // The rows after the header (a last one without a line end counts),
    // skipped over without being copied or decoded.
    let mut n_rows = 0usize;
    while reader.skip_until(b'\n')? > 0 {
        n_rows += 1;
    }
    let Some(picks) = replay_picks(n_rows) else {
        return Ok(None);
    };
    let mut reader = open()?;
    let mut buffer = Vec::new();
    reader.read_until(b'\n', &mut buffer)?; // the header
    let mut rows: Vec<Vec<f64>> = Vec::with_capacity(picks.len());
    let mut next = picks.iter().peekable();
    for r in 0..n_rows {
        if next.peek() != Some(&&r) {
            reader.skip_until(b'\n')?;
            continue;
        }
        next.next();
        buffer.clear();
        reader.read_until(b'\n', &mut buffer)?;
        // Only the picked rows are decoded and parsed.
        let line = String::from_utf8_lossy(&buffer);
        let text = &line[..eol(&line)];
        rows.push(text.split(',').map(|v| v.trim().parse::<f64>().unwrap_or(f64::NAN)).collect());
    }
    Ok(Some(columns.track(rel, &rows)))
}

/// [`replay_track`] of the CSV a [`Recording`] writes
/// ([`Recording::write_csv`]), taken from the recording in memory instead
/// of the file: the same text, since every number of the CSV is written in
/// a form that parses back to its own bits (non-finite ones as `NaN`,
/// `inf`, `-inf`, which parse back too) and the replay rounds what it
/// parses. `ftsmc run` hands its recordings over, so a 20 MB CSV is not
/// read twice more to show 400 of its rows.
fn recorded_track(rel: &Path, recording: &Recording) -> Option<String> {
    let header: Vec<&str> = recording.names.iter().map(String::as_str).collect();
    let columns = ReplayColumns::find(&header)?;
    let picks = replay_picks(recording.len())?;
    let rows: Vec<Vec<f64>> =
        picks.iter().map(|&r| recording.columns.iter().map(|column| column[r]).collect()).collect();
    Some(columns.track(rel, &rows))
}

/// The rows the replay shows of `n_rows`: evenly spaced, at most about
/// [`REPLAY_POINTS`], the last one kept; `None` under two rows.
fn replay_picks(n_rows: usize) -> Option<Vec<usize>> {
    if n_rows < 2 {
        return None;
    }
    let step = n_rows.div_ceil(REPLAY_POINTS).max(1);
    let mut picks: Vec<usize> = (0..n_rows).step_by(step).collect();
    if picks.last() != Some(&(n_rows - 1)) {
        picks.push(n_rows - 1);
    }
    Some(picks)
}

/// Where the replay's columns sit in a recording's header.
struct ReplayColumns {
    /// `t`, `x`, `y`, `z`, `phi`, `theta`, `psi`.
    idx: Vec<usize>,
    /// `x_ref`, `y_ref`, `z_ref`, if all three are there.
    refs: Option<Vec<usize>>,
}

impl ReplayColumns {
    /// `None` without the time, position and attitude columns.
    fn find(header: &[&str]) -> Option<Self> {
        let col = |name: &str| header.iter().position(|h| *h == name);
        let need = ["t", "x", "y", "z", "phi", "theta", "psi"];
        let idx = need.iter().map(|n| col(n)).collect::<Option<Vec<usize>>>()?;
        let refs: Option<Vec<usize>> = ["x_ref", "y_ref", "z_ref"].iter().map(|n| col(n)).collect();
        Some(Self { idx, refs })
    }

    /// The replay's JSON of the picked `rows` (a missing cell is NaN),
    /// every number rounded to 1e-4 (`null` when not finite).
    fn track(&self, rel: &Path, rows: &[Vec<f64>]) -> String {
        let idx = &self.idx;
        let num = |v: f64| if v.is_finite() { format!("{}", (v * 1e4).round() / 1e4) } else { "null".to_string() };
        let series = |cols: &[usize]| -> String {
            let items: Vec<String> = rows
                .iter()
                .map(|row| {
                    let vals: Vec<String> =
                        cols.iter().map(|&c| num(row.get(c).copied().unwrap_or(f64::NAN))).collect();
                    format!("[{}]", vals.join(","))
                })
                .collect();
            format!("[{}]", items.join(","))
        };
        let t: Vec<String> = rows.iter().map(|row| num(row.get(idx[0]).copied().unwrap_or(f64::NAN))).collect();
        let name = rel.with_extension("").to_string_lossy().replace('\\', "/");
        format!(
            "{{\"name\":{},\"t\":[{}],\"p\":{},\"a\":{},\"r\":{}}}",
            serde_json::Value::String(name),
            t.join(","),
            series(&idx[1..4]),
            series(&idx[4..7]),
            self.refs.as_ref().map_or("null".to_string(), |r| series(r))
        )
    }
}

/// The provenance block of `summary.json`, if it has one.
fn provenance(root: &Path) -> Option<String> {
    let text = std::fs::read_to_string(root.join("summary.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    let p = v.get("provenance")?;
    serde_json::to_string_pretty(p).ok()
}

/// The page of the result folder being written at `root` (a staging
/// folder: every file written so far is on the page): `title`, the
/// command's `markdown` report, provenance, figures, replay and links.
pub fn report(root: &Path, title: &str, markdown_text: &str) -> Result<String> {
    report_with(root, title, markdown_text, &[])
}

/// [`report`], the replay of each CSV listed in `recorded` (its path
/// relative to `root`, the recording it was written from by
/// [`Recording::write_csv`]) taken from the recording in memory rather
/// than read back from the file: the same page, byte for byte.
pub fn report_with(
    root: &Path,
    title: &str,
    markdown_text: &str,
    recorded: &[(PathBuf, &Recording)],
) -> Result<String> {
    let all = files(root)?;
    let mut body = String::new();
    let figures: Vec<&PathBuf> = all.iter().filter(|p| ext(p) == "svg").collect();
    let data: Vec<&PathBuf> =
        all.iter().filter(|p| matches!(ext(p).as_str(), "csv" | "json" | "toml" | "md" | "png")).collect();
    let mut tracks = Vec::new();
    for rel in all.iter().filter(|p| ext(p) == "csv") {
        if tracks.len() >= REPLAY_RUNS {
            break;
        }
        let track = match recorded.iter().find(|(path, _)| path == rel) {
            Some((_, recording)) => recorded_track(rel, recording),
            None => replay_track(rel, &root.join(rel)).with_context(|| format!("cannot read {}", rel.display()))?,
        };
        if let Some(track) = track {
            tracks.push(track);
        }
    }

    // Contents.
    body.push_str("<nav class=\"toc\"><strong>Contents</strong> ");
    if !markdown_text.trim().is_empty() {
        body.push_str("<a href=\"#report\">report</a> · ");
    }
    if !tracks.is_empty() {
        body.push_str("<a href=\"#replay\">3-D replay</a> · ");
    }
    if !figures.is_empty() {
        let _ = write!(body, "<a href=\"#figures\">figures ({})</a> · ", figures.len());
    }
    body.push_str("<a href=\"#files\">files</a></nav>\n");

    if !markdown_text.trim().is_empty() {
        let _ = writeln!(body, "<section id=\"report\">\n{}</section>", markdown(markdown_text));
    }
    if let Some(p) = provenance(root) {
        let _ = writeln!(
            body,
            "<section id=\"provenance\"><h2>Provenance</h2><p>From <a href=\"summary.json\">summary.json</a>: \
             the scenario files flown and their SHA-256, the build and the machine.</p>\
             <pre><code>{}</code></pre></section>",
            escape_lines(&p)
        );
    }
    if !tracks.is_empty() {
        let _ = writeln!(
            body,
            "<section id=\"replay\"><h2>3-D replay</h2>\
             <p>The recorded flights in 3-D: the path flown (solid, in full up to the chosen time), the \
             reference (black, dashed) and the vehicle — a “+” of four arms rotated by its attitude \
             R = Rz(ψ) Ry(θ) Rx(φ), front arm red, the short blue line its thrust axis — at the time of the \
             slider (a link ending in #t=12.5 opens it at 12.5 s). Drag to rotate; the wheel zooms. Recordings decimated to at most {REPLAY_POINTS} points.</p>\
             <div class=\"replay-controls\"><label>flight <select id=\"replay-run\"></select></label> \
             <button id=\"replay-play\" type=\"button\">play</button> \
             <input id=\"replay-time\" type=\"range\" min=\"0\" max=\"1000\" value=\"1000\" aria-label=\"time\"> \
             <span id=\"replay-label\"></span></div>\
             <canvas id=\"replay-canvas\" width=\"960\" height=\"600\"></canvas>\
             <script type=\"application/json\" id=\"replay-data\">[{}]</script></section>",
            tracks.join(",").replace("</", "<\\/")
        );
    }
    if !figures.is_empty() {
        body.push_str("<section id=\"figures\"><h2>Figures</h2>\n");
        for (k, rel) in figures.iter().enumerate() {
            let path = root.join(rel);
            let size = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
            let name = rel.to_string_lossy().replace('\\', "/");
            let png = rel.with_extension("png");
            let png_link =
                if all.contains(&png) { format!(" · <a href=\"{}\">PNG</a>", href(&png)) } else { String::new() };
            let _ = write!(body, "<figure id=\"fig-{k}\">");
            if size <= MAX_INLINE_SVG {
                let svg = std::fs::read_to_string(&path).with_context(|| format!("cannot read {}", path.display()))?;
                body.push_str(&inline_svg(&svg, &format!("f{k}-")));
            }
            let _ = writeln!(
                body,
                "<figcaption>{} — <a href=\"{}\">SVG</a>{png_link}</figcaption></figure>",
                escape(&name),
                href(rel)
            );
        }
        body.push_str("</section>\n");
    }
    body.push_str("<section id=\"files\"><h2>Files</h2><ul class=\"files\">\n");
    for rel in &data {
        let _ = writeln!(body, "<li><a href=\"{}\">{}</a></li>", href(rel), escape(&rel.to_string_lossy()));
    }
    body.push_str("</ul></section>\n");

    let mut page = String::with_capacity(body.len() + CSS.len() + JS.len() + 1024);
    let _ = write!(
        page,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>{t}</title>\n<style>\n{CSS}</style>\n\
         <script>\n// Errors of this page's scripts are written into #page-errors (read by the browser test).\n\
         window.pageErrors = [];\nwindow.addEventListener('error', function (e) {{\n  \
         window.pageErrors.push(String(e.message || e));\n  \
         var el = document.getElementById('page-errors');\n  if (el) el.textContent = window.pageErrors.join('\\n');\n}});\n\
         </script>\n</head>\n<body>\n<header><h1>{t}</h1>\
         <p class=\"generated\">Written by ftsmc {v}. Offline page: figures, data and scripts are inline; \
         the links open the files of this folder.</p></header>\n<main>\n{body}</main>\n\
         <pre id=\"page-errors\" class=\"page-errors\"></pre>\n<script>\n{JS}</script>\n</body>\n</html>\n",
        t = escape(title),
        v = env!("CARGO_PKG_VERSION"),
    );
    Ok(page)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markdown_tables_headings_and_escaping() {
        let html = markdown(
            "# Title <x>\n\nSome `a<b` and **bold** [link](beyond/report.md).\n\n| a | b |\n|---|---|\n| 1 | — |\n\n- one\n- two\n",
        );
        assert!(html.contains("<h2>Title &lt;x&gt;</h2>"), "{html}");
        assert!(html.contains("<code>a&lt;b</code>") && html.contains("<strong>bold</strong>"), "{html}");
        assert!(html.contains("<a href=\"beyond/report.md\">link</a>"), "{html}");
        assert!(html.contains("<th>a</th><th>b</th>") && html.contains("<td>1</td><td>—</td>"), "{html}");
        assert!(html.contains("<li>one</li>\n<li>two</li>"), "{html}");
    }

    /// The text a browser shows of `html`: tags removed, entities decoded once.
    fn visible_text(html: &str) -> String {
        let mut text = String::new();
        let mut in_tag = false;
        for c in html.chars() {
            match c {
                '<' => in_tag = true,
                '>' if in_tag => in_tag = false,
                c if !in_tag => text.push(c),
                _ => {}
            }
        }
        text.replace("&lt;", "<").replace("&gt;", ">").replace("&quot;", "\"").replace("&amp;", "&")
    }

    /// A ranking `A < B < C` reads as written on the console (the Markdown
    /// table) and on the page (its HTML), with no entity shown literally; a
    /// cell that could be a tag still cannot become one.
    #[test]
    fn a_ranking_reads_as_written_on_the_console_and_the_page() {
        let mut t = crate::console::Table::new(["state", "ranking ours"]);
        t.row(vec!["x".into(), "FTAFTSMC < TSM-STA < RANFTSMC".into()]);
        t.row(vec!["y".into(), "a|b <script>alert(1)</script> & &amp;".into()]);
        let md = t.render();
        assert!(md.contains("FTAFTSMC < TSM-STA < RANFTSMC") && !md.contains("&lt; "), "{md}");
        let html = markdown(&md);
        assert!(!html.contains("<script>"), "{html}");
        let text = visible_text(&html);
        assert!(text.contains("FTAFTSMC < TSM-STA < RANFTSMC"), "{text}");
        assert!(text.contains("a|b <script>alert(1)</script> & &amp;"), "{text}");
        assert!(!text.contains("&lt;") && !text.contains("\\|"), "{text}");
    }

    /// The provenance block is the pretty JSON of `summary.json`, one key a
    /// line: its line ends are line ends, not a literal `\n`.
    #[test]
    fn the_provenance_block_keeps_its_line_ends() {
        let dir = std::env::temp_dir().join(format!("ftsmc-prov-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("summary.json"), r#"{"provenance": {"seed": 1, "git_commit": "abc"}}"#).unwrap();
        let page = report(&dir, "t", "```\nline 1\nline 2\n```\n").unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        let block = page.split("<section id=\"provenance\">").nth(1).unwrap().split("</section>").next().unwrap();
        let text = visible_text(block);
        assert!(!text.contains("\\n"), "{text}");
        assert!(text.contains("\n  \"git_commit\": \"abc\"") && text.contains("\n  \"seed\": 1"), "{text}");
        assert!(page.contains("<pre><code>line 1\nline 2</code></pre>"), "{page}");
    }

    /// Rows are counted by their line ends; a last row without one counts,
    /// and a file of one row gives no replay.
    #[test]
    fn replay_counts_a_last_row_without_a_line_end() {
        let dir = std::env::temp_dir().join(format!("ftsmc-replay-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let head = "t,x,y,z,phi,theta,psi\n";
        let track = |body: &str| {
            let path = dir.join("a.csv");
            std::fs::write(&path, format!("{head}{body}")).unwrap();
            replay_track(Path::new("a.csv"), &path).unwrap()
        };
        let two = track("0,1,2,3,0,0,0\n0.5,4,5,6,0,0,0").expect("two rows");
        let one = track("0,1,2,3,0,0,0\n");
        let three = track("0,1,2,3,0,0,0\n0.5,4,5,6,0,0,0\n1,7,8,9,0,0,0\n").expect("three rows");
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(two.contains("\"t\":[0,0.5]") && two.contains("[4,5,6]"), "{two}");
        assert!(one.is_none());
        assert!(three.contains("\"t\":[0,0.5,1]"), "{three}");
    }

    /// The replay taken from a recording in memory is the replay read back
    /// from the CSV it writes, whatever its numbers.
    #[test]
    fn replay_from_a_recording_is_the_replay_of_its_csv() {
        let dir = std::env::temp_dir().join(format!("ftsmc-replay-mem-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let names = ["t", "x", "y", "z", "phi", "theta", "psi", "x_ref", "y_ref", "z_ref", "extra"];
        let mut recording = Recording::with_columns(names.iter().map(|n| n.to_string()).collect());
        let odd = [
            0.0,
            -0.0,
            1e-300,
            -5e-324,
            1.2e16,
            0.1 + 0.2,
            12345.67895,
            -0.00005,
            0.00005,
            2.5e-5,
            1e15,
            1e-5,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MAX,
            f64::MIN_POSITIVE,
            0.333333333333333,
        ];
        let mut state = 0x9e3779b97f4a7c15u64;
        for (rows, path) in [(1500usize, "a.csv"), (2, "b.csv"), (1, "c.csv"), (401, "d.csv")] {
            recording.columns.iter_mut().for_each(Vec::clear);
            for r in 0..rows {
                let row: Vec<f64> = (0..names.len())
                    .map(|c| {
                        state ^= state << 13;
                        state ^= state >> 7;
                        state ^= state << 17;
                        match state % 4 {
                            0 => odd[(state >> 8) as usize % odd.len()],
                            1 => f64::from_bits(state >> 2),
                            2 => (state >> 11) as f64 / (1u64 << 53) as f64 * 20.0 - 10.0,
                            _ => r as f64 * 0.01 + c as f64,
                        }
                    })
                    .collect();
                recording.push_row(&row);
            }
            let file = dir.join(path);
            std::fs::write(&file, recording.to_csv()).unwrap();
            let rel = Path::new(path);
            assert_eq!(recorded_track(rel, &recording), replay_track(rel, &file).unwrap(), "{path}");
            assert_eq!(recorded_track(rel, &recording).is_some(), rows >= 2);
        }
        // The recording now holds d.csv's rows: the page with them from
        // memory is the page read from the files.
        let page = report(&dir, "t", "").unwrap();
        assert_eq!(report_with(&dir, "t", "", &[(PathBuf::from("d.csv"), &recording)]).unwrap(), page);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn page_inlines_figures_with_unique_ids_and_embeds_the_replay() {
        let dir = std::env::temp_dir().join(format!("ftsmc-html-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("figs")).unwrap();
        let svg = r##"<svg xmlns="http://www.w3.org/2000/svg"><clipPath id="c1"><rect/></clipPath><path clip-path="url(#c1)"/></svg>"##;
        std::fs::write(dir.join("figs/a.svg"), svg).unwrap();
        std::fs::write(dir.join("figs/b.svg"), svg).unwrap();
        let mut csv = String::from("t,x,y,z,phi,theta,psi,x_ref,y_ref,z_ref\n");
        for k in 0..1000 {
            let t = k as f64 * 0.01;
            let _ = writeln!(csv, "{t},{},0,1,0.1,0,0,1,0,1", ftsmc_core::math::sin(t));
        }
        std::fs::write(dir.join("ftaftsmc.csv"), csv).unwrap();
        std::fs::write(dir.join("summary.json"), r#"{"provenance": {"sha256": "ab"}}"#).unwrap();
        let page = report(&dir, "run <paper-scenario-1>", "| k | v |\n|---|---|\n| ise | — |\n").unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(page.contains("<title>run &lt;paper-scenario-1&gt;</title>"));
        assert!(page.contains("id=\"f0-c1\"") && page.contains("url(#f1-c1)") && !page.contains("id=\"c1\""));
        assert!(page.contains("<td>ise</td><td>—</td>"));
        assert!(page.contains("\"name\":\"ftaftsmc\"") && page.contains("id=\"replay-canvas\""));
        let data = page.split("id=\"replay-data\">").nth(1).unwrap().split("</script>").next().unwrap();
        let parsed: serde_json::Value = serde_json::from_str(data).unwrap();
        let t = parsed[0]["t"].as_array().unwrap();
        assert!(t.len() <= REPLAY_POINTS + 1 && t.len() > 300, "{}", t.len());
        // Every third row of the 1,000 (at most REPLAY_POINTS), the last one kept.
        let times: Vec<f64> = t.iter().map(|v| v.as_f64().unwrap()).collect();
        assert_eq!((times[0], times[1], *times.last().unwrap(), times.len()), (0.0, 0.03, 9.99, 334));
        let x = parsed[0]["p"][1][0].as_f64().unwrap();
        assert_eq!(x, (ftsmc_core::math::sin(0.03) * 1e4).round() / 1e4);
        assert!(page.contains("&quot;sha256&quot;: &quot;ab&quot;") && page.contains("<a href=\"summary.json\">"));
        assert!(!page.contains("src=\"http") && !page.contains("href=\"http"), "no external resources");
    }
}
