//! `ftsmc merge DIR... [--out DIR]`: join the shard folders written by
//! `ftsmc montecarlo --shard K/N` into the result the unsharded batch
//! writes.
//!
//! Each shard folder holds its block of runs (`runs.csv`, contiguous run
//! indices, see [`ftsmc_sim::batch::shard`]), the resolved `scenario.toml`
//! and a `summary.json` with a `shard` object (`index`, `count`,
//! `first_run`, `end_run`, `runs_csv_sha256`). Every file is read only if
//! it is a regular file within a size limit ([`crate::bounded_read`]); the
//! rows must have the SHA-256 the shard recorded, and a completed run's
//! metrics must be finite. The merge checks that the shards are one
//! campaign — same `scenario.toml` (SHA-256), master seed, run count,
//! controllers, shard count N and `runs.csv` columns — and that every shard
//! 1..N is there exactly once and holds exactly its runs; otherwise it
//! stops with an error naming the shard. It then writes `runs.csv` (the
//! shards' rows in run order: byte-identical to the unsharded one),
//! `scenario.toml`, and `summary.json`, whose statistics are recomputed from
//! the merged rows by the same code as the unsharded batch's
//! ([`summarize_outcomes_at`]); only its `provenance` differs: it records the
//! merge and lists the shards (`merged_from`).

use std::ops::Range;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use ftsmc_sim::batch::montecarlo::{summarize_outcomes_at, RowOutcome, SAMPLED_COLUMNS};
use ftsmc_sim::batch::shard::Shard;
use ftsmc_sim::scenario::Scenario;
use serde_json::{json, Map, Value};

use crate::args::{ConfidenceArgs, OutputArgs};
use crate::bounded_read::{read_limited, MAX_RUNS_CSV_BYTES, MAX_SHARD_TEXT_BYTES};
use crate::campaign::{shard_json, tables, write_ise_boxplots};
use crate::output::{provenance, sha256_hex, ResultDir, ScenarioFile};

/// Arguments of `ftsmc merge`.
#[derive(clap::Args)]
#[command(mut_arg("out", |a| a.default_value("results/montecarlo").help("Parent folder: the merged result goes to `OUT/<scenario name>/`")))]
pub struct Args {
    /// Shard folders (all N of one campaign, any order).
    #[arg(required = true, value_name = "DIR")]
    shards: Vec<PathBuf>,
    /// `--out`, `--no-figures` (the box-plot figure).
    #[command(flatten)]
    output: OutputArgs,
    /// `--confidence` of every interval in the tables and summary.json (recorded there).
    #[command(flatten)]
    confidence: ConfidenceArgs,
}

/// Runs `ftsmc merge`.
pub fn run(args: Args) -> Result<()> {
    let confidence = args.confidence.checked()?;
    merge(&args.shards, &args.output.out, args.output.figures(), confidence)
}

/// One shard folder, read and checked on its own.
struct ShardFolder {
    dir: PathBuf,
    shard: Shard,
    runs: u64,
    master_seed: u64,
    scenario_name: String,
    scenario_bytes: Vec<u8>,
    scenario_sha256: String,
    controllers: Vec<String>,
    provenance: Value,
    header: csv::StringRecord,
    rows: Vec<csv::StringRecord>,
    range: Range<u64>,
}

fn u64_field(summary: &Value, path: &[&str], dir: &Path) -> Result<u64> {
    let mut v = summary;
    for key in path {
        v = &v[key];
    }
    v.as_u64().with_context(|| {
        format!("shard `{}`: summary.json has no non-negative integer `{}`", dir.display(), path.join("."))
    })
}

