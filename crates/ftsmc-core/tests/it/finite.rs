//! Property tests of "a core that stays finite": for every
//! gain set that passes `check()` and every finite input with magnitude from
//! 1e-300 to 1e300 (log-uniform, random sign, plus exact 0), each law and the
//! cascade return finite commands with finite adaptive states; a non-finite
//! input returns a non-finite command and leaves every state bit-identical,
//! and the next finite input gives a finite command again.
//!
//! Extreme finite inputs (magnitudes up to `f64::MAX`, whose differences
//! overflow) give either a finite command or a NaN command with every state
//! untouched, and never poison the attitude reference: the next ordinary
//! input gives a finite command again. PID gains at their subnormal lower
//! edge (`yaw_weight`, `velocity_p`) give finite torques and integrators.
//!
//! Saturation remedies: the same holds with the adaptation frozen
//! ([`AxisLaw::set_adaptation_frozen`], `freeze_adaptation_on_saturation`
//! with random actuator feedback) and with random thrust limits; frozen
//! states do not move and the thrust stays inside its limits.

use ftsmc_core::cascade::{
    AttitudeDerivatives, Cascade, CascadeConfig, CascadeSettings, CommandFilterParams, Controller, FilterInit,
    MassAdaptation,
};
use ftsmc_core::ftaftsmc::{FtaftsmcAxis, FtaftsmcGains};
use ftsmc_core::law::{AxisLaw, DT_MAX};
use ftsmc_core::model::{QuadState, QuadrotorParams, Reference};
use ftsmc_core::pid::{PidController, PidGains};
use ftsmc_core::ranftsmc::{RanftsmcAxis, RanftsmcGains};
use ftsmc_core::tsm_sta::{TsmStaAxis, TsmStaGains};
use proptest::prelude::*;

/// Cases per law property (each case runs 6 finite steps and one poisoning
/// check).
const LAW_CASES: u32 = 5000;
/// Cases per cascade property (each case runs 4 cascade updates).
const CASCADE_CASES: u32 = 1000;

/// `10^x` for `x` uniform in `[lo, hi]`: a log-uniform positive number.
fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo..=hi).prop_map(|x| ftsmc_core::math::powf(10f64, x))
}

/// A finite input: exact 0, or ±10^x with x uniform in [-300, 300].
fn finite_input() -> impl Strategy<Value = f64> {
    prop_oneof![
        1 => Just(0.0),
        8 => (log_uniform(-300.0, 300.0), any::<bool>()).prop_map(|(m, neg)| if neg { -m } else { m }),
        1 => -10.0f64..10.0,
    ]
}

/// A legal control period: 0, or log-uniform in [1e-300, DT_MAX].
fn legal_dt() -> impl Strategy<Value = f64> {
    prop_oneof![1 => Just(0.0), 6 => log_uniform(-300.0, ftsmc_core::math::log10(DT_MAX)), 3 => log_uniform(-5.0, -1.0)]
}

fn non_finite() -> impl Strategy<Value = f64> {
    prop_oneof![Just(f64::NAN), Just(f64::INFINITY), Just(f64::NEG_INFINITY)]
}

/// A gain in `(0, 1e6]`, log-uniform from 1e-12 (and sometimes the bound).
fn gain() -> impl Strategy<Value = f64> {
    prop_oneof![8 => log_uniform(-12.0, 6.0), 1 => Just(1e6)]
}

fn gain_or_zero() -> impl Strategy<Value = f64> {
    prop_oneof![1 => Just(0.0), 6 => log_uniform(-12.0, 6.0), 1 => Just(1e6)]
}

/// An exponent in `(1, 10]` (both ends included as far as f64 allows).
fn exponent_above_one() -> impl Strategy<Value = f64> {
    prop_oneof![6 => (1.0f64..=10.0).prop_filter("> 1", |q| *q > 1.0), 1 => Just(10.0), 1 => Just(1.0 + 1e-12)]
}

/// An exponent in `(0, 1)`.
fn exponent_below_one() -> impl Strategy<Value = f64> {
    prop_oneof![6 => 1e-9f64..1.0, 1 => Just(1e-12), 1 => Just(1.0 - 1e-12)]
}

fn initial_state() -> impl Strategy<Value = f64> {
    prop_oneof![2 => Just(0.0), 1 => log_uniform(-300.0, 100.0)]
}

