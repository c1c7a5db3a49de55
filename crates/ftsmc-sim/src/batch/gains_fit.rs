//! Gains that fit the vehicle: the refusal of a campaign that would fly
//! the sliding-mode controllers' published gains on a vehicle they were not
//! made for, when they visibly do not fly it.
//!
//! The FTAFTSMC, RANFTSMC and TSM-STA default gains are the ones published
//! for the paper's vehicle (0.74 kg, inertia 3.8e-3/3.8e-3/7.7e-3 kg·m²,
//! arm 0.21 m). Nothing in them follows the vehicle (the PID and SE(3)
//! defaults do: they are derived from the vehicle's mass, inertia and
//! rotor limit). A time-scaling law for them (gains rescaled by the square
//! root of the control authority ratio, `T_max/m − g` and `τ_max/I`) was
//! measured and rejected: on the Crazyflie 2 it turned RANFTSMC's calm-rung
//! success from 100 % into 39 of 40 divergences. So there is no scaling
//! law here; instead a campaign whose controller flies those gains on a
//! vehicle of another size first flies the scenario's nominal flight (the
//! scenario as written, no Monte Carlo draw) and is refused, before it
//! starts, when that flight fails: a campaign of such flights would only
//! measure gains nobody meant for the vehicle. The refusal names the
//! remedies: tuned gains, a gain table, or `[simulation] unfit_gains =
//! "fly"` to fly them anyway.
//!
//! "Another size": any of the mass, the three principal inertias or the
//! arm length differs from the paper vehicle's by more than a factor
//! [`SIZE_FACTOR`] either way. The Hummingbird (0.716 kg, inertia 1.8×,
//! arm 0.81×) and Agilicious (0.752 kg) are of the paper's size; the
//! Crazyflies (25× lighter) and PX4's x500 (2.8× heavier, 6× the
//! inertia) are not.

use crate::controllers::NominalVehicle;
use crate::run::RunOptions;
use crate::scenario::{Scenario, UnfitGainsPolicy};
use ftsmc_core::model::QuadrotorParams;

/// Largest factor, either way, between a vehicle's mass, principal
/// inertias or arm length and the paper vehicle's for which the published
/// gains are flown without a check.
pub const SIZE_FACTOR: f64 = 2.0;

/// The largest factor, either way (≥ 1), between `vehicle`'s nominal mass,
/// principal inertias and arm length and those of the paper's vehicle
/// ([`QuadrotorParams::default`], paper Table 2). `inf` when one of them is
/// not positive.
pub fn size_factor(vehicle: &NominalVehicle) -> f64 {
    let paper = QuadrotorParams::default();
    let p = &vehicle.plant;
    let pairs = [
        (p.mass, paper.mass),
        (p.inertia[0], paper.inertia[0]),
        (p.inertia[1], paper.inertia[1]),
        (p.inertia[2], paper.inertia[2]),
        (p.arm_length, paper.arm_length),
    ];
    pairs.iter().fold(1.0_f64, |worst, &(v, reference)| {
        if !(v > 0.0 && reference > 0.0) {
            return f64::INFINITY;
        }
        let r = if v >= reference { v / reference } else { reference / v };
        if r > worst {
            r
        } else {
            worst
        }
    })
}

/// Why a campaign was refused: controller `controller` flies the paper
/// vehicle's default gains on a vehicle [`UnfitGains::size_factor`] times
/// another size, and the scenario's nominal flight failed with them.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error(
    "{label}'s published gains (the 0.74 kg paper vehicle's) do not fly {vehicle}, {size_factor:.1}× \
     another size: tune them (`ftsmc tune <scenario> -c {controller}`), write a [{section}] table, or \
     `--set simulation.unfit_gains=fly`. Nominal flight: {why}"
)]
pub struct UnfitGains {
    /// Controller name (`ranftsmc`, …).
    pub controller: String,
    /// Its display label.
    pub label: String,
    /// The gain section it reads (its TOML table).
    pub section: String,
    /// The vehicle, as the scenario names it (preset, or its mass).
    pub vehicle: String,
    /// [`size_factor`] of the scenario's vehicle.
    pub size_factor: f64,
    /// The nominal flight's failure: exit or envelope violation, with its time.
    pub why: String,
}

/// Check each of `names` against `scenario`: `Ok` when it flies gains
/// someone fitted (a gain table, tuned gains, the vehicle-derived PID and
/// SE(3) defaults), when the vehicle is of the paper vehicle's size
/// ([`SIZE_FACTOR`]), when the scenario says `unfit_gains = "fly"`, or when
/// its nominal flight succeeds; otherwise the first refusal. Flies at most
/// one flight per name (only the names that need the check).
pub fn check(scenario: &Scenario, names: &[String]) -> Result<(), Box<UnfitGains>> {
    if scenario.simulation.unfit_gains == UnfitGainsPolicy::Fly {
        return Ok(());
    }
    let vehicle = scenario.nominal_vehicle();
    let factor = size_factor(&vehicle);
    if factor <= SIZE_FACTOR {
        return Ok(());
    }
    for name in names {
        let paper = crate::controllers::flies_paper_defaults(name, &scenario.gains, &vehicle).unwrap_or(false);
        if !paper {
            continue;
        }
        let Ok(out) = crate::registry::run(name, scenario, RunOptions::default()) else { continue };
        if out.success() {
            continue;
        }
        let why = match out.envelope.as_ref().and_then(|v| v.violation.clone()) {
            Some(v) => v,
            None => out.exit.to_string(),
        };
        let vehicle_name = match scenario.vehicle.preset {
            Some(p) => p.name().to_string(),
            None => format!("{} kg", vehicle.plant.mass),
        };
        return Err(Box::new(UnfitGains {
            controller: name.clone(),
            label: plain_label(name),
            section: crate::controllers::section_key(name).unwrap_or(name).to_string(),
            vehicle: vehicle_name,
            size_factor: factor,
            why,
        }));
    }
    Ok(())
}

/// The controller's label without its reference number (`RANFTSMC`, not
/// `RANFTSMC [19]`).
fn plain_label(name: &str) -> String {
    let label = crate::registry::label(name);
    label.split(" [").next().unwrap_or(label).to_string()
}
