//! Regression tests for non-finite results ("a core that
//! stays finite"). Each test reproduces one reported case and failed on the
//! code before the fix; they use only API that existed before it.

use ftsmc_core::ftaftsmc::{FtaftsmcAxis, FtaftsmcGains};
use ftsmc_core::law::AxisLaw;
use ftsmc_core::ranftsmc::{RanftsmcAxis, RanftsmcGains};
use ftsmc_core::tsm_sta::{TsmStaAxis, TsmStaGains};

/// RANFTSMC computed `|ė|^(2−β)` as `|ė|² / |ė|^β`; with β = 5/3 both
/// underflow to 0 for `0 < |ė| ≤ 6.8e-195` and the quotient is `0/0 = NaN`.
#[test]
fn ranftsmc_published_gains_are_finite_for_tiny_error_rates() {
    for g in [RanftsmcGains::PAPER_POSITION, RanftsmcGains::PAPER_ATTITUDE] {
        for ed in [6.8e-195, 1e-200, 1e-250, 1e-300, 5e-324, -6.8e-195, -1e-300, 1e-160, 1e-120] {
            for e in [0.0, 0.3, -1e-300] {
                let mut axis = RanftsmcAxis::new(g);
                let v = axis.update(e, ed, 1e-3);
                assert!(v.is_finite(), "e = {e}, ė = {ed}: {v}");
                assert!(axis.a_hat.iter().all(|a| a.is_finite()));
            }
        }
    }
}

/// FTAFTSMC with ℵ3 = 889 at a 2.24 m error: `|e|^889` overflows, so
/// `exp(−ℵ2 |e|^ℵ3) = 0` and `|e|^(ℵ3−1) = ∞` in Ẏ (Eq. 11): `0·∞ = NaN`.
/// ℵ3 is now limited to 100 by `check()`, the guard makes even the
/// unchecked 889 finite, and the largest legal ℵ3 is finite at every error.
#[test]
fn ftaftsmc_large_aleph3_is_rejected_and_finite() {
    let g = FtaftsmcGains { aleph3: 889.0, ..FtaftsmcGains::PAPER_XY };
    let err = g.check().expect_err("aleph3 = 889 must be rejected");
    assert_eq!(err.field, "aleph3");
    let v = FtaftsmcAxis::new(g).update(2.24, 0.5, 1e-3);
    assert!(v.is_finite(), "unchecked aleph3 = 889 at e = 2.24: {v}");
    let g = FtaftsmcGains { aleph3: 100.0, ..FtaftsmcGains::PAPER_XY };
    g.check().unwrap();
    for e in [2.24, 1e4, -1e8, 1e300] {
        let v = FtaftsmcAxis::new(g).update(e, 0.5, 1e-3);
        assert!(v.is_finite(), "aleph3 = 100 at e = {e}: {v}");
    }
}

/// ε below ~1e-162 makes κ2 = (p−1) ε^(p−2) infinite, and κ2·sig²(0) = ∞·0
/// = NaN at zero error; ξ below ~1e-162 makes 2ξ² = 0 and δ̂/(2ξ²) = 0/0.
/// Both are now rejected with the reason, and the smallest legal values are
/// finite at zero error.
#[test]
fn tiny_epsilon_and_xi_are_rejected_and_the_smallest_legal_ones_are_finite() {
    let base = FtaftsmcGains::PAPER_Z;
    let err = FtaftsmcGains { epsilon: 1e-163, ..base }.check().expect_err("epsilon = 1e-163");
    assert_eq!(err.field, "epsilon");
    let err = FtaftsmcGains { xi: 1e-163, ..base }.check().expect_err("xi = 1e-163");
    assert_eq!(err.field, "xi");
    let smallest = FtaftsmcGains { epsilon: 1e-9, xi: 1e-6, ..base };
    smallest.check().unwrap();
    for (e, ed) in [(0.0, 0.0), (0.0, 1e300), (1e-300, -1e300), (1e300, 1e300)] {
        let mut axis = FtaftsmcAxis::new(smallest);
        let v = axis.update(e, ed, 1e-3);
        assert!(v.is_finite() && axis.delta_hat.is_finite(), "e = {e}, ė = {ed}: {v}");
    }
}