fn ftaftsmc_gains() -> impl Strategy<Value = FtaftsmcGains> {
    (
        (gain(), gain(), gain(), exponent_above_one(), exponent_below_one()),
        (log_uniform(-6.0, 0.0), gain(), (1.0f64..=100.0), log_uniform(-9.0, 6.0)),
        (gain(), gain(), gain(), exponent_above_one(), exponent_below_one()),
        (log_uniform(-6.0, 6.0), gain(), gain(), initial_state()),
    )
        .prop_map(
            |((lambda, gamma, eta, q, p), (aleph1, aleph2, aleph3, epsilon), r, (xi, alpha1, alpha2, d0))| {
                let (lambda2, gamma2, eta2, q2, p2) = r;
                FtaftsmcGains {
                    lambda,
                    gamma,
                    eta,
                    q,
                    p,
                    aleph1,
                    aleph2,
                    aleph3,
                    epsilon,
                    lambda2,
                    gamma2,
                    eta2,
                    q2,
                    p2,
                    xi,
                    alpha1,
                    alpha2,
                    delta_hat0: d0,
                }
            },
        )
}

fn ranftsmc_gains() -> impl Strategy<Value = RanftsmcGains> {
    (
        (gain(), log_uniform(-6.0, 6.0), gain(), (1.0f64..2.0).prop_filter("> 1", |b| *b > 1.0), (0.0f64..=1.0)),
        (gain_or_zero(), gain_or_zero(), gain_or_zero(), gain_or_zero()),
        (initial_state(), initial_state(), initial_state(), prop_oneof![Just(0.0), log_uniform(-300.0, 300.0)]),
    )
        .prop_map(|((b1, b2, c, beta, t), (h, mu0, mu1, mu2), (a0, a1, a2, phi))| {
            // α in (β, 10]
            let alpha = (beta + t * (10.0 - beta)).max(beta + 1e-9).min(10.0);
            RanftsmcGains {
                b1,
                b2,
                c,
                beta,
                alpha,
                h,
                mu0,
                mu1,
                mu2,
                a0_hat0: a0,
                a1_hat0: a1,
                a2_hat0: a2,
                sign_smoothing: phi,
            }
        })
}

fn tsm_sta_gains() -> impl Strategy<Value = TsmStaGains> {
    // Odd q in [1, 99], odd p with q < p < 2q and p <= 99 (q = 1 and q = 99
    // have no such p, so q runs over 3..=97).
    (1u32..=48, 0.0f64..1.0, log_uniform(-6.0, 6.0), gain(), gain(), prop_oneof![Just(0.0), log_uniform(-300.0, 300.0)])
        .prop_map(|(k, t, lambda, k1, k2, phi)| {
            let q = 2 * k + 1;
            let odd: Vec<u32> = (q + 1..(2 * q).min(100)).filter(|p| p % 2 == 1).collect();
            let p = odd[((t * odd.len() as f64) as usize).min(odd.len() - 1)];
            TsmStaGains { lambda, p: p as f64, q: q as f64, k1, k2, sign_smoothing: phi }
        })
}

/// Run finite steps (each frozen or not), then one non-finite step, then
/// one finite step.
fn exercise<L: AxisLaw>(
    mut law: L,
    steps: &[(f64, f64, f64, bool)],
    bad: (f64, f64, f64),
) -> Result<(), TestCaseError> {
    for &(e, ed, dt, frozen) in steps {
        law.set_adaptation_frozen(frozen);
        let held = law.estimates().map(f64::to_bits);
        let v = law.update(e, ed, dt);
        if frozen {
            prop_assert_eq!(law.estimates().map(f64::to_bits), held, "frozen states moved");
        }
        prop_assert!(v.is_finite(), "e = {e:e}, ė = {ed:e}, dt = {dt:e}: command {v}");
        prop_assert!(law.sliding_variable().is_finite(), "sliding variable {}", law.sliding_variable());
        let est = law.estimates();
        prop_assert!(est.iter().all(|x| x.is_finite()), "states {est:?}");
    }
    let before = (law.estimates().map(f64::to_bits), law.sliding_variable().to_bits());
    let v = law.update(bad.0, bad.1, bad.2);
    prop_assert!(!v.is_finite(), "non-finite input {bad:?} gave {v}");
    let after = (law.estimates().map(f64::to_bits), law.sliding_variable().to_bits());
    prop_assert_eq!(before, after, "states changed by a non-finite input");
    let (e, ed, dt, _) = steps[0];
    let v = law.update(e, ed, dt);
    prop_assert!(v.is_finite(), "no recovery after a non-finite input: {v}");
    Ok(())
}

