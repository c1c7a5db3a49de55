//! `ftsmc tune-tsm-sta`: rerun the documented TSM-STA gain procedure
//! (`ftsmc_sim::analysis::tuning::tune_tsm_sta`: match RANFTSMC's
//! scenario-1 settling times) and print the gains as TOML.

use anyhow::Result;

use crate::args::{load_scenario_with_limits, SetArgs};

/// Arguments of `ftsmc tune-tsm-sta`.
#[derive(clap::Args)]
pub struct Args {
    /// Scenario to tune on (file or built-in name).
    #[arg(long, default_value = "paper-scenario-1")]
    scenario: String,
    /// `--set`.
    #[command(flatten)]
    set: SetArgs,
}

/// Runs `ftsmc tune-tsm-sta`.
pub fn run(args: Args) -> Result<()> {
    let scenario = load_scenario_with_limits(&args.scenario, &[], &args.set.set)?;
    let r = ftsmc_sim::analysis::tuning::tune_tsm_sta(
        &scenario,
        &ftsmc_core::tsm_sta::TsmStaGains::BASE_POSITION,
        &ftsmc_core::tsm_sta::TsmStaGains::BASE_ATTITUDE,
    )
    .map_err(anyhow::Error::msg)?;
    println!("# TSM-STA gains from the procedure of docs/results.md (ftsmc tune-tsm-sta)");
    println!("# time-scale factors: position {:.6}, attitude {:.6}", r.position_scale, r.attitude_scale);
    println!(
        "# RANFTSMC settling (slowest of x,y,z; psi): {:.3} s, {:.3} s; TSM-STA achieves {:.3} s, {:.3} s",
        r.target[0], r.target[1], r.achieved[0], r.achieved[1]
    );
    for (axis, g) in r.gains.named() {
        println!("\n[tsm-sta.{axis}]");
        print!("{}", toml::to_string(g)?);
    }
    Ok(())
}
