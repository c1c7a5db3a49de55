//! RANFTSMC and TSM-STA on lanes: lane `i` of a law on `Lanes<N>` has
//! exactly the bits of an `f64` law fed lane `i`'s inputs — outputs,
//! sliding variables, adaptive / integral states and freeze flags — over
//! hundreds of steps whose lanes take different branches: ordinary errors,
//! exact and signed zeros, rates below the shared-power threshold
//! (`|ė| < 1e-100`, the direct power) and subnormal, inputs beyond
//! `INPUT_LIMIT` (clamped), states beyond `STATE_LIMIT` (saturated), frozen
//! and released lanes, a NaN or infinite input in one lane, a non-finite or
//! zero `dt` (shared by every lane), and lanes restarted with `reset_lane`.

use ftsmc_core::lanes::{LaneMask, Lanes, Lanewise, Real};
use ftsmc_core::law::AxisLaw;
use ftsmc_core::ranftsmc::{RanftsmcAxis, RanftsmcGains};
use ftsmc_core::tsm_sta::{TsmStaAxis, TsmStaGains};

/// A 64-bit linear congruential generator (Knuth's MMIX constants): the
/// same inputs on every machine.
struct Lcg(u64);

impl Lcg {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        self.0
    }
    /// Uniform in `[0, 1)`.
    fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn below(&mut self, n: u64) -> u64 {
        (self.next_u64() >> 33) % n
    }
    /// One input value, from a menu that reaches every branch of the laws.
    fn input(&mut self, scale: f64) -> f64 {
        match self.below(20) {
            0 => 0.0,
            1 => -0.0,
            2 => 1e-150 * (self.unit() - 0.5), // below the shared-power threshold
            3 => 3e-100,                       // just above it
            4 => -1e-310,                      // subnormal
            5 => 1e13 * (self.unit() - 0.5),   // clamped to ±INPUT_LIMIT
            6 => -1e300,
            7 => 1e-6 * (self.unit() - 0.5), // near zero
            _ => scale * (2.0 * self.unit() - 1.0),
        }
    }
}

/// What happened over a run, so that the comparison is not vacuous.
#[derive(Default)]
struct Coverage {
    bad_lane_with_good_lanes: usize,
    mixed_freeze: usize,
    resets: usize,
}

/// Feed `lanes` and `scalars` (lane `i` of `lanes` starts as `scalars[i]`)
/// the same inputs for `steps` steps and compare everything bit for bit;
/// `compare` checks the law-specific state (freeze flags, fields).
fn check<const N: usize, LL, LS>(
    mut lanes: LL,
    mut scalars: [LS; N],
    seed: u64,
    steps: usize,
    compare: impl Fn(&LL, &[LS; N], usize),
) -> Coverage
where
    LL: AxisLaw<Lanes<N>>,
    LS: AxisLaw<f64>,
{
    let mut rng = Lcg(seed);
    let mut cov = Coverage::default();
    let mut frozen = [false; N];
    for step in 0..steps {
        // Freeze flags: each lane toggles now and then, independently.
        if step % 7 == 0 {
            for f in frozen.iter_mut() {
                if rng.below(3) == 0 {
                    *f = !*f;
                }
            }
            lanes.set_adaptation_frozen(LaneMask::from_bools(frozen));
            for (law, &f) in scalars.iter_mut().zip(&frozen) {
                law.set_adaptation_frozen(f);
            }
        }
        // A flight restarted in one lane.
        if step % 53 == 29 {
            let lane = rng.below(N as u64) as usize;
            lanes.reset_lane(lane);
            scalars[lane].reset();
            frozen[lane] = false;
            cov.resets += 1;
        }
        let mut e = [0.0; N];
        let mut e_dot = [0.0; N];
        for i in 0..N {
            e[i] = rng.input(2.0);
            e_dot[i] = rng.input(3.0);
        }
        // A bad measurement in one lane now and then.
        if step % 11 == 5 {
            let lane = rng.below(N as u64) as usize;
            let bad = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY][rng.below(3) as usize];
            if rng.below(2) == 0 {
                e[lane] = bad;
            } else {
                e_dot[lane] = bad;
            }
        }
        let dt = match step % 97 {
            13 => f64::NAN,
            14 => f64::INFINITY,
            40 => 0.0,
            41 => 10.0,
            _ => 1e-3,
        };
        let out = lanes.update(Lanes(e), Lanes(e_dot), dt);
        let mut any_nan = false;
        let mut any_finite = false;
        for i in 0..N {
            let want = scalars[i].update(e[i], e_dot[i], dt);
            assert_eq!(
                out.get_lane(i).to_bits(),
                want.to_bits(),
                "{} step {step} lane {i}: e = {:e}, ė = {:e}, dt = {dt}: {} vs {want}",
                LS::NAME,
                e[i],
                e_dot[i],
                out.get_lane(i)
            );
            any_nan |= want.is_nan();
            any_finite |= want.is_finite();
            assert_eq!(
                lanes.sliding_variable().get_lane(i).to_bits(),
                scalars[i].sliding_variable().to_bits(),
                "{} step {step} lane {i}: sliding variable",
                LS::NAME
            );
            let (got, want) = (lanes.estimates(), scalars[i].estimates());
            for k in 0..3 {
                assert_eq!(
                    got[k].get_lane(i).to_bits(),
                    want[k].to_bits(),
                    "{} step {step} lane {i}: estimate {k}",
                    LS::NAME
                );
            }
        }
        compare(&lanes, &scalars, step);
        cov.bad_lane_with_good_lanes += usize::from(any_nan && any_finite);
        cov.mixed_freeze += usize::from(frozen.iter().any(|&f| f) && frozen.iter().any(|&f| !f));
    }
    cov
}