/// The non-finite step: one of e, ė, dt replaced by NaN or ±∞.
fn bad_step() -> impl Strategy<Value = (f64, f64, f64)> {
    (non_finite(), 0usize..3, finite_input(), legal_dt()).prop_map(|(x, which, f, dt)| match which {
        0 => (x, f, dt),
        1 => (f, x, dt),
        _ => (f, f, x),
    })
}

fn steps() -> impl Strategy<Value = Vec<(f64, f64, f64, bool)>> {
    proptest::collection::vec((finite_input(), finite_input(), legal_dt(), any::<bool>()), 6)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(LAW_CASES))]

    #[test]
    fn ftaftsmc_stays_finite(g in ftaftsmc_gains(), s in steps(), bad in bad_step()) {
        prop_assert_eq!(g.check(), Ok(()));
        exercise(FtaftsmcAxis::try_new(g).unwrap(), &s, bad)?;
    }

    #[test]
    fn ranftsmc_stays_finite(g in ranftsmc_gains(), s in steps(), bad in bad_step()) {
        prop_assert_eq!(g.check(), Ok(()));
        exercise(RanftsmcAxis::try_new(g).unwrap(), &s, bad)?;
    }

    #[test]
    fn tsm_sta_stays_finite(g in tsm_sta_gains(), s in steps(), bad in bad_step()) {
        prop_assert_eq!(g.check(), Ok(()));
        exercise(TsmStaAxis::try_new(g).unwrap(), &s, bad)?;
    }
}

fn model() -> impl Strategy<Value = QuadrotorParams> {
    (
        (log_uniform(-6.0, 6.0), log_uniform(-3.0, 3.0), proptest::array::uniform3(gain())),
        (gain_or_zero(), proptest::array::uniform3(gain_or_zero()), proptest::array::uniform3(gain_or_zero())),
        (log_uniform(-12.0, 6.0), log_uniform(-12.0, 6.0), log_uniform(-6.0, 6.0)),
    )
        .prop_map(|((mass, gravity, inertia), (rotor_inertia, dt, dr), (b, d, l))| QuadrotorParams {
            mass,
            gravity,
            inertia,
            rotor_inertia,
            drag_translational: dt,
            drag_rotational: dr,
            lift_coefficient: b,
            yaw_drag_coefficient: d,
            arm_length: l,
        })
}

/// None, or `[lo, hi]` with `0 <= lo < hi <= 1e100` (the legal range),
/// log-uniform from 1e-300.
fn thrust_limits() -> impl Strategy<Value = Option<[f64; 2]>> {
    let lo = prop_oneof![Just(0.0), log_uniform(-300.0, 99.9)];
    let width = prop_oneof![4 => log_uniform(-300.0, 100.0), 1 => Just(1e100)];
    prop_oneof![
        1 => Just(None),
        2 => (lo, width).prop_map(|(lo, width)| {
            let hi = if lo + width > lo { lo + width } else { 2.0 * lo };
            Some([lo, hi.min(1e100)])
        }),
    ]
}

fn settings() -> impl Strategy<Value = CascadeSettings> {
    (
        (any::<bool>(), gain(), gain(), (1e-9f64..core::f64::consts::FRAC_PI_2), any::<bool>()),
        (thrust_limits(), any::<bool>()),
    )
        .prop_map(|((filter, wn, zeta, tilt, from_vehicle), (thrust_limits, freeze))| CascadeSettings {
            attitude_derivatives: if filter { AttitudeDerivatives::CommandFilter } else { AttitudeDerivatives::Zero },
            command_filter: CommandFilterParams { natural_frequency: wn, damping: zeta },
            max_tilt: tilt,
            filter_init: if from_vehicle { FilterInit::VehicleAttitude } else { FilterInit::FirstDemand },
            thrust_limits,
            freeze_adaptation_on_saturation: freeze,
        })
}

fn mass_adaptation() -> impl Strategy<Value = MassAdaptation> {
    (any::<bool>(), gain(), gain(), log_uniform(-100.0, 100.0), any::<bool>(), any::<bool>(), log_uniform(0.0, 50.0))
        .prop_map(|(enabled, beta1, beta2, a0, horizontal, bounded, width)| MassAdaptation {
            enabled,
            beta1,
            beta2,
            alpha_hat0: a0,
            compensate_horizontal: horizontal,
            alpha_hat_bounds: bounded.then(|| [a0 / width, (a0 * width).min(1e100)]).filter(|[lo, hi]| lo < hi),
        })
}

