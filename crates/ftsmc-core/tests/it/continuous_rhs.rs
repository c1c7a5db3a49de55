//! `AxisLaw::continuous_rhs` is the right-hand side that `AxisLaw::update`
//! steps with explicit Euler: same `v`, same `S`, and `update(dt)` moves the
//! adaptive states by `dt` times the rates.

use ftsmc_core::ftaftsmc::{FtaftsmcAxis, FtaftsmcGains};
use ftsmc_core::law::AxisLaw;
use ftsmc_core::ranftsmc::{RanftsmcAxis, RanftsmcGains};
use ftsmc_core::tsm_sta::{TsmStaAxis, TsmStaGains};

fn check<L: AxisLaw + Clone>(law: &L) {
    let dt = 1e-4;
    for &(e, e_dot) in &[(0.4, -0.3), (-2.0, 0.1), (0.01, 0.5), (3.0, 0.0), (0.0, -1.0)] {
        let mut stepped = law.clone();
        // Give the adaptive states non-trivial values first.
        for _ in 0..10 {
            stepped.update(0.5, 0.2, 1e-2);
        }
        let before = stepped.estimates();
        let rhs = stepped.continuous_rhs(e, e_dot, before).expect("implemented");
        let v = stepped.update(e, e_dot, dt);
        assert_eq!(v.to_bits(), rhs.v.to_bits(), "{} v at ({e}, {e_dot})", L::NAME);
        assert_eq!(stepped.sliding_variable().to_bits(), rhs.s.to_bits(), "{} S", L::NAME);
        let after = stepped.estimates();
        for k in 0..3 {
            let euler = before[k] + dt * rhs.estimates_rate[k];
            assert!(
                (after[k] - euler).abs() <= 1e-14 * (1.0 + euler.abs()),
                "{} state {k}: {} vs {euler}",
                L::NAME,
                after[k]
            );
        }
    }
}

#[test]
fn continuous_rhs_matches_update_for_every_law() {
    check(&FtaftsmcAxis::new(FtaftsmcGains::PAPER_XY));
    check(&FtaftsmcAxis::new(FtaftsmcGains::PAPER_YAW));
    check(&RanftsmcAxis::new(RanftsmcGains::PAPER_POSITION));
    check(&RanftsmcAxis::new(RanftsmcGains::PAPER_ATTITUDE));
    check(&TsmStaAxis::new(TsmStaGains::DEFAULT_POSITION));
}