trait FromBools<const N: usize> {
    fn from_bools(b: [bool; N]) -> Self;
}

impl<const N: usize> FromBools<N> for LaneMask<N> {
    fn from_bools(b: [bool; N]) -> Self {
        let mut m = LaneMask::<N>::default();
        for (i, &v) in b.iter().enumerate() {
            m.put_lane(i, v);
        }
        m
    }
}

fn assert_covered(cov: &Coverage, what: &str) {
    assert!(cov.bad_lane_with_good_lanes > 10, "{what}: too few steps with one bad lane among good ones");
    assert!(cov.mixed_freeze > 50, "{what}: too few steps with frozen and released lanes together");
    assert!(cov.resets >= 5, "{what}: too few reset_lane calls");
}

fn ranftsmc_gain_sets() -> Vec<RanftsmcGains> {
    let p = RanftsmcGains::PAPER_POSITION;
    let a = RanftsmcGains::PAPER_ATTITUDE;
    vec![
        p,
        a,
        RanftsmcGains { a0_hat0: 0.2, a1_hat0: 0.1, a2_hat0: 0.05, ..p },
        RanftsmcGains { sign_smoothing: 0.05, ..a },
        // α − 1 = 1 (a multiplication, not exp/ln) and large adaptation rates.
        RanftsmcGains { alpha: 2.0, beta: 1.5, mu0: 1e3, mu1: 1e3, mu2: 1e3, ..a },
    ]
}

fn ranftsmc_lanes<const N: usize>(seed: u64) {
    for (n, g) in ranftsmc_gain_sets().into_iter().enumerate() {
        let mut scalars: [RanftsmcAxis; N] = core::array::from_fn(|_| RanftsmcAxis::new(g));
        // Lanes start from different states; one beyond STATE_LIMIT so the
        // saturation of â acts in that lane only.
        for (i, law) in scalars.iter_mut().enumerate() {
            law.a_hat = [0.1 * i as f64, 0.01 * i as f64, 0.001 * i as f64];
        }
        scalars[N - 1].a_hat = [5e100, 2e100, 3e100];
        let mut lanes = RanftsmcAxis::<Lanes<N>>::splat(g);
        for (i, law) in scalars.iter().enumerate() {
            lanes.put_lane(i, *law);
        }
        let cov = check(lanes, scalars, seed ^ n as u64, 600, |lanes, scalars, step| {
            for (i, law) in scalars.iter().enumerate() {
                let one = lanes.get_lane(i);
                assert_eq!(one.adaptation_frozen(), law.adaptation_frozen(), "step {step} lane {i}: frozen");
                assert_eq!(one.a_hat.map(f64::to_bits), law.a_hat.map(f64::to_bits), "step {step} lane {i}: â");
                assert_eq!(one.sigma.to_bits(), law.sigma.to_bits(), "step {step} lane {i}: σ");
                assert_eq!(lanes.adaptation_frozen().get_lane(i), law.adaptation_frozen());
            }
        });
        assert_covered(&cov, &format!("ranftsmc gain set {n}, {N} lanes"));
    }
}

fn tsm_sta_gain_sets() -> Vec<TsmStaGains> {
    vec![
        TsmStaGains::DEFAULT_POSITION,
        TsmStaGains::DEFAULT_ATTITUDE,
        TsmStaGains { sign_smoothing: 0.05, ..TsmStaGains::BASE_POSITION },
        // q ≠ 3: the q-th root through powf.
        TsmStaGains { p: 7.0, q: 5.0, ..TsmStaGains::DEFAULT_ATTITUDE },
        // Unchecked p, q that are not odd integers: the general real powers.
        TsmStaGains { p: 4.0, q: 3.0, ..TsmStaGains::DEFAULT_POSITION },
    ]
}