fn config() -> impl Strategy<Value = CascadeConfig> {
    (model(), settings(), mass_adaptation()).prop_map(|(model, settings, mass_adaptation)| CascadeConfig {
        model,
        settings,
        mass_adaptation,
    })
}

fn state() -> impl Strategy<Value = QuadState> {
    proptest::array::uniform12(finite_input()).prop_map(|a| QuadState::from_array(&a))
}

fn reference() -> impl Strategy<Value = Reference> {
    proptest::array::uniform12(finite_input()).prop_map(|a| Reference {
        position: [a[0], a[1], a[2]],
        velocity: [a[3], a[4], a[5]],
        acceleration: [a[6], a[7], a[8]],
        yaw: a[9],
        yaw_rate: a[10],
        yaw_acceleration: a[11],
    })
}

fn fly<L: AxisLaw>(
    mut c: Cascade<L>,
    steps: &[(QuadState, Reference, f64, bool)],
    bad_state: QuadState,
) -> Result<(), TestCaseError> {
    let settings = c.config.settings;
    for (k, (state, reference, dt, saturated)) in steps.iter().enumerate() {
        c.actuator_feedback(*saturated);
        let held = (c.telemetry().estimates.map(|e| e.map(f64::to_bits)), c.alpha_hat().to_bits());
        let cmd = c.update(state, reference, *dt);
        prop_assert!(cmd.thrust.is_finite() && cmd.torque.iter().all(|t| t.is_finite()), "{cmd:?}");
        let t = c.telemetry();
        let sm = t.sliding_mode.expect("the cascade reports its sliding part");
        prop_assert!(sm.alpha_hat.is_finite() && t.estimates.iter().flatten().all(|x| x.is_finite()), "{t:?}");
        let frozen = settings.freeze_adaptation_on_saturation && *saturated;
        prop_assert_eq!(sm.adaptation_frozen, frozen);
        // Before the first update the telemetry holds no law states yet.
        if frozen && k > 0 {
            let now = (t.estimates.map(|e| e.map(f64::to_bits)), c.alpha_hat().to_bits());
            prop_assert_eq!(now, held, "frozen states moved");
        }
        if let Some([lo, hi]) = settings.thrust_limits {
            prop_assert!(cmd.thrust >= lo && cmd.thrust <= hi, "thrust {} outside [{lo}, {hi}]", cmd.thrust);
        }
    }
    let before = *c.telemetry();
    let cmd = c.update(&bad_state, &steps[0].1, steps[0].2);
    prop_assert!(!cmd.thrust.is_finite());
    prop_assert_eq!(before, *c.telemetry());
    let cmd = c.update(&steps[0].0, &steps[0].1, steps[0].2);
    prop_assert!(cmd.thrust.is_finite() && cmd.torque.iter().all(|t| t.is_finite()), "{cmd:?}");
    Ok(())
}

fn cascade_steps() -> impl Strategy<Value = Vec<(QuadState, Reference, f64, bool)>> {
    proptest::collection::vec((state(), reference(), legal_dt(), any::<bool>()), 4)
}

fn bad_state() -> impl Strategy<Value = QuadState> {
    (state(), 0usize..12, non_finite()).prop_map(|(s, i, x)| {
        let mut a = s.to_array();
        a[i] = x;
        QuadState::from_array(&a)
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASCADE_CASES))]

    #[test]
    fn ftaftsmc_cascade_stays_finite(
        config in config(),
        g in proptest::array::uniform6(ftaftsmc_gains()),
        s in cascade_steps(),
        bad in bad_state(),
    ) {
        fly(Cascade::new(config, g.map(FtaftsmcAxis::new)).unwrap(), &s, bad)?;
    }

    #[test]
    fn ranftsmc_cascade_stays_finite(
        config in config(),
        g in proptest::array::uniform6(ranftsmc_gains()),
        s in cascade_steps(),
        bad in bad_state(),
    ) {
        fly(Cascade::new(config, g.map(RanftsmcAxis::new)).unwrap(), &s, bad)?;
    }

    #[test]
    fn tsm_sta_cascade_stays_finite(
        config in config(),
        g in proptest::array::uniform6(tsm_sta_gains()),
        s in cascade_steps(),
        bad in bad_state(),
    ) {
        fly(Cascade::new(config, g.map(TsmStaAxis::new)).unwrap(), &s, bad)?;
    }
}

