//! The paper scenarios' ISE and IAE per axis, flown with the paper's three
//! controllers, must stay bit-identical: the values below were recorded
//! (as `f64::to_bits`) before the crate was reorganised (issue 11, item 1).
//! A change here means a change of results, not of layout.

use ftsmc_sim::registry::{run, PAPER_CONTROLLERS};
use ftsmc_sim::run::RunOptions;
use ftsmc_sim::Scenario;

const fn b(bits: u64) -> f64 {
    f64::from_bits(bits)
}

/// (scenario index in `Scenario::paper_scenarios()`, controller, ISE, IAE)
/// per axis x, y, z, φ, θ, ψ.
type Row = (usize, &'static str, [f64; 6], [f64; 6]);

const RECORDED: [Row; 6] = [
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

#[test]
fn paper_scenarios_are_bit_identical() {
    let scenarios = Scenario::paper_scenarios();
    assert_eq!(scenarios.len(), 2);
    let mut flown = 0;
    for (i, scenario) in scenarios.iter().enumerate() {
        for name in PAPER_CONTROLLERS {
            let (_, _, ise, iae) = RECORDED
                .iter()
                .find(|(j, c, _, _)| *j == i && *c == name)
                .unwrap_or_else(|| panic!("no recorded values for scenario {i}, {name}"));
            let out =
                run(name, scenario, RunOptions { record: false, ..Default::default() }).expect("known controller");
            for (k, ((axis, got_ise), (_, got_iae))) in
                out.metrics.ise.named().into_iter().zip(out.metrics.iae.named()).enumerate()
            {
                assert_eq!(
                    got_ise.to_bits(),
                    ise[k].to_bits(),
                    "scenario {i} {name} ISE {axis}: {got_ise:e} != {:e}",
                    ise[k]
                );
                assert_eq!(
                    got_iae.to_bits(),
                    iae[k].to_bits(),
                    "scenario {i} {name} IAE {axis}: {got_iae:e} != {:e}",
                    iae[k]
                );
            }
            flown += 1;
        }
    }
    assert_eq!(flown, RECORDED.len());
}