fn tsm_sta_lanes<const N: usize>(seed: u64) {
    for (n, g) in tsm_sta_gain_sets().into_iter().enumerate() {
        let mut scalars: [TsmStaAxis; N] = core::array::from_fn(|_| TsmStaAxis::new(g));
        for (i, law) in scalars.iter_mut().enumerate() {
            law.nu = 0.3 * i as f64 - 0.5;
        }
        // Beyond STATE_LIMIT: saturated at the next integration, in that lane only.
        scalars[N - 1].nu = -4e100;
        let mut lanes = TsmStaAxis::<Lanes<N>>::splat(g);
        for (i, law) in scalars.iter().enumerate() {
            lanes.put_lane(i, *law);
        }
        let cov = check(lanes, scalars, seed ^ (n as u64) << 8, 600, |lanes, scalars, step| {
            for (i, law) in scalars.iter().enumerate() {
                let one = lanes.get_lane(i);
                assert_eq!(one.adaptation_frozen(), law.adaptation_frozen(), "step {step} lane {i}: frozen");
                assert_eq!(one.nu.to_bits(), law.nu.to_bits(), "step {step} lane {i}: ν");
                assert_eq!(one.s.to_bits(), law.s.to_bits(), "step {step} lane {i}: s");
            }
        });
        assert_covered(&cov, &format!("tsm-sta gain set {n}, {N} lanes"));
    }
}

#[test]
fn ranftsmc_on_4_lanes_is_4_scalar_laws_bit_for_bit() {
    ranftsmc_lanes::<4>(0x5eed_0004);
}

#[test]
fn ranftsmc_on_8_lanes_is_8_scalar_laws_bit_for_bit() {
    ranftsmc_lanes::<8>(0x5eed_0008);
}

#[test]
fn tsm_sta_on_4_lanes_is_4_scalar_laws_bit_for_bit() {
    tsm_sta_lanes::<4>(0x7577_0004);
}

#[test]
fn tsm_sta_on_8_lanes_is_8_scalar_laws_bit_for_bit() {
    tsm_sta_lanes::<8>(0x7577_0008);
}

/// `reset_lane` restores that lane's initial states only, and `reset`
/// every lane; `continuous_rhs` of a lane law is lane 0's scalar law.
#[test]
fn reset_lane_touches_one_lane_and_continuous_rhs_is_lane_zero() {
    let g = RanftsmcGains { a0_hat0: 0.2, ..RanftsmcGains::PAPER_POSITION };
    let mut lanes = RanftsmcAxis::<Lanes<4>>::splat(g);
    lanes.set_adaptation_frozen(LaneMask::from_bools([false, true, false, true]));
    for k in 0..20 {
        lanes.update(Lanes::from_fn(|i| 0.3 - 0.1 * (i + k) as f64), Lanes::splat(0.4), 1e-2);
    }
    let before = lanes;
    lanes.reset_lane(1);
    let fresh = RanftsmcAxis::new(g);
    let one = lanes.get_lane(1);
    assert_eq!(one.a_hat, fresh.a_hat);
    assert_eq!(one.sigma.to_bits(), fresh.sigma.to_bits());
    assert!(!one.adaptation_frozen());
    for i in [0, 2, 3] {
        assert_eq!(lanes.get_lane(i).a_hat, before.get_lane(i).a_hat);
        assert_eq!(lanes.get_lane(i).adaptation_frozen(), before.get_lane(i).adaptation_frozen());
    }
    assert_ne!(before.get_lane(0).a_hat, fresh.a_hat, "the lanes moved: the test is not vacuous");
    let rhs = lanes.continuous_rhs(0.2, -0.1, [0.3, 0.02, 0.01]).unwrap();
    let want = lanes.get_lane(0).continuous_rhs(0.2, -0.1, [0.3, 0.02, 0.01]).unwrap();
    assert_eq!(rhs, want);
    lanes.reset();
    for i in 0..4 {
        assert_eq!(lanes.get_lane(i).a_hat, fresh.a_hat);
        assert!(!lanes.get_lane(i).adaptation_frozen());
    }

    let mut tsm = TsmStaAxis::<Lanes<8>>::splat(TsmStaGains::DEFAULT_ATTITUDE);
    for _ in 0..20 {
        tsm.update(Lanes::from_fn(|i| 0.1 * i as f64 - 0.3), Lanes::splat(-0.2), 1e-2);
    }
    let before = tsm;
    tsm.reset_lane(6);
    assert_eq!(tsm.get_lane(6).nu.to_bits(), 0.0f64.to_bits());
    for i in (0..8).filter(|&i| i != 6) {
        assert_eq!(tsm.get_lane(i).nu.to_bits(), before.get_lane(i).nu.to_bits());
    }
    assert_ne!(before.get_lane(6).nu, 0.0, "the lanes moved: the test is not vacuous");
    let frozen_lane0 = {
        let mut t = tsm;
        t.set_adaptation_frozen(LaneMask::from_bools([true, false, false, false, false, false, false, false]));
        t
    };
    let rhs = frozen_lane0.continuous_rhs(0.2, -0.1, [0.3, 0.0, 0.0]).unwrap();
    assert_eq!(rhs.estimates_rate, [0.0; 3], "lane 0 is frozen");
    assert_eq!(rhs, frozen_lane0.get_lane(0).continuous_rhs(0.2, -0.1, [0.3, 0.0, 0.0]).unwrap());
}