fn check_not_poisoned<L: AxisLaw>(mut law: L) {
    for k in 0..50 {
        law.update(0.3 - 0.01 * k as f64, -0.2, 1e-3);
    }
    for (e, ed, dt) in
        [(f64::NAN, 0.1, 1e-3), (0.1, f64::INFINITY, 1e-3), (0.1, 0.1, f64::NAN), (-f64::INFINITY, 0.0, 1e-3)]
    {
        let before = (law.estimates(), law.sliding_variable());
        let v = law.update(e, ed, dt);
        assert!(!v.is_finite(), "a non-finite input must give a non-finite command, got {v}");
        let after = (law.estimates(), law.sliding_variable());
        assert_eq!(before.0.map(f64::to_bits), after.0.map(f64::to_bits), "states changed by a non-finite input");
        assert_eq!(before.1.to_bits(), after.1.to_bits());
        let v = law.update(0.1, -0.1, 1e-3);
        assert!(v.is_finite(), "not recovered after a non-finite input: {v}");
        assert!(law.estimates().iter().all(|x| x.is_finite()));
    }
}

/// One NaN or ∞ measurement used to turn δ̂ (FTAFTSMC) and â (RANFTSMC)
/// into NaN/∞ for ever.
#[test]
fn a_non_finite_input_does_not_poison_the_adaptive_states() {
    check_not_poisoned(FtaftsmcAxis::new(FtaftsmcGains::PAPER_XY));
    check_not_poisoned(FtaftsmcAxis::new(FtaftsmcGains::PAPER_Z));
    check_not_poisoned(RanftsmcAxis::new(RanftsmcGains::PAPER_POSITION));
    check_not_poisoned(RanftsmcAxis::new(RanftsmcGains::PAPER_ATTITUDE));
    check_not_poisoned(TsmStaAxis::new(TsmStaGains::DEFAULT_POSITION));
}

/// TSM-STA accepted `p = 2999999999, q = 1999999999`; the update then cast p
/// to i32 (saturating at 2147483647), looped that many times (≈ 5 s) and
/// returned a wrong sliding variable. p and q are now odd integers ≤ 99.
#[test]
fn tsm_sta_huge_integers_are_rejected_not_truncated() {
    let base = TsmStaGains::DEFAULT_POSITION;
    let err = TsmStaGains { p: 2999999999.0, q: 1999999999.0, ..base }.check().expect_err("huge p, q");
    assert_eq!(err.field, "p");
    let err = TsmStaGains { p: 101.0, q: 99.0, ..base }.check().expect_err("p = 101");
    assert_eq!(err.field, "p");
    let err = TsmStaGains { p: 5.0, q: 101.0, ..base }.check().expect_err("q = 101");
    assert_eq!(err.field, "q");
    let err = TsmStaGains { p: 5.5, ..base }.check().expect_err("non-integer p");
    assert_eq!(err.field, "p");
    TsmStaGains { p: 97.0, q: 99.0, ..base }.check().expect_err("p/q < 1");
    TsmStaGains { p: 99.0, q: 97.0, ..base }.check().unwrap();
    // Even unchecked, the update is O(1) and uses the exact ratio p/q.
    let g = TsmStaGains { p: 2999999999.0, q: 1999999999.0, ..base };
    let mut axis = TsmStaAxis::new(g);
    let start = std::time::Instant::now();
    let (e, ed) = (0.2, 0.7f64);
    let v = axis.update(e, ed, 1e-3);
    assert!(start.elapsed().as_millis() < 100, "one update took {:?}", start.elapsed());
    let want = e + ftsmc_core::math::powf(ed, g.p / g.q) / g.lambda;
    assert!(v.is_finite() && (axis.s - want).abs() < 1e-12, "s = {} (want {want})", axis.s);
}