/// A finite input up to `f64::MAX` in magnitude: [`finite_input`] or ±10^x
/// with x in [300, 308.25] (so `x − x_d` can overflow).
fn extreme_input() -> impl Strategy<Value = f64> {
    prop_oneof![
        1 => finite_input(),
        1 => (log_uniform(300.0, 308.25), any::<bool>()).prop_map(|(m, neg)| if neg { -m } else { m }),
        1 => Just(f64::MAX),
        1 => Just(-f64::MAX),
    ]
}

fn extreme_steps() -> impl Strategy<Value = Vec<(QuadState, Reference, f64)>> {
    let state = proptest::array::uniform12(extreme_input()).prop_map(|a| QuadState::from_array(&a));
    let reference = proptest::array::uniform12(extreme_input()).prop_map(|a| Reference {
        position: [a[0], a[1], a[2]],
        velocity: [a[3], a[4], a[5]],
        acceleration: [a[6], a[7], a[8]],
        yaw: a[9],
        yaw_rate: a[10],
        yaw_acceleration: a[11],
    });
    proptest::collection::vec((state, reference, legal_dt()), 4)
}

/// Extreme steps: each gives a finite command, or a NaN command with the
/// telemetry (every law state, α̂, the attitude reference) unchanged; then an
/// ordinary hover step gives a finite command and a finite attitude reference.
fn survive_extremes(c: &mut dyn Controller, steps: &[(QuadState, Reference, f64)]) -> Result<(), TestCaseError> {
    for (state, reference, dt) in steps {
        let before = *c.telemetry();
        let cmd = c.update(state, reference, *dt);
        let finite = cmd.thrust.is_finite() && cmd.torque.iter().all(|t| t.is_finite());
        if !finite {
            prop_assert!(cmd.thrust.is_nan(), "{cmd:?}");
            prop_assert_eq!(before, *c.telemetry(), "a NaN command moved a state");
        }
    }
    let cmd = c.update(&QuadState::default(), &Reference::default(), 1e-3);
    prop_assert!(cmd.thrust.is_finite() && cmd.torque.iter().all(|t| t.is_finite()), "poisoned: {cmd:?}");
    prop_assert!(c.telemetry().attitude_reference.iter().all(|v| v.is_finite()), "{:?}", c.telemetry());
    Ok(())
}

/// Cases per extreme-input property.
const EXTREME_CASES: u32 = 2000;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(EXTREME_CASES))]

    #[test]
    fn ftaftsmc_cascade_survives_overflowing_differences(
        config in config(), g in proptest::array::uniform6(ftaftsmc_gains()), s in extreme_steps(),
    ) {
        survive_extremes(&mut Cascade::new(config, g.map(FtaftsmcAxis::new)).unwrap(), &s)?;
    }

    #[test]
    fn ranftsmc_cascade_survives_overflowing_differences(
        config in config(), g in proptest::array::uniform6(ranftsmc_gains()), s in extreme_steps(),
    ) {
        survive_extremes(&mut Cascade::new(config, g.map(RanftsmcAxis::new)).unwrap(), &s)?;
    }

    #[test]
    fn tsm_sta_cascade_survives_overflowing_differences(
        config in config(), g in proptest::array::uniform6(tsm_sta_gains()), s in extreme_steps(),
    ) {
        survive_extremes(&mut Cascade::new(config, g.map(TsmStaAxis::new)).unwrap(), &s)?;
    }

    #[test]
    fn pid_with_subnormal_yaw_weight_and_velocity_p_stays_finite(
        yaw_weight in prop_oneof![Just(f64::from_bits(1)), Just(1e-310), Just(f64::MIN_POSITIVE)],
        velocity_p in prop_oneof![Just(f64::from_bits(1)), Just(1e-310), Just(f64::MIN_POSITIVE)],
        s in cascade_steps(),
    ) {
        let gains = PidGains { yaw_weight, velocity_p: [velocity_p; 3], ..PidGains::default() };
        let mut c = PidController::new(QuadrotorParams::default(), gains).unwrap();
        for (state, reference, dt, _) in &s {
            let cmd = c.update(state, reference, *dt);
            prop_assert!(cmd.thrust.is_finite() && cmd.torque.iter().all(|t| t.is_finite()), "{cmd:?}");
            prop_assert!(c.velocity_integral().iter().all(|v| v.is_finite()), "{:?}", c.velocity_integral());
        }
        // Level, at rest, 1 rad off in yaw: the yaw torque is a number.
        let cmd = c.update(&QuadState::default(), &Reference { yaw: 1.0, ..Reference::default() }, 1e-3);
        prop_assert!(cmd.torque[2].is_finite(), "{cmd:?}");
    }
}