fn read_shard(dir: &Path) -> Result<ShardFolder> {
    let shown = dir.display();
    let summary_path = dir.join("summary.json");
    let text = read_limited(&summary_path, MAX_SHARD_TEXT_BYTES, &format!("shard `{shown}`: summary.json"))?;
    let text = String::from_utf8(text).with_context(|| format!("shard `{shown}`: summary.json is not UTF-8"))?;
    let summary: Value =
        serde_json::from_str(&text).with_context(|| format!("shard `{shown}`: summary.json is not valid JSON"))?;
    if !summary["shard"].is_object() {
        bail!(
            "`{shown}` is not a shard folder: its summary.json has no `shard` object (shards are written by `ftsmc montecarlo --shard K/N`)"
        );
    }
    let index = u64_field(&summary, &["shard", "index"], dir)?;
    let count = u64_field(&summary, &["shard", "count"], dir)?;
    let first = u64_field(&summary, &["shard", "first_run"], dir)?;
    let end = u64_field(&summary, &["shard", "end_run"], dir)?;
    let runs = u64_field(&summary, &["runs"], dir)?;
    let master_seed = u64_field(&summary, &["master_seed"], dir)?;
    let shard = Shard::new(index, count).with_context(|| format!("shard `{shown}`"))?;
    let range = shard.range(runs).with_context(|| format!("shard `{shown}`"))?;
    if range != (first..end) {
        bail!("shard `{shown}`: holds runs {first}..{end}, but shard {shard} of {runs} runs is runs {range:?}");
    }

    let scenario_bytes =
        read_limited(&dir.join("scenario.toml"), MAX_SHARD_TEXT_BYTES, &format!("shard `{shown}`: scenario.toml"))?;
    let scenario_sha256 = sha256_hex(&scenario_bytes);
    let recorded = summary["provenance"]["scenario_sha256"].as_str().unwrap_or("");
    if recorded != scenario_sha256 {
        bail!(
            "shard `{shown}`: scenario.toml has sha256 {scenario_sha256}, but summary.json records {recorded:?} (the file was changed after the shard was flown)"
        );
    }
    let scenario_text = String::from_utf8(scenario_bytes.clone())
        .with_context(|| format!("shard `{shown}`: scenario.toml is not UTF-8"))?;
    let scenario = Scenario::from_toml_str(&scenario_text, &dir.join("scenario.toml").display().to_string())
        .with_context(|| format!("shard `{shown}`"))?;
    if scenario.seed != master_seed {
        bail!("shard `{shown}`: scenario.toml has seed {}, summary.json master_seed {master_seed}", scenario.seed);
    }

    let csv_path = dir.join("runs.csv");
    let csv_bytes = read_limited(&csv_path, MAX_RUNS_CSV_BYTES, &format!("shard `{shown}`: runs.csv"))?;
    let mut reader = csv::Reader::from_reader(csv_bytes.as_slice());
    let header = reader.headers().with_context(|| format!("shard `{shown}`: runs.csv has no header"))?.clone();
    let rows = reader
        .records()
        .collect::<std::result::Result<Vec<_>, _>>()
        .with_context(|| format!("shard `{shown}`: runs.csv is not valid CSV"))?;
    // Exactly its runs, each with every controller, in (run, controller) order.
    let controllers = scenario.controllers.clone();
    let expected = (end - first) as usize * controllers.len();
    let mut expect = (first..end).flat_map(|run| controllers.iter().map(move |c| (run, c)));
    for (n, row) in rows.iter().enumerate() {
        let got = (row.get(0).unwrap_or(""), row.get(2).unwrap_or(""));
        match expect.next() {
            Some((run, c)) if got.0 == run.to_string() && got.1 == c => {}
            Some((run, c)) => bail!(
                "shard `{shown}`: runs.csv row {} is run {} of `{}`, expected run {run} of `{c}` (a shard holds runs {first}..{end} with every controller)",
                n + 1,
                got.0,
                got.1
            ),
            None => bail!("shard `{shown}`: runs.csv has {} rows, expected {expected}", rows.len()),
        }
    }
    if rows.len() != expected {
        bail!(
            "shard `{shown}`: runs.csv has {} rows, expected {expected} (incomplete shard: fly it again)",
            rows.len()
        );
    }
    // Whole rows, but are they the shard's?
    let csv_sha256 = sha256_hex(&csv_bytes);
    let recorded = summary["shard"]["runs_csv_sha256"].as_str().unwrap_or("");
    if recorded != csv_sha256 {
        bail!(
            "shard `{shown}`: runs.csv has sha256 {csv_sha256}, but summary.json records {recorded:?} (the rows were changed after the shard was flown, or it was written by an ftsmc that recorded no digest: fly it again)"
        );
    }
    Ok(ShardFolder {
        dir: dir.to_path_buf(),
        shard,
        runs,
        master_seed,
        scenario_name: scenario.name.clone(),
        scenario_bytes,
        scenario_sha256,
        controllers,
        provenance: summary["provenance"].clone(),
        header,
        rows,
        range,
    })
}

