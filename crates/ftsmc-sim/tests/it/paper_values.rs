//! The paper scenarios' ISE and IAE per axis, flown with the paper's three
//! controllers.
//!
//! - [`CURRENT`] pins them bit for bit: a change here means a change of
//!   results, not of layout.
//! - [`PLATFORM_LIBM`] holds the values published before every
//!   transcendental function went through the one pure-Rust maths library
//!   (`ftsmc_core::math`): they were computed with glibc's FMA build of
//!   `pow`, `exp`, `atan2` … on an x86-64 CPU with FMA. The flights must
//!   still agree with them to 1e-12 relative.
//!
//! After a deliberate change of the numerics, `cargo test -p ftsmc-sim
//! --test paper_values -- --ignored --nocapture` prints the new table.

use ftsmc_sim::registry::{run, PAPER_CONTROLLERS};
use ftsmc_sim::run::RunOptions;
use ftsmc_sim::Scenario;

const fn b(bits: u64) -> f64 {
    f64::from_bits(bits)
}

/// (scenario index in `Scenario::paper_scenarios()`, controller, ISE, IAE)
/// per axis x, y, z, φ, θ, ψ.
type Row = (usize, &'static str, [f64; 6], [f64; 6]);

/// Before the one maths library (commit 2684107, glibc's FMA `libm`).
const PLATFORM_LIBM: [Row; 6] = [
    (
        0,
        "ranftsmc",
        [
            b(0x3feec6fdece9f5c6),
            b(0x3ff063420b287d64),
            b(0x3fe8de2c07bac4f2),
            b(0x3f4227bf5394d58f),
            b(0x3f7a1d5921c79c55),
            b(0x3fa2121c6879bc2c),
        ],
        [
            b(0x3ff46e022448306a),
            b(0x3ff56f6911bff56d),
            b(0x3ff149a835d263ce),
            b(0x3f9ce6d8d66f776c),
            b(0x3fb0b45d93d67324),
            b(0x3fbe740265661ce6),
        ],
    ),
    (
        0,
        "tsm-sta",
        [
            b(0x3fedb603affe2558),
            b(0x3fef7adb2dfd0793),
            b(0x3fe91a36ae8cf446),
            b(0x3f375bef9e4aaa1c),
            b(0x3f75e1544711023e),
            b(0x3fb15b0944f57a2c),
        ],
        [
            b(0x3ff3f7f2cfc3a0c8),
            b(0x3ff4b4abaaee3151),
            b(0x3ff1a441039a8ca1),
            b(0x3f938ec78629d88f),
            b(0x3fabf1e66aed0f6e),
            b(0x3fc847b6d8987223),
        ],
    ),
    (
        0,
        "ftaftsmc",
        [
            b(0x3fe543546d1c4462),
            b(0x3fe4203a642bbbfe),
            b(0x3fcc0004bb5a224e),
            b(0x3f4e4c28e0be5949),
            b(0x3f8e5b70ae934efa),
            b(0x3f986c1174ade305),
        ],
        [
            b(0x3fec366a36353eca),
            b(0x3feb45c9519214cf),
            b(0x3fd4b52bc7aa4a7d),
            b(0x3fa693bd75c056d4),
            b(0x3fb0d288ee19a602),
            b(0x3fb18675a861d906),
        ],
    ),
    (
        1,
        "ranftsmc",
        [
            b(0x3fc091264a3c8258),
            b(0x3ff8c598d7793080),
            b(0x403f15f94e99fa79),
            b(0x3f7baccf8dcae5df),
            b(0x3f5678f4f4b77b52),
            b(0x3f7867ec18391da9),
        ],
        [
            b(0x3ff14ce3c7803657),
            b(0x3ffbc278b1e3cd3b),
            b(0x403109ee6a0112a0),
            b(0x3fc61fb0c386a902),
            b(0x3fbeac22ebc15b05),
            b(0x3faaf893bd7efd67),
        ],
    ),
    (
        1,
        "tsm-sta",
        [
            b(0x3fb250a7bbec5eca),
            b(0x3ff95cfa225f64b0),
            b(0x4062d0e626645a9f),
            b(0x3f76375cd8781b46),
            b(0x3f39bcc507af28ed),
            b(0x3f81622fda63fbbc),
        ],
        [
            b(0x3fe93067297fd654),
            b(0x40026c54275a4141),
            b(0x4043a181615825e4),
            b(0x3fb0efc5ee1d2a63),
            b(0x3fa01c39402e7b51),
            b(0x3fb281bc91c0df0e),
        ],
    ),
    (
        1,
        "ftaftsmc",
        [
            b(0x3fa15c12c43dc94b),
            b(0x3fecf1b49ccc4ea3),
            b(0x3fcc019b8d2b84ec),
            b(0x3f88e819ddcd17ee),
            b(0x3f7571ccbe0dc05d),
            b(0x3f6a37ed6100fa54),
        ],
        [
            b(0x3fc8b11e5781ece0),
            b(0x3ff0ba49eb8b56e8),
            b(0x3fd5466be49a50b6),
            b(0x3fb979a8d390e657),
            b(0x3fb49879eca06977),
            b(0x3f983239962178ef),
        ],
    ),
];

/// ISE and IAE of every paper scenario × paper controller, as flown now.
fn flown() -> Vec<Row> {
    let scenarios = Scenario::paper_scenarios();
    assert_eq!(scenarios.len(), 2);
    let mut rows = Vec::new();
    for (i, scenario) in scenarios.iter().enumerate() {
        for name in PAPER_CONTROLLERS {
            let out =
                run(name, scenario, RunOptions { record: false, ..Default::default() }).expect("known controller");
            let ise = out.metrics.ise.named().map(|(_, v)| *v);
            let iae = out.metrics.iae.named().map(|(_, v)| *v);
            rows.push((i, name, ise, iae));
        }
    }
    rows
}

fn find(table: &[Row], i: usize, name: &str) -> ([f64; 6], [f64; 6]) {
    let (_, _, ise, iae) = table
        .iter()
        .find(|(j, c, _, _)| *j == i && *c == name)
        .unwrap_or_else(|| panic!("no recorded values for scenario {i}, {name}"));
    (*ise, *iae)
}

const AXES: [&str; 6] = ["x", "y", "z", "phi", "theta", "psi"];

#[test]
fn paper_scenarios_are_bit_identical() {
    let rows = flown();
    assert_eq!(rows.len(), CURRENT.len());
    for (i, name, ise, iae) in rows {
        let (want_ise, want_iae) = find(&CURRENT, i, name);
        for k in 0..6 {
            assert_eq!(
                ise[k].to_bits(),
                want_ise[k].to_bits(),
                "scenario {i} {name} ISE {}: {:e} != {:e}",
                AXES[k],
                ise[k],
                want_ise[k]
            );
            assert_eq!(
                iae[k].to_bits(),
                want_iae[k].to_bits(),
                "scenario {i} {name} IAE {}: {:e} != {:e}",
                AXES[k],
                iae[k],
                want_iae[k]
            );
        }
    }
}

#[test]
fn paper_scenarios_agree_with_the_platform_libm_values_to_1e_12() {
    let mut worst = 0.0f64;
    for (i, name, ise, iae) in flown() {
        let (old_ise, old_iae) = find(&PLATFORM_LIBM, i, name);
        for k in 0..6 {
            for (what, got, old) in [("ISE", ise[k], old_ise[k]), ("IAE", iae[k], old_iae[k])] {
                let rel = (got - old).abs() / old.abs();
                assert!(rel <= 1e-12, "scenario {i} {name} {what} {}: {got:e} vs {old:e} ({rel:e} relative)", AXES[k]);
                worst = worst.max(rel);
            }
        }
    }
    println!("largest relative change against the platform libm: {worst:e}");
}

/// Prints [`CURRENT`] as flown (run with `--ignored --nocapture`).
#[test]
#[ignore = "prints the table to pin after a deliberate change of the numerics"]
fn print_current_table() {
    println!("const CURRENT: [Row; 6] = [");
    for (i, name, ise, iae) in flown() {
        println!("    (\n        {i},\n        {name:?},");
        for values in [ise, iae] {
            println!("        [");
            for v in values {
                println!("            b({:#018x}),", v.to_bits());
            }
            println!("        ],");
        }
        println!("    ),");
    }
    println!("];");
}

/// As flown since the one maths library and the lean step (powers as
/// `exp(a ln|x|)`, signals sampled on the loop's grids, metrics summed
/// before the factor `dt`).
const CURRENT: [Row; 6] = [
    (
        0,
        "ranftsmc",
        [
            b(0x3feec6fdece9f5a3),
            b(0x3ff063420b287d16),
            b(0x3fe8de2c07bac569),
            b(0x3f4227bf5394d598),
            b(0x3f7a1d5921c79cb8),
            b(0x3fa2121c6879bc26),
        ],
        [
            b(0x3ff46e022448304b),
            b(0x3ff56f6911bff5b5),
            b(0x3ff149a835d263a0),
            b(0x3f9ce6d8d66f7796),
            b(0x3fb0b45d93d672f3),
            b(0x3fbe740265661cca),
        ],
    ),
    (
        0,
        "tsm-sta",
        [
            b(0x3fedb603affe24fa),
            b(0x3fef7adb2dfd07a0),
            b(0x3fe91a36ae8cf446),
            b(0x3f375bef9e4aaa4d),
            b(0x3f75e15447110252),
            b(0x3fb15b0944f579dc),
        ],
        [
            b(0x3ff3f7f2cfc3a0df),
            b(0x3ff4b4abaaee3131),
            b(0x3ff1a441039a8d04),
            b(0x3f938ec78629d88c),
            b(0x3fabf1e66aed0f7f),
            b(0x3fc847b6d8986f7c),
        ],
    ),
    (
        0,
        "ftaftsmc",
        [
            b(0x3fe543546d1c447f),
            b(0x3fe4203a642bbbf3),
            b(0x3fcc0004bb5a221f),
            b(0x3f4e4c28e0be59df),
            b(0x3f8e5b70ae934f5c),
            b(0x3f986c1174ade2f8),
        ],
        [
            b(0x3fec366a36353f16),
            b(0x3feb45c9519214c3),
            b(0x3fd4b52bc7aa4ab2),
            b(0x3fa693bd75c056bc),
            b(0x3fb0d288ee19a5f6),
            b(0x3fb18675a861d90c),
        ],
    ),
    (
        1,
        "ranftsmc",
        [
            b(0x3fc091264a3c8257),
            b(0x3ff8c598d779301c),
            b(0x403f15f94e99fa9c),
            b(0x3f7baccf8dcae55c),
            b(0x3f5678f4f4b77b59),
            b(0x3f7867ec18391de2),
        ],
        [
            b(0x3ff14ce3c780360f),
            b(0x3ffbc278b1e3cda5),
            b(0x403109ee6a011326),
            b(0x3fc61fb0c386a9b3),
            b(0x3fbeac22ebc15ad5),
            b(0x3faaf893bd7efdaa),
        ],
    ),
    (
        1,
        "tsm-sta",
        [
            b(0x3fb250a7bbec5ea2),
            b(0x3ff95cfa225f646d),
            b(0x4062d0e626645adf),
            b(0x3f76375cd8781b87),
            b(0x3f39bcc507af2915),
            b(0x3f81622fda63fb23),
        ],
        [
            b(0x3fe93067297fd624),
            b(0x40026c54275a4133),
            b(0x4043a18161582663),
            b(0x3fb0efc5ee1d2a25),
            b(0x3fa01c39402e7b66),
            b(0x3fb281bc91c0df20),
        ],
    ),
    (
        1,
        "ftaftsmc",
        [
            b(0x3fa15c12c43dc98e),
            b(0x3fecf1b49ccc4ef4),
            b(0x3fcc019b8d2b8488),
            b(0x3f88e819ddcd172e),
            b(0x3f7571ccbe0dc0b8),
            b(0x3f6a37ed6100fa91),
        ],
        [
            b(0x3fc8b11e5781e9ad),
            b(0x3ff0ba49eb8b56b3),
            b(0x3fd5466be49a50b7),
            b(0x3fb979a8d390e683),
            b(0x3fb49879eca06f79),
            b(0x3f98323996217581),
        ],
    ),
];
