//! What the commands print on the console: aligned Markdown tables, numbers
//! in table form and the progress bar over simulated control steps. Shared
//! by every command, so no command module imports another for them.

use std::fmt::Write as _;

use ftsmc_sim::escape::markdown_cell;
use indicatif::{ProgressBar, ProgressStyle};

/// A progress bar over `total` simulated control steps (on stderr; hidden
/// when stderr is not a terminal).
pub fn steps_bar(total: u64, flights: u64) -> ProgressBar {
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template(&format!(
            "{{spinner}} [{{elapsed_precise}}] {{bar:30}} {{human_pos}}/{{human_len}} control steps of {flights} flight{} ({{percent}} %, eta {{eta}})",
            if flights == 1 { "" } else { "s" }
        ))
        .expect("valid template"),
    );
    bar
}

/// Print `text` on stdout and flush at once, so a table reaches a pipe or
/// a file as soon as it is computed, not when the command ends.
pub fn print_now(text: &str) {
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{text}");
    let _ = out.flush();
}

/// Four decimals, or scientific notation for small non-zero values (below
/// 1e-3) and large ones (1e6 and above); `—` for NaN (a metric that does
/// not apply, e.g. the RMS error of a gain set none of whose runs completed).
pub fn num(v: f64) -> String {
    if v.is_nan() {
        return "—".to_string();
    }
    if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e6) {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
    }
}

/// A Markdown table with every column padded to its widest cell, so it
/// reads aligned on a console too.
pub struct Table {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Table {
    /// A table with these column headers.
    pub fn new<S: Into<String>>(header: impl IntoIterator<Item = S>) -> Self {
        Self { header: header.into_iter().map(Into::into).collect(), rows: Vec::new() }
    }

    /// Add a row (as many cells as headers).
    pub fn row(&mut self, cells: Vec<String>) {
        debug_assert_eq!(cells.len(), self.header.len());
        self.rows.push(cells);
    }

    /// The Markdown text, one line per row, each ending in a newline (cells
    /// escaped by [`markdown_cell`]: a `|` inside a cell is `\|`, a newline
    /// `\n`, so every row keeps its columns).
    pub fn render(&self) -> String {
        let width = |s: &str| s.chars().count();
        let escape = |cells: &[String]| cells.iter().map(|c| markdown_cell(c)).collect::<Vec<_>>();
        let header = escape(&self.header);
        let rows: Vec<Vec<String>> = self.rows.iter().map(|r| escape(r)).collect();
        let widths: Vec<usize> = (0..header.len())
            .map(|i| rows.iter().map(|r| width(&r[i])).chain([width(&header[i]), 3]).max().unwrap_or(3))
            .collect();
        let line = |cells: &[String]| {
            let mut l = String::from("|");
            for (cell, w) in cells.iter().zip(&widths) {
                let _ = write!(l, " {cell}{} |", " ".repeat(w - width(cell)));
            }
            l.push('\n');
            l
        };
        let mut md = line(&header);
        md.push('|');
        for w in &widths {
            let _ = write!(md, "{}|", "-".repeat(w + 2));
        }
        md.push('\n');
        for r in &rows {
            md.push_str(&line(r));
        }
        md
    }
}