/// Check that `shards` are the whole of one campaign: same campaign, no
/// shard repeated, none missing. Returns them in shard order.
fn check_campaign(mut shards: Vec<ShardFolder>) -> Result<Vec<ShardFolder>> {
    let first = &shards[0];
    for s in &shards[1..] {
        let foreign = |what: &str, theirs: String, ours: String| {
            anyhow::anyhow!(
                "shard `{}` is foreign to `{}`: its {what} is {theirs}, not {ours}",
                s.dir.display(),
                first.dir.display()
            )
        };
        if s.master_seed != first.master_seed {
            return Err(foreign("master seed", s.master_seed.to_string(), first.master_seed.to_string()));
        }
        if s.runs != first.runs {
            return Err(foreign("run count", s.runs.to_string(), first.runs.to_string()));
        }
        if s.controllers != first.controllers {
            return Err(foreign("controller list", s.controllers.join(","), first.controllers.join(",")));
        }
        if s.shard.count != first.shard.count {
            return Err(foreign("shard count N", s.shard.count.to_string(), first.shard.count.to_string()));
        }
        if s.scenario_sha256 != first.scenario_sha256 {
            return Err(foreign("scenario.toml (sha256)", s.scenario_sha256.clone(), first.scenario_sha256.clone()));
        }
        if s.header != first.header {
            return Err(foreign(
                "runs.csv header",
                s.header.iter().collect::<Vec<_>>().join(","),
                "the first's".into(),
            ));
        }
        for key in ["ftsmc_version", "git_commit"] {
            if s.provenance[key] != first.provenance[key] {
                eprintln!(
                    "warning: shard `{}` was written by ftsmc {} {}, `{}` by {} {}: check the numbers agree",
                    s.dir.display(),
                    s.provenance["ftsmc_version"],
                    s.provenance["git_commit"],
                    first.dir.display(),
                    first.provenance["ftsmc_version"],
                    first.provenance["git_commit"]
                );
                break;
            }
        }
    }
    shards.sort_by_key(|s| s.shard.index);
    for pair in shards.windows(2) {
        if pair[0].shard == pair[1].shard {
            bail!(
                "shard {} is given twice: `{}` and `{}`",
                pair[0].shard,
                pair[0].dir.display(),
                pair[1].dir.display()
            );
        }
    }
    let count = shards[0].shard.count;
    let missing: Vec<Shard> = (1..=count)
        .filter(|k| !shards.iter().any(|s| s.shard.index == *k))
        .map(|k| Shard { index: k, count })
        .collect();
    if !missing.is_empty() {
        let names: Vec<String> = missing.iter().take(8).map(|k| k.to_string()).collect();
        bail!(
            "{} of {count} shards missing: {}{} (fly them with `ftsmc montecarlo … --shard K/{count}`; expected folders like `{}`)",
            missing.len(),
            names.join(", "),
            if missing.len() > 8 { ", …" } else { "" },
            missing[0].folder_name(&shards[0].scenario_name)
        );
    }
    Ok(shards)
}

