//! The exact PX4-priority mixer (`[actuators] mixer = "px4-exact" |
//! "px4-exact-airmode"`) beside
//! the thrust-first one: near full throttle PX4 keeps roll and pitch and
//! lowers the collective thrust; it never raises it unless in airmode; yaw
//! gives way last; what the rotors deliver is what `applied` says.

use ftsmc_core::model::{Command, QuadrotorParams};
use ftsmc_sim::actuators::{ActuatorParams, Mixer, MixerKind};

fn mixer(kind: MixerKind) -> (Mixer, f64) {
    let p = QuadrotorParams::default();
    let a = ActuatorParams { max_rotor_speed: 400.0, mixer: kind, ..ActuatorParams::default() };
    let m = Mixer::for_paper(&p, &a).unwrap();
    (m, 4.0 * p.lift_coefficient * 400.0 * 400.0)
}

fn delivered(m: &Mixer, speeds: &[f64; 4]) -> Command {
    m.forces(&speeds.map(|w| w * w))
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs()))
}

#[test]
fn a_feasible_command_is_applied_unchanged_by_every_mixer() {
    for kind in [MixerKind::ThrustFirst, MixerKind::Px4Exact, MixerKind::Px4ExactAirmode] {
        let (m, t_max) = mixer(kind);
        let c = Command { thrust: 0.5 * t_max, torque: [0.05, -0.03, 0.002] };
        let out = m.mix(&c);
        assert!(!out.saturated, "{kind:?}");
        assert_eq!(out.applied, c);
    }
}

#[test]
fn near_full_throttle_px4_keeps_roll_and_lowers_thrust_thrust_first_the_opposite() {
    let c = |t_max: f64| Command { thrust: 0.95 * t_max, torque: [0.4, 0.0, 0.0] };
    let (tf, t_max) = mixer(MixerKind::ThrustFirst);
    let out = tf.mix(&c(t_max));
    assert!(out.saturated);
    assert!(close(out.applied.thrust, 0.95 * t_max));
    assert!(out.applied.torque[0] < 0.4 * 0.5, "thrust first cuts roll: {:?}", out.applied);
    for kind in [MixerKind::Px4Exact, MixerKind::Px4ExactAirmode] {
        let (m, _) = mixer(kind);
        let out = m.mix(&c(t_max));
        assert!(out.saturated, "{kind:?}");
        assert!(close(out.applied.torque[0], 0.4), "{kind:?} keeps roll: {:?}", out.applied);
        assert!(out.applied.thrust < 0.95 * t_max, "{kind:?} lowers thrust: {:?}", out.applied);
        // The most thrust that still fits the roll torque (one rotor at ω_max).
        assert!(out.rotor_speeds.iter().any(|w| close(*w, 400.0)), "{:?}", out.rotor_speeds);
        let d = delivered(&m, &out.rotor_speeds);
        assert!(close(d.thrust, out.applied.thrust) && close(d.torque[0], 0.4), "{d:?} vs {:?}", out.applied);
    }
}

#[test]
fn without_airmode_px4_never_raises_thrust_with_airmode_it_does() {
    let (m, t_max) = mixer(MixerKind::Px4Exact);
    // Low throttle, large roll: one rotor would need a negative ω².
    let c = Command { thrust: 0.05 * t_max, torque: [0.4, 0.0, 0.0] };
    let out = m.mix(&c);
    assert!(out.applied.thrust <= c.thrust + 1e-12, "{:?}", out.applied);
    assert!(out.applied.torque[0] < 0.4, "roll scaled instead: {:?}", out.applied);
    let (air, _) = mixer(MixerKind::Px4ExactAirmode);
    let out = air.mix(&c);
    assert!(out.applied.thrust > c.thrust, "airmode raises thrust: {:?}", out.applied);
    assert!(close(out.applied.torque[0], 0.4), "{:?}", out.applied);
    let d = delivered(&air, &out.rotor_speeds);
    assert!(close(d.thrust, out.applied.thrust), "{d:?}");
}

#[test]
fn yaw_gives_way_last_and_roll_pitch_only_when_no_thrust_fits_them() {
    let (m, t_max) = mixer(MixerKind::Px4Exact);
    // Half throttle, moderate roll, impossible yaw: roll kept, yaw scaled.
    let c = Command { thrust: 0.5 * t_max, torque: [0.2, 0.1, 1.0] };
    let out = m.mix(&c);
    assert!(close(out.applied.torque[0], 0.2) && close(out.applied.torque[1], 0.1), "{:?}", out.applied);
    assert!(out.applied.torque[2] < 1.0 && out.applied.torque[2] >= 0.0, "{:?}", out.applied);
    // A roll torque larger than the rotors can give at any thrust: scaled,
    // direction kept, rotors within limits.
    let c = Command { thrust: 0.5 * t_max, torque: [5.0, 5.0, 0.0] };
    let out = m.mix(&c);
    let s = out.applied.torque[0] / 5.0;
    assert!(s > 0.0 && s < 1.0 && close(out.applied.torque[1] / 5.0, s), "{:?}", out.applied);
    assert!(out.rotor_speeds.iter().all(|w| (0.0..=400.0).contains(w)), "{:?}", out.rotor_speeds);
}

#[test]
fn the_mixer_key_parses_and_defaults_to_thrust_first() {
    let a: ActuatorParams = toml::from_str("max_rotor_speed = 838.0\nmixer = \"px4\"").unwrap();
    assert_eq!(a.mixer, MixerKind::Px4);
    let a: ActuatorParams = toml::from_str("max_rotor_speed = 838.0\nmixer = \"px4-exact\"").unwrap();
    assert_eq!(a.mixer, MixerKind::Px4Exact);
    // The exact airmode allocation's earlier name still loads.
    let a: ActuatorParams = toml::from_str("max_rotor_speed = 838.0\nmixer = \"px4-airmode\"").unwrap();
    assert_eq!(a.mixer, MixerKind::Px4ExactAirmode);
    // PX4's setpoints are fractions of full thrust: an unbounded rotor is refused.
    let a: ActuatorParams = toml::from_str("mixer = \"px4\"").unwrap();
    assert!(a.check().unwrap_err().to_string().contains("finite max_rotor_speed"));
    let a: ActuatorParams = toml::from_str("max_rotor_speed = 838.0").unwrap();
    assert_eq!(a.mixer, MixerKind::ThrustFirst);
    assert!(toml::from_str::<ActuatorParams>("mixer = \"betaflight\"").is_err());
}