/// A `runs.csv` cell as a number (empty: `NaN`, as a metric that does not apply).
fn number(cell: &str, dir: &Path, row: usize, column: &str) -> Result<f64> {
    if cell.is_empty() {
        return Ok(f64::NAN);
    }
    cell.parse::<f64>().with_context(|| {
        format!("shard `{}`: runs.csv row {row}, column `{column}`: `{cell}` is not a number", dir.display())
    })
}

fn boolean(cell: &str, dir: &Path, row: usize, column: &str) -> Result<bool> {
    match cell {
        "true" => Ok(true),
        "false" => Ok(false),
        _ => bail!("shard `{}`: runs.csv row {row}, column `{column}`: `{cell}` is not true/false", dir.display()),
    }
}

/// Merge `dirs` (the N shard folders of one campaign) into
/// `out/<scenario name>/`: `runs.csv`, `scenario.toml`, `summary.json` and,
/// with `figures`, the ISE box plots.
pub fn merge(dirs: &[PathBuf], out: &Path, figures: bool, confidence: f64) -> Result<()> {
    let shards = dirs.iter().map(|d| read_shard(d)).collect::<Result<Vec<_>>>()?;
    let shards = check_campaign(shards)?;
    let first = &shards[0];
    let folder = out.join(&first.scenario_name);
    if let Some(s) = shards.iter().find(|s| s.dir.canonicalize().ok() == folder.canonicalize().ok()) {
        bail!("--out would replace shard `{}` with the merged result: choose another --out", s.dir.display());
    }
    // The merged folder is the Monte Carlo result itself: owned as `montecarlo`
    // writes it (see output.rs), so a later `ftsmc montecarlo` into it replaces it.
    let dir = ResultDir::begin(&folder, "montecarlo")?;

    // runs.csv: the rows of shards 1..N in order, written as the batch writes them.
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(&first.header)?;
    for s in &shards {
        for row in &s.rows {
            w.write_record(row)?;
        }
    }
    let csv_bytes = w.into_inner().map_err(|e| anyhow::anyhow!("csv: {e}"))?;
    dir.write("runs.csv", &csv_bytes)?;
    dir.write("scenario.toml", &first.scenario_bytes)?;

    // The rows as the summary reads them.
    let names: Vec<&str> = first.header.iter().collect();
    let tail = ["completed", "success", "crashed"];
    let metrics_from = 5 + SAMPLED_COLUMNS.len();
    // The robustness-margin columns follow the tail; the summary does not read them.
    let margin = ftsmc_sim::batch::runs_table::MARGIN_COLUMNS;
    let end = if names.ends_with(&margin) { names.len() - margin.len() } else { names.len() };
    if end < metrics_from + ftsmc_sim::batch::runs_table::STATS_COLUMNS.len() + tail.len()
        || names[end - 3..end] != tail
        || names[2] != "controller"
    {
        bail!("shard `{}`: runs.csv columns are not those of `ftsmc montecarlo`", first.dir.display());
    }
    // The flight-statistics columns sit between the metrics and the tail;
    // summary.json summarises the metrics only.
    let stats = ftsmc_sim::batch::runs_table::STATS_COLUMNS.len();
    let metric_columns = metrics_from..end - 3 - stats;
    let mut outcomes = Vec::with_capacity(shards.iter().map(|s| s.rows.len()).sum());
    let mut completed_ise: Vec<(String, [f64; 4])> = Vec::new();
    let ise_at: Vec<usize> = ["ise_x", "ise_y", "ise_z", "ise_psi"]
        .iter()
        .map(|n| names.iter().position(|c| c == n).unwrap_or(usize::MAX))
        .collect();
    for s in &shards {
        for (k, row) in s.rows.iter().enumerate() {
            let cell = |i: usize| row.get(i).unwrap_or("");
            let line = k + 2;
            let metrics = metric_columns
                .clone()
                .map(|i| Ok((names[i].to_string(), number(cell(i), &s.dir, line, names[i])?)))
                .collect::<Result<Vec<_>>>()?;
            let n = end;
            let outcome = RowOutcome {
                controller: cell(2).to_string(),
                completed: boolean(cell(n - 3), &s.dir, line, "completed")?,
                success: boolean(cell(n - 2), &s.dir, line, "success")?,
                crashed: boolean(cell(n - 1), &s.dir, line, "crashed")?,
                metrics,
            };
            if outcome.completed {
                // A completed flight has finite metrics; only a settling time
                // (`NaN`: not settled) and the error after steady state
                // (empty: not reached) may have none.
                if let Some((name, v)) = outcome.metrics.iter().find(|(name, v)| {
                    !v.is_finite()
                        && !(v.is_nan() && (name.starts_with("settling_time_") || name.starts_with("max_error_after_")))
                }) {
                    bail!(
                        "shard `{}`: runs.csv row {line}, column `{name}`: a completed run with the value {} (a completed run's metrics are finite)",
                        s.dir.display(),
                        crate::output::format_number(*v)
                    );
                }
                let value = |i: usize| {
                    if i == usize::MAX {
                        f64::NAN
                    } else {
                        number(cell(i), &s.dir, line, "ise").unwrap_or(f64::NAN)
                    }
                };
                completed_ise.push((
                    outcome.controller.clone(),
                    [value(ise_at[0]), value(ise_at[1]), value(ise_at[2]), value(ise_at[3])],
                ));
            }
            outcomes.push(outcome);
        }
    }
    let summaries = summarize_outcomes_at(&outcomes, &first.controllers, confidence);
    let mut per_controller = Map::new();
    for (name, s) in &summaries {
        per_controller.insert(name.clone(), serde_json::to_value(s)?);
    }
    let file =
        ScenarioFile { file: "scenario.toml".into(), sha256: first.scenario_sha256.clone(), seed: first.master_seed };
    let mut prov = provenance(&[file]);
    prov["merged_from"] = Value::Array(
        shards
            .iter()
            .map(|s| {
                json!({
                    "folder": s.dir.display().to_string(),
                    "shard": shard_json(s.shard, &s.range),
                    "provenance": s.provenance,
                })
            })
            .collect(),
    );
    let summary = json!({
        "scenario": first.scenario_name,
        "runs": first.runs,
        "master_seed": first.master_seed,
        "confidence": confidence,
        "controllers": Value::Object(per_controller),
        "provenance": prov,
    });
    dir.write("summary.json", serde_json::to_string_pretty(&summary)?.as_bytes())?;
    if figures {
        let completed: Vec<(&str, [f64; 4])> = completed_ise.iter().map(|(c, v)| (c.as_str(), *v)).collect();
        let title = format!("{} runs of {}", first.runs, first.scenario_name);
        write_ise_boxplots(&title, &first.controllers, &summaries, &completed, &dir.path().join("montecarlo-ise"))?;
    }
    let md = format!(
        "Monte Carlo: {} × {} runs of {} (master seed {}), merged from {} shards; every run's row is in [runs.csv](runs.csv).\n\n{}\n",
        first.controllers.len(),
        first.runs,
        first.scenario_name,
        first.master_seed,
        shards.len(),
        tables(&summaries, confidence)
    );
    let html = crate::html::report(dir.path(), &format!("ftsmc merge {}", first.scenario_name), &md)?;
    dir.write("report.html", html.as_bytes())?;
    dir.commit()?;

    println!(
        "Monte Carlo: {} × {} runs of {} (seed {}), merged from {} shards\n",
        first.controllers.len(),
        first.runs,
        first.scenario_name,
        first.master_seed,
        shards.len()
    );
    println!("{}", tables(&summaries, confidence));
    println!(
        "\nwrote {}/ (runs.csv, summary.json, scenario.toml, report.html{})",
        folder.display(),
        if figures { ", montecarlo-ise.{svg,png}" } else { "" }
    );
    Ok(())
}
